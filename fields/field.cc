// SPDX-License-Identifier: MIT
#include "fields/field.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "fields/activation_layer.h"
#include "autodiff/on_columns.h"
#include "fields/dense.h"
#include "fields/radiance_network.h"
#include "io/registry.h"

namespace nfield::fields {
namespace {

const Registry<int>& field_types() {
  static const Registry<int> registry = [] {
    Registry<int> r("field type");
    r.add("siren", 0);
    r.add("mlp", 1);
    r.add("nerf", 2);
    return r;
  }();
  return registry;
}

[[noreturn]] void reject(const std::string& field, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument("field." + field + " = " + value + ": " + rule);
}

bool is_siren(const FieldOptions& o) { return Registry<int>::lower(o.type) == "siren"; }
bool is_nerf(const FieldOptions& o) { return Registry<int>::lower(o.type) == "nerf"; }


// Uniform in [−a, a] from the raw 64-bit engine, independent of library distributions.
double uniform(std::mt19937_64& rng, double a) {
  return a * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0);
}

}  // namespace

void FieldOptions::validate() const {
  field_types().at(type);
  if (input_dim < 1) reject("input_dim", std::to_string(input_dim), "must be >= 1");
  if (output_dim < 1) reject("output_dim", std::to_string(output_dim), "must be >= 1");
  if (is_nerf(*this) && input_dim != kRadianceInputs)
    reject("input_dim", std::to_string(input_dim), "must be 6 for nerf (position, direction)");
  if (is_nerf(*this) && output_dim != kRadianceOutputs)
    reject("output_dim", std::to_string(output_dim), "must be 4 for nerf (density, r, g, b)");
  if (is_nerf(*this)) {
    for (size_t i = 0; i < color_hidden.size(); ++i)
      if (color_hidden[i] < 1)
        reject("color_hidden[" + std::to_string(i) + "]", std::to_string(color_hidden[i]), "must be >= 1");
    if (direction_frequencies < 1 || direction_frequencies > 16)
      reject("direction_frequencies", std::to_string(direction_frequencies), "must be in [1, 16]");
  }
  if (hidden.empty()) reject("hidden", "[]", "needs at least one hidden layer");
  for (size_t i = 0; i < hidden.size(); ++i)
    if (hidden[i] < 1)
      reject("hidden[" + std::to_string(i) + "]", std::to_string(hidden[i]), "must be >= 1");
  if (!is_siren(*this)) {
    try {
      make_activation<double>({activation.empty() ? default_activation(type) : activation, hidden_omega});
    } catch (const UnknownNameError& e) {
      reject("activation", activation, e.what());
    }
  }
  if (!(first_omega > 0)) reject("first_omega", std::to_string(first_omega), "must be > 0");
  if (!(hidden_omega > 0)) reject("hidden_omega", std::to_string(hidden_omega), "must be > 0");
  encoding.validate();
  try {
    encoding.validate(is_nerf(*this) ? 3 : input_dim);  // nerf encodes the position alone
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("field." + std::string(e.what()));
  }
}

std::vector<std::string> field_type_names() { return field_types().names(); }

std::string default_activation(const std::string& type) {
  const std::string kind = Registry<int>::lower(type);
  return kind == "mlp" ? "tanh" : kind == "nerf" ? "relu" : "sine";
}

template <typename Scalar>
const autodiff::Module<Scalar>& parameter_owner(const autodiff::Module<Scalar>& module) {
  if (const auto* on = dynamic_cast<const autodiff::OnColumns<Scalar>*>(&module)) return on->inner();
  return module;
}

template <typename Scalar>
Field<Scalar>::Field(FieldOptions options, autodiff::SequentialOptions evaluation)
    : options_(std::move(options)), network_(evaluation) {
  if (options_.activation.empty()) options_.activation = default_activation(options_.type);
  options_.validate();
  const int d = options_.input_dim;
  if (is_nerf(options_)) {
    encoding_matrix_ = fields::encoding_matrix(options_.encoding, 3);
    add_radiance_modules(options_, network_);
    parameters_.setZero(network_.parameter_count());
    initialize();
    return;
  }
  encoding_matrix_ = fields::encoding_matrix(options_.encoding, d);
  Eigen::Index width = d;
  if (auto encoding = make_encoding<Scalar>(options_.encoding, d)) {
    width = encoding->output_width();
    if (options_.encoding.from_stage > 0)
      late_features_ = dynamic_cast<FeatureEncoding<Scalar>*>(encoding.get());
    network_.add(std::move(encoding));
  }
  const bool siren = is_siren(options_);
  for (size_t l = 0; l < options_.hidden.size(); ++l) {
    network_.add(std::make_unique<Dense<Scalar>>(width, options_.hidden[l]));
    width = options_.hidden[l];
    ActivationSpec spec{siren ? "sine" : options_.activation,
                        siren && l == 0 ? options_.first_omega : options_.hidden_omega};
    network_.add(std::make_unique<ActivationLayer<Scalar>>(spec, width));
  }
  network_.add(std::make_unique<Dense<Scalar>>(width, options_.output_dim));
  parameters_.setZero(network_.parameter_count());
  initialize();
}

template <typename Scalar>
void Field<Scalar>::initialize() {
  std::mt19937_64 rng(options_.seed);
  const bool siren = is_siren(options_);
  const bool relu = Registry<int>::lower(options_.activation) == "relu";
  int dense_index = 0;
  for (size_t m = 0; m < network_.modules().size(); ++m) {
    const auto& module = parameter_owner(*network_.modules()[m]);
    if (module.parameter_count() == 0) continue;
    Scalar* p = parameters_.data() + network_.parameter_offset(m);
    if (module.initialize(p, rng)) continue;  // e.g. hash-grid tables
    const Eigen::Index in = module.input_width(), out = module.output_width();
    double weight_bound, bias_bound = 0;
    if (siren) {
      weight_bound = dense_index == 0 ? 1.0 / in : std::sqrt(6.0 / in) / options_.hidden_omega;
      bias_bound = 1.0 / std::sqrt(static_cast<double>(in));
    } else {
      weight_bound = relu ? std::sqrt(6.0 / in) : std::sqrt(6.0 / (in + out));
    }
    for (Eigen::Index i = 0; i < in * out; ++i) p[i] = static_cast<Scalar>(uniform(rng, weight_bound));
    for (Eigen::Index i = 0; i < out; ++i)
      p[in * out + i] = static_cast<Scalar>(bias_bound > 0 ? uniform(rng, bias_bound) : 0.0);
    if (dense_index == 0 && late_features_) {
      // W is out × in column-major (fields/dense.h); the features follow the d inputs.
      const Eigen::Index d = options_.input_dim;
      std::fill(p + d * out, p + in * out, Scalar(0));
    }
    ++dense_index;
  }
}

template <typename Scalar>
void Field<Scalar>::begin_stage(int stage) {
  if (late_features_) late_features_->set_features_on(stage >= options_.encoding.from_stage);
}

template <typename Scalar>
autodiff::Matrix<Scalar> Field<Scalar>::values(
    const Eigen::Ref<const autodiff::Matrix<Scalar>>& x) const {
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(options_.input_dim));
  autodiff::Streams<Scalar> out;
  evaluate(layout, x, out);
  return out.data;
}

template <typename Scalar>
template <typename Other>
Field<Other> Field<Scalar>::cast() const {
  Field<Other> other(options_, network_.options());
  other.parameters() = parameters_.template cast<Other>();
  return other;
}

template const autodiff::Module<float>& parameter_owner(const autodiff::Module<float>&);
template const autodiff::Module<double>& parameter_owner(const autodiff::Module<double>&);
template class Field<float>;
template class Field<double>;
template Field<double> Field<float>::cast<double>() const;
template Field<float> Field<double>::cast<float>() const;
template Field<float> Field<float>::cast<float>() const;
template Field<double> Field<double>::cast<double>() const;

}  // namespace nfield::fields
