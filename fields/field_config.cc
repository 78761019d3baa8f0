// SPDX-License-Identifier: MIT
#include "fields/field_config.h"

#include "fields/activations.h"
#include "fields/encoding_type.h"

namespace nfield::fields {

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
  if (o.type == "mlp" || o.type == "nerf")
    o.activation = node.get_choice("activation", activation_names(), default_activation(o.type));
  if (o.type == "nerf") {
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
    encoding_type(o.encoding.type).read(e, {input_dim, o.seed, std::move(input_names)}, o.encoding);
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
  YAML::Node encoding = n["encoding"];
  encoding_type(o.encoding.type).write(o.encoding, {o.input_dim, o.seed, std::move(input_names)},
                                       encoding);
  return n;
}

}  // namespace nfield::fields
