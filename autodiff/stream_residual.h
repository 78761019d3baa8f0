// SPDX-License-Identifier: MIT
#pragma once

#include "autodiff/streams.h"

namespace nfield::autodiff {

// A per-point residual r(xₙ) ∈ R^C read from the output streams at xₙ alone (a PDE or a
// boundary condition at one collocation point). Sequential::residuals_and_jacobian
// differentiates it with respect to the parameters. Both methods are called once per block
// of points, from several threads at once: they must be safe to call concurrently.
template <typename Scalar>
class StreamResidual {
 public:
  virtual ~StreamResidual() = default;
  virtual int components() const = 0;
  // r (out.points × components()) for batch points [first, first + out.points).
  virtual void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                        Matrix<Scalar>& r) const = 0;
  // adjoint += ∂(Σₙ Σ_c r̄ₙ_c r_c(xₙ))/∂out, r̄ shaped like r. Since point n's residual reads
  // only point n's rows, the rows of point n then hold Σ_c r̄ₙ_c ∂r_c(xₙ)/∂outₙ.
  virtual void backward(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                        const Matrix<Scalar>& r_bar, Streams<Scalar>& adjoint) const = 0;
};

}  // namespace nfield::autodiff
