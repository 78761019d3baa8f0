// SPDX-License-Identifier: MIT
#include "fields/field.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "autodiff/on_columns.h"
#include "fields/field_branches.h"
#include "fields/field_type.h"
#include "fields/latent_code.h"

namespace nfield::fields {
namespace {

// Uniform in [−a, a] from the raw 64-bit engine, independent of library distributions.
double uniform(std::mt19937_64& rng, double a) {
  return a * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0);
}

// Keeps scale `scale`'s m columns of a network's outputs (all of them when there is one scale).
template <typename Scalar>
void keep_scale(int scale, Eigen::Index m, int scales, autodiff::Streams<Scalar>& out) {
  if (scales == 1) return;
  if (scale < 0 || scale >= scales)
    throw std::out_of_range("field scale " + std::to_string(scale) + " of " + std::to_string(scales));
  autodiff::Matrix<Scalar> kept = out.data.middleCols(scale * m, m);
  out.data = std::move(kept);
}

// The columns of scale s of a multiscale output, as Streams of their own.
template <typename Scalar>
void slice_scale(const autodiff::Streams<Scalar>& out, int s, Eigen::Index m, autodiff::Streams<Scalar>& part) {
  part.resize(out.points, out.count, m);
  part.data = out.data.middleCols(s * m, m);
}

// A loss over one scale's outputs applied to scales [first, last) in turn and summed.
template <typename Scalar>
class ScaleLoss final : public autodiff::StreamLoss<Scalar> {
 public:
  ScaleLoss(const autodiff::StreamLoss<Scalar>& inner, Eigen::Index m, int first, int last)
      : inner_(inner), m_(m), first_(first), last_(last) {}
  double evaluate(Eigen::Index first_point, const autodiff::StreamLayout& layout,
                  const autodiff::Streams<Scalar>& out, autodiff::Streams<Scalar>& adjoint) const override {
    double sum = 0;
    autodiff::Streams<Scalar> part, part_adjoint;
    for (int s = first_; s < last_; ++s) {
      slice_scale(out, s, m_, part);
      part_adjoint.resize(out.points, out.count, m_);
      part_adjoint.data.setZero();
      sum += inner_.evaluate_scale(s, first_point, layout, part, part_adjoint);
      adjoint.data.middleCols(s * m_, m_) += part_adjoint.data;
    }
    return sum;
  }

 private:
  const autodiff::StreamLoss<Scalar>& inner_;
  Eigen::Index m_;
  int first_, last_;
};

// A residual read from one scale's outputs.
template <typename Scalar>
class ScaleResidual final : public autodiff::StreamResidual<Scalar> {
 public:
  ScaleResidual(const autodiff::StreamResidual<Scalar>& inner, Eigen::Index m, int scale)
      : inner_(inner), m_(m), scale_(scale) {}
  int components() const override { return inner_.components(); }
  void evaluate(Eigen::Index first, const autodiff::StreamLayout& layout, const autodiff::Streams<Scalar>& out,
                autodiff::Matrix<Scalar>& r) const override {
    autodiff::Streams<Scalar> part;
    slice_scale(out, scale_, m_, part);
    inner_.evaluate(first, layout, part, r);
  }
  void backward(Eigen::Index first, const autodiff::StreamLayout& layout, const autodiff::Streams<Scalar>& out,
                const autodiff::Matrix<Scalar>& r_bar, autodiff::Streams<Scalar>& adjoint) const override {
    autodiff::Streams<Scalar> part, part_adjoint;
    slice_scale(out, scale_, m_, part);
    part_adjoint.resize(out.points, out.count, m_);
    part_adjoint.data.setZero();
    inner_.backward(first, layout, part, r_bar, part_adjoint);
    adjoint.data.middleCols(scale_ * m_, m_) += part_adjoint.data;
  }

 private:
  const autodiff::StreamResidual<Scalar>& inner_;
  Eigen::Index m_;
  int scale_;
};

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
  if (options_.branches.empty()) {
    late_features_ = type.append_modules(options_, network_);
  } else {
    for (FieldBranch& branch : options_.branches)
      if (branch.options.activation.empty()) branch.options.activation = field_type(branch.options.type).default_activation();
    validate_branches(options_);
    late_features_ = append_branched_network(type, options_, network_, parts_);
  }
  scales_ = type.output_scales(options_);
  output_scale_ = type.output_scale(options_);
  all_scales_ = scales_ > 1 && type.trains_all_scales(options_);
  for (size_t m = 0; m < network_.modules().size(); ++m) {
    const autodiff::Module<Scalar>* module = network_.modules()[m].get();
    if (const auto* on = dynamic_cast<const autodiff::OnColumns<Scalar>*>(module)) module = &on->inner();
    if (dynamic_cast<const LatentCode<Scalar>*>(module)) latent_offset_ = network_.parameter_offset(m);
  }
  parameters_.setZero(network_.parameter_count());
  initialize();
}

template <typename Scalar>
void Field<Scalar>::initialize() {
  std::mt19937_64 rng(options_.seed);
  // Each part (the field's own network, each branch, fields/field_branches.h) counts its
  // dense layers from 0 and draws them as its own type would.
  std::vector<int> dense(options_.branches.size() + 1, 0);
  for (size_t m = 0; m < network_.modules().size(); ++m) {
    const auto& module = parameter_owner(*network_.modules()[m]);
    if (module.parameter_count() == 0) continue;
    Scalar* p = parameters_.data() + network_.parameter_offset(m);
    if (module.initialize(p, rng)) continue;  // e.g. hash-grid tables
    const int part = parts_.empty() ? 0 : parts_[m];
    const FieldOptions& own = part == 0 ? options_ : options_.branches[static_cast<size_t>(part - 1)].options;
    int& dense_index = dense[static_cast<size_t>(part)];
    const Eigen::Index in = module.input_width(), out = module.output_width();
    const InitialBounds bounds = field_type(own.type).initial_bounds(own, dense_index, in, out);
    for (Eigen::Index i = 0; i < in * out; ++i) p[i] = static_cast<Scalar>(uniform(rng, bounds.weight));
    for (Eigen::Index i = 0; i < out; ++i)
      p[in * out + i] = static_cast<Scalar>(bounds.bias > 0 ? uniform(rng, bounds.bias) : 0.0);
    if (part == 0 && dense_index == 0 && late_features_) {
      // W is out × in column-major (fields/dense.h); the features follow the d inputs.
      const Eigen::Index d = options_.input_dim;
      std::fill(p + d * out, p + in * out, Scalar(0));
    }
    ++dense_index;
  }
}

template <typename Scalar>
void Field<Scalar>::set_extra_parameters(const std::vector<double>& values) {
  const Eigen::Index n = network_.parameter_count();
  extra_ = static_cast<Eigen::Index>(values.size());
  parameters_.conservativeResize(n + extra_);
  for (Eigen::Index i = 0; i < extra_; ++i) parameters_(n + i) = static_cast<Scalar>(values[static_cast<std::size_t>(i)]);
}

template <typename Scalar>
void Field<Scalar>::begin_stage(int stage) {
  if (late_features_) late_features_->set_features_on(stage >= entry_stage(options_.encoding));
}

template <typename Scalar>
void Field<Scalar>::evaluate_scale(int scale, const autodiff::StreamLayout& layout,
                                   const Eigen::Ref<const autodiff::Matrix<Scalar>>& x,
                                   autodiff::Streams<Scalar>& out) const {
  network_.evaluate(parameters_.data(), layout, x, out);
  keep_scale(scale, options_.output_dim, scales_, out);
}

template <typename Scalar>
void Field<Scalar>::evaluate(const Scalar* theta, const autodiff::StreamLayout& layout,
                             const autodiff::Batch<Scalar>& batch, autodiff::Streams<Scalar>& out) const {
  network_.evaluate(theta, layout, batch, out);
  keep_scale(output_scale_, options_.output_dim, scales_, out);
}

template <typename Scalar>
double Field<Scalar>::value_and_gradient(const Scalar* theta, const autodiff::StreamLayout& layout,
                                         const autodiff::Batch<Scalar>& batch,
                                         const autodiff::StreamLoss<Scalar>& loss, Scalar* gradient) const {
  if (scales_ == 1) return network_.value_and_gradient(theta, layout, batch, loss, gradient);
  const ScaleLoss<Scalar> scaled(loss, options_.output_dim, all_scales_ ? 0 : output_scale_,
                                 all_scales_ ? scales_ : output_scale_ + 1);
  return network_.value_and_gradient(theta, layout, batch, scaled, gradient);
}

template <typename Scalar>
void Field<Scalar>::residuals_and_jacobian(const Scalar* theta, const autodiff::StreamLayout& layout,
                                           const autodiff::Batch<Scalar>& batch,
                                           const autodiff::StreamResidual<Scalar>& residual,
                                           Scalar* residuals, Scalar* jacobian) const {
  // With extra parameters, the network's rows are written narrow and then spread to rows of
  // parameter_count() (in place, from the last row back), zeros in the extra columns.
  if (scales_ == 1) {
    network_.residuals_and_jacobian(theta, layout, batch, residual, residuals, jacobian);
  } else {
    const ScaleResidual<Scalar> scaled(residual, options_.output_dim, output_scale_);
    network_.residuals_and_jacobian(theta, layout, batch, scaled, residuals, jacobian);
  }
  if (extra_ == 0 || !jacobian) return;
  const Eigen::Index n = network_.parameter_count(), p = n + extra_;
  for (Eigen::Index row = batch.points.rows() * residual.components() - 1; row >= 0; --row) {
    std::copy_backward(jacobian + row * n, jacobian + row * n + n, jacobian + row * p + n);
    std::fill(jacobian + row * p + n, jacobian + row * p + p, Scalar(0));
  }
}

template <typename Scalar>
autodiff::Matrix<Scalar> Field<Scalar>::values(const Eigen::Ref<const autodiff::Matrix<Scalar>>& x,
                                               int scale) const {
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(options_.input_dim));
  autodiff::Streams<Scalar> out;
  evaluate_scale(scale, layout, x, out);
  return out.data;
}

template <typename Scalar>
template <typename Other>
Field<Other> Field<Scalar>::cast() const {
  Field<Other> other(options_, network_.options());
  other.parameters() = parameters_.template cast<Other>();
  other.extra_ = extra_;
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
