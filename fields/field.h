// SPDX-License-Identifier: MIT
//
// A field f_θ: R^d → R^m, a coordinate network with one flat parameter vector θ, built by its
// field type (fields/field_type.h: siren, mlp, nerf, bacon, acorn, and types registered from outside).
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
  // θ as the optimizers see it: the network's parameters, then extra_parameters() trainable
  // numbers the network does not read (an inverse problem's unknown constants,
  // solvers/core/unknowns.h). The passes below read only the network's part; their gradient leaves
  // the extra entries as they are and their Jacobian rows have zeros there, for the caller to
  // fill. Checkpoints of the field (fields/field_io.h) keep the network's part only.
  Eigen::Index parameter_count() const { return network_.parameter_count() + extra_; }
  Eigen::Index network_parameter_count() const { return network_.parameter_count(); }
  Eigen::Index extra_parameters() const { return extra_; }
  // Appends `values` to θ (replacing extra entries already there).
  void set_extra_parameters(const std::vector<double>& values);

  autodiff::Vector<Scalar>& parameters() { return parameters_; }
  const autodiff::Vector<Scalar>& parameters() const { return parameters_; }
  // The fixed linear part of the encoding (encoding_matrix() of fields/encodings.h: B, or the
  // rows e_a of a cusp encoding; empty for the identity).
  const Eigen::MatrixXd& encoding_matrix() const { return encoding_matrix_; }

  const autodiff::Sequential<Scalar>& network() const { return network_; }
  autodiff::Sequential<Scalar>& network() { return network_; }

  // The latent code's slice of θ (fields/latent_code.h): its first index and its length c;
  // (−1, 0) when the field takes no code.
  Eigen::Index latent_offset() const { return latent_offset_; }
  int latent_size() const { return options_.latent_size; }

  // Draws θ from the initialization of `options().type` with `options().seed`; the first
  // layer's weights on cusp features that enter late (encoding.from_stage > 0) are zero.
  void initialize();

  // Training stage `stage` (0-based) begins: cusp features that enter at a later stage are
  // switched off until then (fields/encodings.h). A field nobody calls this on has them on.
  void begin_stage(int stage);

  // Scales (FieldType::output_scales; fields/bacon.h): the network has scales() · output_dim()
  // outputs, scale 0 first. Everything below shows output_scale()'s output_dim() columns, the
  // one problems, outputs and metrics see; value_and_gradient's loss is that scale's, or,
  // when the type trains all scales (BACON's sum of per-scale losses), the loss applied to
  // each scale's columns in turn and summed, each call by StreamLoss::evaluate_scale with its
  // scale (a loss whose target differs per scale overrides it; fit's band-limited targets). A
  // problem so needs no change to train a field with several scales. residuals_and_jacobian
  // (Levenberg–Marquardt) fits output_scale() alone: its residual count is fixed by the
  // problem. One field type's output streams are one quantity per scale; a single-scale field
  // (every other type) is scales() = 1 and passes straight through.
  int scales() const { return scales_; }
  int output_scale() const { return output_scale_; }
  bool trains_all_scales() const { return all_scales_; }

  // Output streams at x (N × d), at the field's own parameters: output_scale()'s, or `scale`'s.
  void evaluate(const autodiff::StreamLayout& layout, const Eigen::Ref<const autodiff::Matrix<Scalar>>& x,
                autodiff::Streams<Scalar>& out) const {
    evaluate_scale(output_scale_, layout, x, out);
  }
  void evaluate_scale(int scale, const autodiff::StreamLayout& layout,
                      const Eigen::Ref<const autodiff::Matrix<Scalar>>& x, autodiff::Streams<Scalar>& out) const;

  // The passes a trainer runs, at parameters θ (parameter_count() values), over a batch of
  // points with optional per-point tangents and groups (autodiff/sequential.h).
  void evaluate(const Scalar* theta, const autodiff::StreamLayout& layout,
                const autodiff::Batch<Scalar>& batch, autodiff::Streams<Scalar>& out) const;
  // Σ of `loss` over the batch; adds ∂/∂θ into `gradient` (not cleared). Returns the sum.
  double value_and_gradient(const Scalar* theta, const autodiff::StreamLayout& layout,
                            const autodiff::Batch<Scalar>& batch,
                            const autodiff::StreamLoss<Scalar>& loss, Scalar* gradient) const;
  // Per-point residuals and their Jacobian ∂r/∂θ (Sequential::residuals_and_jacobian).
  void residuals_and_jacobian(const Scalar* theta, const autodiff::StreamLayout& layout,
                              const autodiff::Batch<Scalar>& batch,
                              const autodiff::StreamResidual<Scalar>& residual,
                              Scalar* residuals, Scalar* jacobian) const;
  // Points per block and threads of every pass.
  void set_evaluation(const autodiff::SequentialOptions& evaluation) {
    network_.set_options(evaluation);
  }
  // Values only: N × output_dim (output_scale()'s, or `scale`'s).
  autodiff::Matrix<Scalar> values(const Eigen::Ref<const autodiff::Matrix<Scalar>>& x) const {
    return values(x, output_scale_);
  }
  autodiff::Matrix<Scalar> values(const Eigen::Ref<const autodiff::Matrix<Scalar>>& x, int scale) const;

  // The same field in another scalar type (parameters converted).
  template <typename Other>
  Field<Other> cast() const;

 private:
  template <typename>
  friend class Field;
  FieldOptions options_;
  Eigen::MatrixXd encoding_matrix_;
  autodiff::Sequential<Scalar> network_;
  autodiff::Vector<Scalar> parameters_;
  fields::FeatureEncoding<Scalar>* late_features_ = nullptr;  // in network_; set if from_stage > 0
  int scales_ = 1, output_scale_ = 0;
  bool all_scales_ = false;
  Eigen::Index extra_ = 0;
  Eigen::Index latent_offset_ = -1;
  std::vector<int> parts_;  // with branches: each module's part (fields/field_branches.h); else empty
};

}  // namespace nfield::fields
