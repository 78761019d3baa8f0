// SPDX-License-Identifier: MIT
//
// Stream rules of an elementwise function y = σ(z) (activations, sin/cos encodings).
//
// Given the derivative tables dₘ = σ⁽ᵐ⁾(z⁰), the forward rules are
//
//   y⁰     = d₀
//   y⁽ⁱ⁾   = d₁ ⊙ z⁽ⁱ⁾
//   y^[C]  = d₁ ⊙ z^[C] + d₂ ⊙ Σᵢⱼ Cᵢⱼ z⁽ⁱ⁾ ⊙ z⁽ʲ⁾
//   y_k    = Σ_{m=1..k} (dₘ / m!) (δᵐ)_k          (Taylor, Faà di Bruno in power form)
//
// where δ = (0, z₁, …, z_K) is a Taylor series without its constant and δᵐ its m-th
// Cauchy power. The reverse rules are the adjoints of these (docs/design.md lists them); they
// read d₀ … d_{r+1} with r = StreamLayout::forward_order(), which is why a recording
// forward pass keeps one derivative table more than it uses.
//
// Pitfall: the tables are evaluated at z⁰ only, so σ must be smooth there to the order the
// streams need (ReLU gives zero second derivatives everywhere, which is its true a.e. value).
#pragma once

#include <vector>

#include "autodiff/streams.h"

namespace nfield::autodiff {

// An elementwise scalar function with derivatives of any order.
template <typename Scalar>
class ElementwiseFunction {
 public:
  virtual ~ElementwiseFunction() = default;
  // tables[m] = σ⁽ᵐ⁾(z), m = 0 … max_order, each shaped like z.
  virtual void derivatives(const Eigen::Ref<const Matrix<Scalar>>& z, int max_order,
                           std::vector<Matrix<Scalar>>& tables) const = 0;
};

// y from z, all streams; `tables` holds at least forward_order() + 1 entries.
template <typename Scalar>
void elementwise_forward(const StreamLayout& layout, const std::vector<Matrix<Scalar>>& tables,
                         const Streams<Scalar>& z, Streams<Scalar>& y);

// z̄ from ȳ, all streams; `tables` holds at least forward_order() + 2 entries.
template <typename Scalar>
void elementwise_backward(const StreamLayout& layout, const std::vector<Matrix<Scalar>>& tables,
                          const Streams<Scalar>& z, const Streams<Scalar>& y_adjoint,
                          Streams<Scalar>& z_adjoint);

// The elementwise product y = a ⊙ b of two quantities of the same width, all streams
// (Leibniz's rule; the integrated positional encoding multiplies sinusoids by damping
// factors, fields/integrated_positional.h):
//
//   y⁰     = a⁰ b⁰
//   y⁽ⁱ⁾   = a⁽ⁱ⁾ b⁰ + a⁰ b⁽ⁱ⁾
//   y^[C]  = a^[C] b⁰ + a⁰ b^[C] + Σᵢⱼ Cᵢⱼ (a⁽ⁱ⁾ b⁽ʲ⁾ + a⁽ʲ⁾ b⁽ⁱ⁾)
//   y_k    = Σ_{m=0..k} a_m b_{k−m}         (Taylor: the Cauchy product, a₀ = a⁰)
//
// The double sum runs over the layout's terms (i ≤ j, coefficient c = Cᵢⱼ + Cⱼᵢ off the
// diagonal, Cᵢᵢ on it) as Σ c (a⁽ⁱ⁾ b⁽ʲ⁾ + a⁽ʲ⁾ b⁽ⁱ⁾): a diagonal term gives 2Cᵢᵢ a⁽ⁱ⁾ b⁽ⁱ⁾.
template <typename Scalar>
void product_forward(const StreamLayout& layout, const Streams<Scalar>& a, const Streams<Scalar>& b,
                     Streams<Scalar>& y);

// ā and b̄ (overwritten) from ȳ: the adjoint of product_forward.
template <typename Scalar>
void product_backward(const StreamLayout& layout, const Streams<Scalar>& a, const Streams<Scalar>& b,
                      const Streams<Scalar>& y_adjoint, Streams<Scalar>& a_adjoint,
                      Streams<Scalar>& b_adjoint);

}  // namespace nfield::autodiff
