// SPDX-License-Identifier: MIT
//
// A latent code z ∈ R^c joined to a layer's output (issue 28, item 1; DeepSDF's auto-decoder,
// Park et al. 2019): out = [in | z] at every point,
//
//   value      [a⁰ | z]
//   tangents, operators, Taylor coefficients
//              [a^(s) | 0]            z does not vary with x, so every derivative of it is 0.
//
// Reverse: ∂L/∂in = the first `width` columns of ∂L/∂out; ∂L/∂z = Σₙ of the value stream's
// last c columns of ∂L/∂out (point n's own term for a per-point Jacobian row). The other
// streams' adjoints of z's columns are dropped: z enters them with coefficient 0.
//
// Parameter slice: z (c values). A field holds one code (the instance it shows); a family's
// table of codes is kept by the run that trains them (solvers/run/latent_run.h), which writes
// instance k's row into this slice before each of k's passes. The slice starts at zero, the
// mean of the codes' Gaussian prior.
#pragma once

#include "autodiff/module.h"

namespace nfield::fields {

template <typename Scalar>
class LatentCode final : public autodiff::Module<Scalar> {
 public:
  LatentCode(Eigen::Index width, Eigen::Index code_size) : width_(width), size_(code_size) {}

  std::string name() const override { return "latent code"; }
  Eigen::Index input_width() const override { return width_; }
  Eigen::Index output_width() const override { return width_ + size_; }
  Eigen::Index parameter_count() const override { return size_; }
  bool initialize(Scalar* params, std::mt19937_64& rng) const override;

  void forward(const autodiff::StreamLayout& layout, const Scalar* params, const autodiff::Streams<Scalar>& in,
               autodiff::Streams<Scalar>& out, autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params, const autodiff::Streams<Scalar>& in,
                const autodiff::SavedTensors<Scalar>& saved, autodiff::Streams<Scalar>& out_adjoint,
                Scalar* gradient, autodiff::Streams<Scalar>* in_adjoint) const override;
  bool has_per_point_gradients() const override { return true; }
  void backward_per_point(const autodiff::StreamLayout& layout, const Scalar* params,
                          const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                          autodiff::Streams<Scalar>& out_adjoint, autodiff::JacobianRows<Scalar> jacobian,
                          autodiff::Streams<Scalar>* in_adjoint) const override;

 private:
  void pass_adjoint(const autodiff::Streams<Scalar>& out_adjoint, autodiff::Streams<Scalar>* in_adjoint) const;

  Eigen::Index width_, size_;
};

}  // namespace nfield::fields
