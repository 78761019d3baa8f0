// SPDX-License-Identifier: MIT
#include "fields/field_config.h"

#include "fields/activations.h"
#include "fields/encoding_type.h"
#include "fields/field_type.h"

namespace nfield::fields {

FieldOptions field_options_from_config(const io::ConfigNode& node, int input_dim, int output_dim,
                                       std::uint64_t seed, std::vector<std::string> input_names,
                                       SineFrequencies sine) {
  FieldOptions o;
  o.first_omega = sine.first;
  o.hidden_omega = sine.hidden;
  o.input_dim = input_dim;
  o.output_dim = output_dim;
  o.type = node.get_choice("type", field_type_names(), FieldOptions().type);
  const FieldType& type = field_type(o.type);
  if (node.has("hidden")) {
    o.hidden = node.get<std::vector<int>>("hidden");
    node.require("hidden", !o.hidden.empty(), "expected a non-empty list of widths");
    for (int h : o.hidden) node.require("hidden", h >= 1 && h <= 16384, "expected widths in [1, 16384]");
  }
  if (type.has_activation())
    o.activation = node.get_choice("activation", activation_names(), type.default_activation());
  type.read(node, o);
  o.first_omega = node.get_or("first_omega", o.first_omega);
  node.require("first_omega", o.first_omega > 0, "expected a number > 0");
  o.hidden_omega = node.get_or("hidden_omega", o.hidden_omega);
  node.require("hidden_omega", o.hidden_omega > 0, "expected a number > 0");
  o.seed = node.has("seed") ? static_cast<std::uint64_t>(node.get_nonnegative<std::int64_t>("seed")) : seed;
  if (node.has("encoding")) {
    const io::ConfigNode e = node.child("encoding");
    o.encoding.type = e.get_choice("type", encoding_names(), o.encoding.type);
    encoding_type(o.encoding.type).read(e, {input_dim, o.seed, std::move(input_names)}, o.encoding);
    e.reject_unknown_keys();
    // Means and variances: the problem appends the variances (solvers/run/run.cc checks it can).
    if (reads_variances(o.encoding)) o.input_dim += type.variance_inputs(o);
  }
  if (node.has("latent")) {
    const io::ConfigNode latent = node.child("latent");
    o.latent_size = latent.get<int>("size");
    latent.require("size", o.latent_size >= 1 && o.latent_size <= 4096, "expected a code size in [1, 4096]");
    latent.reject_unknown_keys();
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
  const FieldType& type = field_type(o.type);
  n["type"] = o.type;
  n["hidden"] = o.hidden;
  if (type.has_activation()) n["activation"] = o.activation;
  type.write(o, n);
  n["first_omega"] = o.first_omega;
  n["hidden_omega"] = o.hidden_omega;
  n["seed"] = o.seed;
  if (o.latent_size > 0) n["latent"]["size"] = o.latent_size;
  n["encoding"]["type"] = o.encoding.type;
  YAML::Node encoding = n["encoding"];
  encoding_type(o.encoding.type).write(o.encoding, {o.input_dim, o.seed, std::move(input_names)},
                                       encoding);
  return n;
}

}  // namespace nfield::fields
