// SPDX-License-Identifier: MIT
//
// Affine layer z = W a + b over all streams at once: Z = A Wᵀ (one product over the stacked
// streams), then b is added to the value rows only, since a constant has no derivatives.
// Reverse: W̄ += Z̄ᵀ A, b̄ += Σₙ z̄⁰ₙ, Ā = Z̄ W.
// Per point (backward_per_point): W̄ₙ = Σ_s z̄_{s,n} a_{s,n}ᵀ (S outer products, one per
// stream), b̄ₙ = z̄⁰ₙ, written straight into point n's row of the row-major Jacobian, where
// W̄ₙ is out × in contiguous: each row is written once while it sits in L1, and no block
// of the Jacobian is ever transposed.
//
// Parameter slice: W as an out × in column-major matrix, then b (length out).
#pragma once

#include "autodiff/module.h"

namespace nfield::fields {

template <typename Scalar>
class Dense final : public autodiff::Module<Scalar> {
 public:
  Dense(Eigen::Index in, Eigen::Index out) : in_(in), out_(out) {}

  std::string name() const override { return "dense"; }
  Eigen::Index input_width() const override { return in_; }
  Eigen::Index output_width() const override { return out_; }
  Eigen::Index parameter_count() const override { return out_ * in_ + out_; }

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;
  bool has_per_point_gradients() const override { return true; }
  void backward_per_point(const autodiff::StreamLayout& layout, const Scalar* params,
                          const autodiff::Streams<Scalar>& in,
                          const autodiff::SavedTensors<Scalar>& saved,
                          autodiff::Streams<Scalar>& out_adjoint,
                          autodiff::JacobianRows<Scalar> jacobian,
                          autodiff::Streams<Scalar>* in_adjoint) const override;

 private:
  Eigen::Index in_, out_;
};

}  // namespace nfield::fields
