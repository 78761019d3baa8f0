// SPDX-License-Identifier: MIT
//
// A field f_θ: R^d → R^m, a coordinate network with one flat parameter vector θ, built by its
// field type (fields/field_type.h: siren, mlp, nerf, and types registered from outside).
//
// Encodings with parameters (hash_grid) draw their own initialization (Module::initialize),
// from the same engine, before the dense layers.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "autodiff/sequential.h"
#include "fields/encodings.h"
#include "fields/field_options.h"

namespace nfield::fields {

// The module that holds a layer's parameters: itself, or the module inside an
// autodiff::OnColumns (a Dense carried on some columns is still a Dense for initialization
// and checkpoints).
template <typename Scalar>
const autodiff::Module<Scalar>& parameter_owner(const autodiff::Module<Scalar>& module);

template <typename Scalar>
class Field {
 public:
  explicit Field(FieldOptions options, autodiff::SequentialOptions evaluation = {});

  const FieldOptions& options() const { return options_; }
  int input_dim() const { return options_.input_dim; }
  int output_dim() const { return options_.output_dim; }
  Eigen::Index parameter_count() const { return network_.parameter_count(); }

  autodiff::Vector<Scalar>& parameters() { return parameters_; }
  const autodiff::Vector<Scalar>& parameters() const { return parameters_; }
  // The fixed linear part of the encoding (encoding_matrix() of fields/encodings.h: B, or the
  // rows e_a of a cusp encoding; empty for the identity).
  const Eigen::MatrixXd& encoding_matrix() const { return encoding_matrix_; }

  const autodiff::Sequential<Scalar>& network() const { return network_; }
  autodiff::Sequential<Scalar>& network() { return network_; }

  // Draws θ from the initialization of `options().type` with `options().seed`; the first
  // layer's weights on cusp features that enter late (encoding.from_stage > 0) are zero.
  void initialize();

  // Training stage `stage` (0-based) begins: cusp features that enter at a later stage are
  // switched off until then (fields/encodings.h). A field nobody calls this on has them on.
  void begin_stage(int stage);

  // Output streams at x (N × d), at the field's own parameters.
  void evaluate(const autodiff::StreamLayout& layout, const Eigen::Ref<const autodiff::Matrix<Scalar>>& x,
                autodiff::Streams<Scalar>& out) const {
    network_.evaluate(parameters_.data(), layout, x, out);
  }

  // The passes a trainer runs, at parameters θ (parameter_count() values), over a batch of
  // points with optional per-point tangents and groups (autodiff/sequential.h).
  void evaluate(const Scalar* theta, const autodiff::StreamLayout& layout,
                const autodiff::Batch<Scalar>& batch, autodiff::Streams<Scalar>& out) const {
    network_.evaluate(theta, layout, batch, out);
  }
  // Σ of `loss` over the batch; adds ∂/∂θ into `gradient` (not cleared). Returns the sum.
  double value_and_gradient(const Scalar* theta, const autodiff::StreamLayout& layout,
                            const autodiff::Batch<Scalar>& batch,
                            const autodiff::StreamLoss<Scalar>& loss, Scalar* gradient) const {
    return network_.value_and_gradient(theta, layout, batch, loss, gradient);
  }
  // Per-point residuals and their Jacobian ∂r/∂θ (Sequential::residuals_and_jacobian).
  void residuals_and_jacobian(const Scalar* theta, const autodiff::StreamLayout& layout,
                              const autodiff::Batch<Scalar>& batch,
                              const autodiff::StreamResidual<Scalar>& residual,
                              Scalar* residuals, Scalar* jacobian) const {
    network_.residuals_and_jacobian(theta, layout, batch, residual, residuals, jacobian);
  }
  // Points per block and threads of every pass.
  void set_evaluation(const autodiff::SequentialOptions& evaluation) {
    network_.set_options(evaluation);
  }
  // Values only: N × output_dim.
  autodiff::Matrix<Scalar> values(const Eigen::Ref<const autodiff::Matrix<Scalar>>& x) const;

  // The same field in another scalar type (parameters converted).
  template <typename Other>
  Field<Other> cast() const;

 private:
  FieldOptions options_;
  Eigen::MatrixXd encoding_matrix_;
  autodiff::Sequential<Scalar> network_;
  autodiff::Vector<Scalar> parameters_;
  fields::FeatureEncoding<Scalar>* late_features_ = nullptr;  // in network_; set if from_stage > 0
};

}  // namespace nfield::fields
