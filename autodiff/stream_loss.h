// SPDX-License-Identifier: MIT
#pragma once

#include <functional>

#include "autodiff/streams.h"

namespace nfield::autodiff {

// A loss that is a sum over points of a function of each point's output streams (PDE
// residuals, data terms). Sequential::value_and_gradient calls it once per block of points,
// from several threads at once: it must be safe to call concurrently.
template <typename Scalar>
class StreamLoss {
 public:
  virtual ~StreamLoss() = default;
  // `out` holds the output streams of batch points [first, first + out.points). Returns
  // their loss sum and writes ∂loss/∂out into `adjoint` (sized like `out`, zero on entry).
  virtual double evaluate(Eigen::Index first, const StreamLayout& layout,
                          const Streams<Scalar>& out, Streams<Scalar>& adjoint) const = 0;
  // The same for the outputs of one scale of a field with one output per scale (BACON,
  // fields/field.h), which calls it once per trained scale. A loss whose target differs
  // from scale to scale (a picture low-passed to each scale's band) overrides it.
  virtual double evaluate_scale(int scale, Eigen::Index first, const StreamLayout& layout,
                                const Streams<Scalar>& out, Streams<Scalar>& adjoint) const {
    (void)scale;
    return evaluate(first, layout, out, adjoint);
  }
};

// A StreamLoss from a callable with the same signature.
template <typename Scalar>
class LambdaLoss final : public StreamLoss<Scalar> {
 public:
  using Function = std::function<double(Eigen::Index, const StreamLayout&,
                                        const Streams<Scalar>&, Streams<Scalar>&)>;
  explicit LambdaLoss(Function f) : f_(std::move(f)) {}
  double evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<Scalar>& out,
                  Streams<Scalar>& adjoint) const override {
    return f_(first, layout, out, adjoint);
  }

 private:
  Function f_;
};

}  // namespace nfield::autodiff
