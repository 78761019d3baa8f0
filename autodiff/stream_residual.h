// SPDX-License-Identifier: MIT
#pragma once

#include "autodiff/streams.h"

namespace nfield::autodiff {

// Residuals read from a block's output streams: per point, r(xₙ) ∈ R^C from the streams at
// xₙ alone (a PDE or a boundary condition at one collocation point), or per group, one row
// of r per group of points that starts in the block (a ray's pixel colour from its samples;
// autodiff::groups_in_block). Sequential::residuals_and_jacobian differentiates per-point
// ones with respect to the parameters; a trainer turns either kind into a StreamLoss. Both
// methods are called once per block, from several threads at once: they must be safe to
// call concurrently.
template <typename Scalar>
class StreamResidual {
 public:
  virtual ~StreamResidual() = default;
  virtual int components() const = 0;
  // r for batch points [first, first + out.points): out.points × components() per point, or
  // one row per group in the block.
  virtual void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                        Matrix<Scalar>& r) const = 0;
  // adjoint += ∂(Σₙ Σ_c r̄ₙ_c r_c)/∂out, r̄ shaped like r. For a per-point residual, which
  // reads only point n's rows, the rows of point n then hold Σ_c r̄ₙ_c ∂r_c(xₙ)/∂outₙ.
  virtual void backward(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                        const Matrix<Scalar>& r_bar, Streams<Scalar>& adjoint) const = 0;

  // The residual of one scale's outputs of a field with one output per scale (BACON,
  // fields/field.h): itself, unless its target differs per scale (StreamLoss::evaluate_scale).
  virtual const StreamResidual& at_scale(int scale) const {
    (void)scale;
    return *this;
  }

  // Trainable numbers the residual reads besides the field's outputs (an inverse problem's
  // unknown constants, solvers/core/unknowns.h): how many (q, 0 for most residuals), and
  // ∂r/∂c for the block's rows of r, (rows · components()) × q, row n·C + c for r_c of
  // row n. Called like evaluate, from several threads at once.
  virtual int extra_parameters() const { return 0; }
  virtual void extra_jacobian(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                              Matrix<Scalar>& jacobian) const {
    (void)first;
    (void)layout;
    jacobian.setZero(out.points * components(), 0);
  }
};

}  // namespace nfield::autodiff
