// SPDX-License-Identifier: MIT
//
// The registered field types (fields/field_type.h), the registry, and the validation of
// FieldOptions that depends on them.
#include <cmath>
#include <span>
#include <stdexcept>

#include "fields/acorn.h"
#include "fields/activation_layer.h"
#include "fields/activations.h"
#include "fields/bacon.h"
#include "fields/dense.h"
#include "fields/encoding_type.h"
#include "fields/field_type.h"
#include "fields/latent_code.h"
#include "fields/radiance_network.h"
#include "io/registry.h"
#include "io/text.h"

namespace nfield::fields {
namespace {

[[noreturn]] void reject(const std::string& field, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("field." + field + " = " + value + ": " + rule);
}

// x → γ(x) → [Dense → σ_l] × H → Dense, σ_l = sine at first_omega then hidden_omega for a
// siren, the field's activation at hidden_omega otherwise.
template <typename Scalar>
FeatureEncoding<Scalar>* append_coordinate_network(const FieldOptions& o, bool siren,
                                                   autodiff::Sequential<Scalar>& network) {
  FeatureEncoding<Scalar>* late_features = nullptr;
  Eigen::Index width = o.input_dim;
  if (auto encoding = make_encoding<Scalar>(o.encoding, o.input_dim)) {
    width = encoding->output_width();
    if (entry_stage(o.encoding) > 0) late_features = dynamic_cast<FeatureEncoding<Scalar>*>(encoding.get());
    network.add(std::move(encoding));
  }
  for (size_t l = 0; l < o.hidden.size(); ++l) {
    network.add(std::make_unique<Dense<Scalar>>(width, o.hidden[l]));
    width = o.hidden[l];
    const ActivationSpec spec{siren ? "sine" : o.activation,
                              siren && l == 0 ? o.first_omega : o.hidden_omega};
    network.add(std::make_unique<ActivationLayer<Scalar>>(spec, width));
    if (l == 0 && o.latent_size > 0) {
      network.add(std::make_unique<LatentCode<Scalar>>(width, o.latent_size));
      width += o.latent_size;
    }
  }
  network.add(std::make_unique<Dense<Scalar>>(width, o.output_dim));
  return late_features;
}

class SirenType final : public FieldTypeOf<SirenType> {
 public:
  std::string default_activation() const override { return "sine"; }
  bool has_activation() const override { return false; }
  bool takes_latent_code() const override { return true; }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    return append_coordinate_network(o, true, network);
  }
  InitialBounds initial_bounds(const FieldOptions& o, int index, Eigen::Index in,
                               Eigen::Index) const override {
    return {index == 0 ? 1.0 / in : std::sqrt(6.0 / in) / o.hidden_omega,
            1.0 / std::sqrt(static_cast<double>(in))};
  }
};

class MlpType final : public FieldTypeOf<MlpType> {
 public:
  std::string default_activation() const override { return "tanh"; }
  bool takes_latent_code() const override { return true; }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    return append_coordinate_network(o, false, network);
  }
};

class NerfType final : public FieldTypeOf<NerfType> {
 public:
  std::string default_activation() const override { return "relu"; }
  void validate(const FieldOptions& o) const override {
    if (reads_variances(o.encoding)) {
      if (o.input_dim != kRadianceInputs + 3)
        reject("input_dim", std::to_string(o.input_dim),
               "must be 9 for nerf with encoding " + o.encoding.type + " (position, direction, variances)");
    } else if (o.input_dim != kRadianceInputs) {
      reject("input_dim", std::to_string(o.input_dim), "must be 6 for nerf (position, direction)");
    }
    if (o.output_dim != kRadianceOutputs)
      reject("output_dim", std::to_string(o.output_dim), "must be 4 for nerf (density, r, g, b)");
    for (size_t i = 0; i < o.color_hidden.size(); ++i)
      if (o.color_hidden[i] < 1)
        reject("color_hidden[" + std::to_string(i) + "]", std::to_string(o.color_hidden[i]), "must be >= 1");
    if (o.direction_frequencies < 1 || o.direction_frequencies > 16)
      reject("direction_frequencies", std::to_string(o.direction_frequencies), "must be in [1, 16]");
  }
  int encoded_inputs(const FieldOptions& o) const override { return reads_variances(o.encoding) ? 6 : 3; }
  bool takes_latent_code() const override { return true; }  // into the colour layers: an appearance code
  int variance_inputs(const FieldOptions&) const override { return 3; }
  template <typename Scalar>
  static FeatureEncoding<Scalar>* append(const FieldOptions& o, autodiff::Sequential<Scalar>& network) {
    add_radiance_modules(o, network);
    return nullptr;
  }
  void read(const io::ConfigNode& node, FieldOptions& o) const override {
    if (node.has("color_hidden")) {
      o.color_hidden = node.get<std::vector<int>>("color_hidden");
      for (int c : o.color_hidden)
        node.require("color_hidden", c >= 1 && c <= 16384, "expected widths in [1, 16384]");
    }
    if (node.has("direction_frequencies"))
      o.direction_frequencies = node.get_in_range("direction_frequencies", 1, 16);
  }
  void write(const FieldOptions& o, YAML::Node& n) const override {
    n["color_hidden"] = o.color_hidden;
    n["direction_frequencies"] = o.direction_frequencies;
  }
  void save(io::H5Writer& file, const std::string& group, const FieldOptions& o) const override {
    std::vector<std::int64_t> color(o.color_hidden.begin(), o.color_hidden.end());
    file.write_attribute(group, "color_hidden", std::span<const std::int64_t>(color));
    file.write_attribute(group, "direction_frequencies", o.direction_frequencies);
  }
  void load(const io::H5Reader& file, const std::string& group, FieldOptions& o) const override {
    if (file.has_attribute(group, "color_hidden")) {
      const auto color = file.read_attribute<std::vector<std::int64_t>>(group, "color_hidden");
      o.color_hidden.assign(color.begin(), color.end());
    }
    if (file.has_attribute(group, "direction_frequencies"))
      o.direction_frequencies =
          static_cast<int>(file.read_attribute<std::int64_t>(group, "direction_frequencies"));
  }
};

using FieldTypeRegistry = Registry<std::unique_ptr<const FieldType>>;

void register_field_types(FieldTypeRegistry& registry) {
  registry.add("siren", std::make_unique<SirenType>());
  registry.add("mlp", std::make_unique<MlpType>());
  registry.add("nerf", std::make_unique<NerfType>());
  registry.add("bacon", make_bacon_type());
  registry.add("acorn", make_acorn_type());
}

FieldTypeRegistry& field_types() {
  static FieldTypeRegistry registry = [] {
    FieldTypeRegistry r("field type");
    register_field_types(r);
    return r;
  }();
  return registry;
}

}  // namespace

InitialBounds FieldType::initial_bounds(const FieldOptions& o, int, Eigen::Index in,
                                        Eigen::Index out) const {
  const bool relu = io::to_lower(o.activation) == "relu";
  return {relu ? std::sqrt(6.0 / in) : std::sqrt(6.0 / (in + out)), 0.0};
}

const FieldType& field_type(std::string_view name) { return *field_types().at(name); }

void register_field_type(std::string_view name, std::unique_ptr<const FieldType> type) {
  field_types().add(name, std::move(type));
}

std::vector<std::string> field_type_names() { return field_types().names(); }

std::string default_activation(const std::string& type) {
  return field_type(type).default_activation();
}

void FieldOptions::validate() const {
  const FieldType& kind = field_type(type);
  if (input_dim < 1) reject("input_dim", std::to_string(input_dim), "must be >= 1");
  if (output_dim < 1) reject("output_dim", std::to_string(output_dim), "must be >= 1");
  kind.validate(*this);
  if (hidden.empty()) reject("hidden", "[]", "needs at least one hidden layer");
  for (size_t i = 0; i < hidden.size(); ++i)
    if (hidden[i] < 1)
      reject("hidden[" + std::to_string(i) + "]", std::to_string(hidden[i]), "must be >= 1");
  if (kind.has_activation()) {
    try {
      make_activation<double>({activation.empty() ? kind.default_activation() : activation, hidden_omega});
    } catch (const UnknownNameError& e) {
      reject("activation", activation, e.what());
    }
  }
  if (latent_size < 0 || latent_size > 4096)
    reject("latent.size", std::to_string(latent_size), "must be in [1, 4096]");
  if (latent_size > 0 && !kind.takes_latent_code())
    reject("latent", "{size: " + std::to_string(latent_size) + "}",
           "field.type " + type + " takes no latent code (siren, mlp and nerf do)");
  if (latent_size > 0 && !branches.empty())
    reject("latent", "{size: " + std::to_string(latent_size) + "}", "a field with unknown-field branches takes no latent code");
  if (!(first_omega > 0)) reject("first_omega", std::to_string(first_omega), "must be > 0");
  if (!(hidden_omega > 0)) reject("hidden_omega", std::to_string(hidden_omega), "must be > 0");
  encoding.validate();
  try {
    encoding.validate(kind.encoded_inputs(*this));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("field." + std::string(e.what()));
  }
}

}  // namespace nfield::fields
