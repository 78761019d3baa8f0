// SPDX-License-Identifier: MIT
//
// Checks of a residual over groups of points (a ray's samples) on random output streams: its
// adjoint against central differences of Σ r̄ ⊙ r along a random direction, and rows that do
// not depend on where a block of the pass starts.
#pragma once

#include <gtest/gtest.h>

#include <random>

#include "solvers/core/residual.h"

namespace nfield::testutil {

// Random streams (out.count streams of `width` columns, entries in ±scale/2) for `points`.
inline solvers::Streams<double> random_streams(Eigen::Index points, int count, Eigen::Index width, double scale,
                                                std::mt19937_64& engine) {
  solvers::Streams<double> out;
  out.resize(points, count, width);
  for (Eigen::Index i = 0; i < out.data.size(); ++i)
    out.data.data()[i] = scale * (static_cast<double>(engine() >> 11) * 0x1.0p-53 - 0.5);
  return out;
}

// Runs the residual on `out` (rays given by `groups`) and checks backward against central
// differences; then that the rays from group `cut_group` on give the same rows when their
// block starts there. Returns the adjoint of `out`.
inline solvers::Streams<double> expect_ray_residual_adjoint(const solvers::Residual& residual,
                                                            const solvers::StreamLayout& layout,
                                                            const solvers::Streams<double>& out,
                                                            const std::vector<Eigen::Index>& groups,
                                                            size_t cut_group, std::mt19937_64& engine) {
  const auto rays = static_cast<Eigen::Index>(groups.size()) - 1;
  const Eigen::MatrixXd r_bar = random_streams(rays, 1, residual.components(), 1.0, engine).data;
  Eigen::MatrixXd r;
  residual.evaluate(0, layout, out, r);
  EXPECT_EQ(r.rows(), rays);
  EXPECT_EQ(r.cols(), residual.components());
  solvers::Streams<double> adjoint;
  adjoint.resize(out.points, out.count, out.width());
  adjoint.data.setZero();
  residual.backward(0, layout, out, r_bar, adjoint);

  const Eigen::MatrixXd v = random_streams(out.points, out.count, out.width(), 1.0, engine).data;
  auto objective = [&](double h) {
    solvers::Streams<double> moved = out;
    moved.data += h * v;
    Eigen::MatrixXd rh;
    residual.evaluate(0, layout, moved, rh);
    return (r_bar.array() * rh.array()).sum();
  };
  const double h = 1e-6, fd = (objective(h) - objective(-h)) / (2 * h);
  const double reverse = (adjoint.data.array() * v.array()).sum();
  EXPECT_NEAR(reverse, fd, 1e-7 * (1 + std::abs(fd)));

  const Eigen::Index cut = groups[cut_group];
  solvers::Streams<double> tail;
  tail.resize(out.points - cut, out.count, out.width());
  for (int s = 0; s < out.count; ++s) tail.stream(s) = out.stream(s).bottomRows(out.points - cut);
  Eigen::MatrixXd r_tail;
  residual.evaluate(cut, layout, tail, r_tail);
  EXPECT_EQ(r_tail.rows(), rays - static_cast<Eigen::Index>(cut_group));
  if (r_tail.rows() == rays - static_cast<Eigen::Index>(cut_group)) EXPECT_EQ(r_tail, r.bottomRows(r_tail.rows()));
  return adjoint;
}

}  // namespace nfield::testutil
