// SPDX-License-Identifier: MIT
#include "fields/field.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "autodiff/on_columns.h"
#include "fields/field_type.h"

namespace nfield::fields {
namespace {

// Uniform in [−a, a] from the raw 64-bit engine, independent of library distributions.
double uniform(std::mt19937_64& rng, double a) {
  return a * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0);
}

}  // namespace

template <typename Scalar>
const autodiff::Module<Scalar>& parameter_owner(const autodiff::Module<Scalar>& module) {
  if (const auto* on = dynamic_cast<const autodiff::OnColumns<Scalar>*>(&module)) return on->inner();
  return module;
}

template <typename Scalar>
Field<Scalar>::Field(FieldOptions options, autodiff::SequentialOptions evaluation)
    : options_(std::move(options)), network_(evaluation) {
  const FieldType& type = field_type(options_.type);
  if (options_.activation.empty()) options_.activation = type.default_activation();
  options_.validate();
  encoding_matrix_ = fields::encoding_matrix(options_.encoding, type.encoded_inputs(options_));
  late_features_ = type.append_modules(options_, network_);
  parameters_.setZero(network_.parameter_count());
  initialize();
}

template <typename Scalar>
void Field<Scalar>::initialize() {
  std::mt19937_64 rng(options_.seed);
  const FieldType& type = field_type(options_.type);
  int dense_index = 0;
  for (size_t m = 0; m < network_.modules().size(); ++m) {
    const auto& module = parameter_owner(*network_.modules()[m]);
    if (module.parameter_count() == 0) continue;
    Scalar* p = parameters_.data() + network_.parameter_offset(m);
    if (module.initialize(p, rng)) continue;  // e.g. hash-grid tables
    const Eigen::Index in = module.input_width(), out = module.output_width();
    const InitialBounds bounds = type.initial_bounds(options_, dense_index, in, out);
    for (Eigen::Index i = 0; i < in * out; ++i) p[i] = static_cast<Scalar>(uniform(rng, bounds.weight));
    for (Eigen::Index i = 0; i < out; ++i)
      p[in * out + i] = static_cast<Scalar>(bounds.bias > 0 ? uniform(rng, bounds.bias) : 0.0);
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
