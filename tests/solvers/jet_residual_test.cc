// SPDX-License-Identifier: MIT
//
// JetResidual (solvers/jet_residual.h): on a functor with a closed-form derivative, backward
// adds r̄ᵀ ∂r/∂z into the entries its reads name (other streams and channels untouched) and
// takes the per-point data of point first + row; the guards give the subgradient 0 where
// sqrt and abs have no derivative.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "solvers/jet_residual.h"

namespace nfield::solvers {
namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937_64& rng,
                              double lo = -1, double hi = 1) {
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(rng, lo, hi);
  return m;
}

autodiff::Streams<double> random_streams(const StreamLayout& layout, Eigen::Index points,
                                         int width, std::mt19937_64& rng) {
  autodiff::Streams<double> out;
  out.resize(points, layout.count(), width);
  out.data = random_matrix(out.data.rows(), width, rng);
  return out;
}

// r = [z₀ z₁ + c, sin(z₀) eᶻ¹] with c the point's constant, reading channel 1 of the value
// and channel 0 of tangent 1.
struct Toy {
  struct PointData {
    double c;
  };
  static constexpr int kReads = 2;
  static constexpr int kComponents = 2;
  Eigen::VectorXd constants;
  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return {StreamRead{StreamLayout::value(), 1}, StreamRead{layout.tangent(1), 0}};
  }
  PointData point(Eigen::Index index) const { return {constants(index)}; }
  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    using std::exp;
    using std::sin;
    r[0] = z[0] * z[1] + data.c;
    r[1] = sin(z[0]) * exp(z[1]);
  }
};

TEST(JetResidual, AddsTheClosedFormAdjointIntoTheStreamsItReads) {
  std::mt19937_64 rng(1);
  const StreamLayout layout(autodiff::StreamSpec::gradient(2));
  const Eigen::Index set = 9, first = 4, n = 5;
  const JetResidual<Toy> residual(Toy{random_matrix(set, 1, rng).col(0)});
  const autodiff::Streams<double> out = random_streams(layout, n, 2, rng);
  const Eigen::MatrixXd r_bar = random_matrix(n, 2, rng);
  Eigen::MatrixXd r;
  residual.evaluate(first, layout, out, r);
  autodiff::Streams<double> adjoint = random_streams(layout, n, 2, rng);
  const autodiff::Streams<double> before = adjoint;
  residual.backward(first, layout, out, r_bar, adjoint);
  autodiff::Streams<double> expected = before;
  for (Eigen::Index p = 0; p < n; ++p) {
    const double a = out.stream(StreamLayout::value())(p, 1), b = out.stream(layout.tangent(1))(p, 0);
    EXPECT_EQ(r(p, 0), a * b + residual.functor().constants(first + p));
    EXPECT_EQ(r(p, 1), std::sin(a) * std::exp(b));
    expected.stream(StreamLayout::value())(p, 1) +=
        r_bar(p, 0) * b + r_bar(p, 1) * std::cos(a) * std::exp(b);
    expected.stream(layout.tangent(1))(p, 0) += r_bar(p, 0) * a + r_bar(p, 1) * std::sin(a) * std::exp(b);
  }
  EXPECT_LT((adjoint.data - expected.data).cwiseAbs().maxCoeff(), 1e-14);
  // Entries it does not read are left exactly as they were.
  EXPECT_EQ(adjoint.stream(StreamLayout::value()).col(0), before.stream(StreamLayout::value()).col(0));
  EXPECT_EQ(adjoint.stream(layout.tangent(0)), before.stream(layout.tangent(0)));
  EXPECT_EQ(adjoint.stream(layout.tangent(1)).col(1), before.stream(layout.tangent(1)).col(1));
}

TEST(JetResidual, GuardsGiveTheSubgradientZeroWhereSqrtAndAbsHaveNone) {
  using Jet = ceres::Jet<double, 3>;
  const Jet zero[3] = {Jet(0.0, 0), Jet(0.0, 1), Jet(0.0, 2)};
  const Jet norm = norm_or_flat(zero, 3);
  EXPECT_EQ(norm.a, 0);
  EXPECT_TRUE(norm.v.isZero());  // a plain sqrt gives NaN here
  EXPECT_TRUE(abs_or_flat(zero[0]).v.isZero());
  EXPECT_TRUE(min_zero(zero[0]).v.isZero());
  const Jet g[2] = {Jet(3.0, 0), Jet(-4.0, 1)};
  const Jet five = norm_or_flat(g, 2);
  EXPECT_EQ(five.a, 5);
  EXPECT_NEAR(five.v(0), 0.6, 1e-15);
  EXPECT_NEAR(five.v(1), -0.8, 1e-15);
  EXPECT_EQ(abs_or_flat(Jet(-2.0, 2)).v(2), -1);
}

}  // namespace
}  // namespace nfield::solvers
