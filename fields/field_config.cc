// SPDX-License-Identifier: MIT
#include "fields/field_config.h"

#include <algorithm>
#include <cmath>

#include "fields/activations.h"

namespace nfield::fields {

namespace {

std::vector<std::string> names_or_default(std::vector<std::string> names, int input_dim) {
  if (names.empty())
    for (int a = 0; a < input_dim; ++a) names.push_back(std::string(1, "xyzw"[a % 4]));
  return names;
}

}  // namespace

FieldOptions field_options_from_config(const io::ConfigNode& node, int input_dim, int output_dim,
                                       std::uint64_t seed, std::vector<std::string> input_names) {
  FieldOptions o;
  o.input_dim = input_dim;
  o.output_dim = output_dim;
  o.type = node.get_choice("type", field_type_names(), "siren");
  if (node.has("hidden")) {
    o.hidden = node.get<std::vector<int>>("hidden");
    node.require("hidden", !o.hidden.empty(), "expected a non-empty list of widths");
    for (int h : o.hidden) node.require("hidden", h >= 1 && h <= 16384, "expected widths in [1, 16384]");
  }
  if (o.type == "mlp") o.activation = node.get_choice("activation", activation_names(), "tanh");
  if (o.type == "nerf") {
    o.activation = node.get_choice("activation", activation_names(), "relu");
    if (node.has("color_hidden")) {
      o.color_hidden = node.get<std::vector<int>>("color_hidden");
      for (int c : o.color_hidden)
        node.require("color_hidden", c >= 1 && c <= 16384, "expected widths in [1, 16384]");
    }
    if (node.has("direction_frequencies"))
      o.direction_frequencies = node.get_in_range("direction_frequencies", 1, 16);
  }
  o.first_omega = node.get_or("first_omega", o.first_omega);
  node.require("first_omega", o.first_omega > 0, "expected a number > 0");
  o.hidden_omega = node.get_or("hidden_omega", o.hidden_omega);
  node.require("hidden_omega", o.hidden_omega > 0, "expected a number > 0");
  o.seed = node.has("seed") ? static_cast<std::uint64_t>(node.get_nonnegative<std::int64_t>("seed")) : seed;
  if (node.has("encoding")) {
    const io::ConfigNode e = node.child("encoding");
    o.encoding.type = e.get_choice("type", encoding_names(), "identity");
    if (o.encoding.type == "positional") {
      if (e.has("frequencies")) o.encoding.frequencies = e.get_in_range("frequencies", 1, 24);
      o.encoding.include_input = e.get_or("include_input", true);
    } else if (o.encoding.type == "fourier") {
      if (e.has("features")) o.encoding.features = e.get_in_range("features", 1, 65536);
      o.encoding.scale = e.get_or("scale", o.encoding.scale);
      e.require("scale", o.encoding.scale > 0, "expected a number > 0");
      o.encoding.seed = e.has("seed") ? static_cast<std::uint64_t>(e.get_nonnegative<std::int64_t>("seed")) : o.seed;
    } else if (o.encoding.type == "cusp") {
      const std::vector<std::string> axes = names_or_default(std::move(input_names), input_dim);
      const std::string axis = e.get_choice("axis", axes);
      o.encoding.axis = static_cast<int>(std::find(axes.begin(), axes.end(), axis) - axes.begin());
      o.encoding.at = e.get<std::vector<double>>("at");
      e.require("at", !o.encoding.at.empty(), "expected a non-empty list of plane positions");
      for (double c : o.encoding.at) e.require("at", std::isfinite(c), "expected finite numbers");
      if (e.has("from_stage")) o.encoding.from_stage = e.get_in_range("from_stage", 0, 1000);
    }
    e.reject_unknown_keys();
  }
  node.reject_unknown_keys();
  try {
    o.validate();
  } catch (const std::invalid_argument& error) {
    throw node.error(error.what());
  }
  return o;
}

YAML::Node to_yaml(const FieldOptions& o, std::vector<std::string> input_names) {
  YAML::Node n;
  n["type"] = o.type;
  n["hidden"] = o.hidden;
  if (o.type == "mlp" || o.type == "nerf") n["activation"] = o.activation;
  if (o.type == "nerf") {
    n["color_hidden"] = o.color_hidden;
    n["direction_frequencies"] = o.direction_frequencies;
  }
  n["first_omega"] = o.first_omega;
  n["hidden_omega"] = o.hidden_omega;
  n["seed"] = o.seed;
  n["encoding"]["type"] = o.encoding.type;
  if (o.encoding.type == "positional") {
    n["encoding"]["frequencies"] = o.encoding.frequencies;
    n["encoding"]["include_input"] = o.encoding.include_input;
  } else if (o.encoding.type == "fourier") {
    n["encoding"]["features"] = o.encoding.features;
    n["encoding"]["scale"] = o.encoding.scale;
    n["encoding"]["seed"] = o.encoding.seed;
  } else if (o.encoding.type == "cusp") {
    n["encoding"]["axis"] = names_or_default(std::move(input_names), o.input_dim).at(o.encoding.axis);
    n["encoding"]["at"] = o.encoding.at;
    if (o.encoding.from_stage > 0) n["encoding"]["from_stage"] = o.encoding.from_stage;
  }
  return n;
}

}  // namespace nfield::fields
