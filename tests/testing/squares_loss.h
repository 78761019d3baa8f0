// SPDX-License-Identifier: MIT
//
// A loss of all output streams for gradient tests: ½ Σₙ Σ_s Σ_o w_{s,o} out_s(n, o)².
#pragma once

#include <algorithm>

#include "autodiff/sequential.h"
#include "autodiff/stream_loss.h"

namespace nfield::testutil {

template <typename Scalar>
class SquaresLoss final : public autodiff::StreamLoss<Scalar> {
 public:
  // weights: count × output width.
  explicit SquaresLoss(Eigen::MatrixXd weights) : weights_(std::move(weights)) {}

  // Weights 1 / (N · max_n out_s(n, o)²) that make every stream count alike.
  static Eigen::MatrixXd balanced_weights(const autodiff::Streams<Scalar>& out) {
    Eigen::MatrixXd w(out.count, out.width());
    for (int s = 0; s < out.count; ++s)
      for (Eigen::Index o = 0; o < out.width(); ++o) {
        const double m = static_cast<double>(out.stream(s).col(o).cwiseAbs().maxCoeff());
        w(s, o) = m > 0 ? 1.0 / (m * m * static_cast<double>(out.points)) : 1.0;
      }
    return w;
  }

  // The loss of given streams, computed here rather than through evaluate().
  double value(const autodiff::Streams<Scalar>& out) const {
    double total = 0;
    for (int s = 0; s < out.count; ++s)
      for (Eigen::Index o = 0; o < out.width(); ++o)
        total += 0.5 * weights_(s, o) *
                 out.stream(s).col(o).template cast<double>().squaredNorm();
    return total;
  }

  double evaluate(Eigen::Index, const autodiff::StreamLayout&, const autodiff::Streams<Scalar>& out,
                  autodiff::Streams<Scalar>& adjoint) const override {
    for (int s = 0; s < out.count; ++s)
      for (Eigen::Index o = 0; o < out.width(); ++o)
        adjoint.stream(s).col(o) = static_cast<Scalar>(weights_(s, o)) * out.stream(s).col(o);
    return value(out);
  }

 private:
  Eigen::MatrixXd weights_;
};

}  // namespace nfield::testutil
