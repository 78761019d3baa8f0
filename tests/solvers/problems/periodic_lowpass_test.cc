// SPDX-License-Identifier: MIT
//
// The periodic low-pass of grid samples (solvers/problems/periodic_lowpass.h): sinusoids at or
// below the cut-off pass unchanged and those above vanish, per axis of a 1-, 2- and 3-axis grid;
// the result is an orthogonal projection (idempotent, its residual orthogonal to it); a cut-off
// at the grid's Nyquist limit changes nothing; a grid of the wrong size is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "solvers/problems/periodic_lowpass.h"

namespace nfield::solvers {
namespace {

using Dims = std::array<Eigen::Index, 3>;

// cos(2π (mx·i/Nx + my·j/Ny + mt·k/Nt) + phase) on the grid, x fastest.
Eigen::VectorXd wave(const Dims& n, const Dims& m, double phase) {
  Eigen::VectorXd v(n[0] * n[1] * n[2]);
  for (Eigen::Index k = 0; k < n[2]; ++k)
    for (Eigen::Index j = 0; j < n[1]; ++j)
      for (Eigen::Index i = 0; i < n[0]; ++i) {
        const double a = static_cast<double>(m[0] * i) / static_cast<double>(n[0]) +
                         static_cast<double>(m[1] * j) / static_cast<double>(n[1]) +
                         static_cast<double>(m[2] * k) / static_cast<double>(n[2]);
        v((k * n[1] + j) * n[0] + i) = std::cos(2 * std::numbers::pi * a + phase);
      }
  return v;
}

TEST(PeriodicLowpass, KeepsTheModesAtOrBelowTheCutoffAndRemovesTheOthers) {
  for (const Dims& n : {Dims{40, 1, 1}, Dims{32, 24, 1}, Dims{12, 10, 8}}) {
    const Dims cut{5, n[1] > 1 ? 3 : 0, n[2] > 1 ? 2 : 0};
    // Kept: every component within its axis' cut-off, the cut-off itself included.
    const Eigen::VectorXd kept = wave(n, {5, n[1] > 1 ? -3 : 0, n[2] > 1 ? 1 : 0}, 0.3) + 0.5 * wave(n, {1, 0, 0}, 1.1);
    // Removed: one component above its cut-off is enough.
    Eigen::VectorXd removed = wave(n, {6, 0, 0}, 0.7);
    if (n[1] > 1) removed += wave(n, {2, 4, 0}, -0.4);
    if (n[2] > 1) removed += wave(n, {0, 1, 3}, 2.0);
    Eigen::MatrixXd values(kept.size(), 2);
    values.col(0) = kept + removed;
    values.col(1) = 2.0 * removed - kept;
    periodic_lowpass(values, n, cut);
    EXPECT_LT((values.col(0) - kept).cwiseAbs().maxCoeff(), 1e-12) << n[0] << " x " << n[1] << " x " << n[2];
    EXPECT_LT((values.col(1) + kept).cwiseAbs().maxCoeff(), 1e-12) << n[0] << " x " << n[1] << " x " << n[2];
  }
}

TEST(PeriodicLowpass, IsAnOrthogonalProjection) {
  const Dims n{16, 9, 1};
  const Eigen::MatrixXd s = Eigen::MatrixXd::Random(16 * 9, 3);
  Eigen::MatrixXd p = s;
  periodic_lowpass(p, n, {3, 2, 0});
  Eigen::MatrixXd pp = p;
  periodic_lowpass(pp, n, {3, 2, 0});
  EXPECT_LT((pp - p).cwiseAbs().maxCoeff(), 1e-12);
  for (Eigen::Index c = 0; c < 3; ++c) EXPECT_NEAR((s - p).col(c).dot(p.col(c)), 0.0, 1e-12 * s.col(c).squaredNorm());
  EXPECT_GT((s - p).norm(), 0.5 * s.norm());  // random samples are mostly above such a cut-off
}

TEST(PeriodicLowpass, ACutoffAtTheNyquistLimitChangesNothing) {
  const Eigen::MatrixXd s = Eigen::MatrixXd::Random(16 * 9, 1);
  Eigen::MatrixXd p = s;
  periodic_lowpass(p, {16, 9, 1}, {8, 5, 0});
  EXPECT_EQ(p, s);
  // Just below it along x: the Nyquist mode (−1)^i goes.
  p = wave({16, 9, 1}, {8, 0, 0}, 0.0);
  periodic_lowpass(p, {16, 9, 1}, {7, 5, 0});
  EXPECT_LT(p.cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PeriodicLowpass, RefusesAGridOfAnotherSizeOrANegativeCutoff) {
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(10, 1);
  EXPECT_THROW(periodic_lowpass(s, {3, 3, 1}, {1, 1, 0}), std::invalid_argument);
  EXPECT_THROW(periodic_lowpass(s, {10, 1, 1}, {-1, 0, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
