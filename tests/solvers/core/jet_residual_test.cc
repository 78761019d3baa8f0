// SPDX-License-Identifier: MIT
//
// JetResidual (solvers/core/jet_residual.h): on a functor with a closed-form derivative, backward
// adds r̄ᵀ ∂r/∂z into the entries its reads name (other streams and channels untouched) and
// takes the per-point data of point first + row. The eikonal residual (every kind and form,
// 2D and 3D, plain and factored) and the SDF residuals (surface and interior, siren and
// squares), now written once through it, give the values and adjoints of the hand-written
// residuals they replace (eikonal_reference.h, sdf_reference.h) to 1e-12, on random streams
// and at the points where the hand-written ones took a subgradient (∇u = 0, u = 0, x = x₀),
// and their adjoints equal central differences of their values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "solvers/core/jet_residual.h"
#include "tests/solvers/core/eikonal_reference.h"
#include "tests/solvers/core/sdf_reference.h"

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
    const double a = out.stream(StreamLayout::value())(p, 1);
    const double b = out.stream(layout.tangent(1))(p, 0);
    EXPECT_EQ(r(p, 0), a * b + residual.functor().constants(first + p));
    EXPECT_EQ(r(p, 1), std::sin(a) * std::exp(b));
    expected.stream(StreamLayout::value())(p, 1) +=
        r_bar(p, 0) * b + r_bar(p, 1) * std::cos(a) * std::exp(b);
    expected.stream(layout.tangent(1))(p, 0) +=
        r_bar(p, 0) * a + r_bar(p, 1) * std::sin(a) * std::exp(b);
  }
  EXPECT_LT((adjoint.data - expected.data).cwiseAbs().maxCoeff(), 1e-14);
  // Entries it does not read are left exactly as they were.
  EXPECT_EQ(adjoint.stream(StreamLayout::value()).col(0),
            before.stream(StreamLayout::value()).col(0));
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

// Largest |a − b| / (1 + |b|) over the entries.
double relative_gap(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  EXPECT_EQ(a.rows(), b.rows());
  EXPECT_EQ(a.cols(), b.cols());
  EXPECT_TRUE(a.allFinite());
  return ((a - b).array().abs() / (1 + b.array().abs())).maxCoeff();
}

double pairing(const Residual& residual, Eigen::Index first, const StreamLayout& layout,
               const autodiff::Streams<double>& out, const Eigen::MatrixXd& r_bar) {
  Eigen::MatrixXd r;
  residual.evaluate(first, layout, out, r);
  return (r.array() * r_bar.array()).sum();
}

// The new residual against the hand-written one on `out` (values and adjoints, 1e-12), and
// with `central_differences` its adjoint against central differences of its values.
void compare(const Residual& jet, const Residual& reference, const StreamLayout& layout,
             Eigen::Index first, const autodiff::Streams<double>& out, std::mt19937_64& rng,
             bool central_differences) {
  ASSERT_EQ(jet.components(), reference.components());
  Eigen::MatrixXd r, r_reference;
  jet.evaluate(first, layout, out, r);
  reference.evaluate(first, layout, out, r_reference);
  EXPECT_LT(relative_gap(r, r_reference), 1e-12);
  const Eigen::MatrixXd r_bar = random_matrix(out.points, jet.components(), rng);
  autodiff::Streams<double> adjoint = out, adjoint_reference = out;  // added to, not set
  jet.backward(first, layout, out, r_bar, adjoint);
  reference.backward(first, layout, out, r_bar, adjoint_reference);
  EXPECT_LT(relative_gap(adjoint.data, adjoint_reference.data), 1e-12);
  if (!central_differences) return;
  const double h = 1e-6;
  double worst = 0;
  for (Eigen::Index i = 0; i < out.data.size(); ++i) {
    autodiff::Streams<double> plus = out, minus = out;
    plus.data.data()[i] += h;
    minus.data.data()[i] -= h;
    const double fd =
        (pairing(jet, first, layout, plus, r_bar) - pairing(jet, first, layout, minus, r_bar)) /
        (2 * h);
    const double exact = adjoint.data.data()[i] - out.data.data()[i];
    worst = std::max(worst, std::abs(fd - exact) / (1 + std::abs(fd)));
  }
  EXPECT_LT(worst, 1e-7);
}

struct EikonalForm {
  EikonalKind kind;
  double viscosity;
  bool concave;
  const char* name;
};

TEST(JetResidual, EikonalEqualsTheHandWrittenResidualInEveryForm) {
  const EikonalForm forms[] = {
      {EikonalKind::kEikonal, 0, false, "eikonal"},
      {EikonalKind::kEikonal, 0.05, false, "eikonal, viscosity laplacian"},
      {EikonalKind::kEikonal, 0.05, true, "eikonal, viscosity concave"},
      {EikonalKind::kOutflow, 0, false, "outflow"},
      {EikonalKind::kInterface, 0, false, "interface"},
      {EikonalKind::kSource, 0, false, "source"},
  };
  std::mt19937_64 rng(7);
  for (const int d : {2, 3}) {
    for (const bool factored : {false, true}) {
      for (const EikonalForm& form : forms) {
        SCOPED_TRACE(std::string(form.name) + ", d = " + std::to_string(d) +
                     (factored ? ", factored" : ", plain"));
        const Eigen::Index set = 16, first = 5, n = set - first;
        EikonalSetup setup;
        setup.factored = factored;
        setup.x0 = random_matrix(d, 1, rng, 0, 1).col(0);
        setup.v0 = uniform(rng, 0.5, 2);
        setup.viscosity = form.viscosity;
        setup.concave = form.concave;
        setup.length = uniform(rng, 1, 2);
        setup.far_slowness = uniform(rng, 0.3, 1);
        Eigen::MatrixXd points = random_matrix(set, d, rng, 0, 1);
        points.row(first + 1) = setup.x0.transpose();  // T₀ = 0, ∇T₀ undefined (taken as 0)
        Eigen::MatrixXd per_point;
        if (form.kind == EikonalKind::kEikonal) {
          per_point = random_matrix(set, 1, rng, 0.3, 2);
        } else if (form.kind != EikonalKind::kSource) {
          per_point = random_matrix(set, d, rng);
          per_point.rowwise().normalize();
        }
        const auto jet = make_eikonal_residual(form.kind, points, per_point, setup);
        const reference::EikonalResidual hand(form.kind, points, per_point, setup);
        const autodiff::StreamSpec spec = form.kind == EikonalKind::kSource
                                              ? autodiff::StreamSpec::values(d)
                                          : form.viscosity > 0 ? autodiff::StreamSpec::laplacian(d)
                                                               : autodiff::StreamSpec::gradient(d);
        const StreamLayout layout(spec);
        for (const int width : {1, 2}) {
          autodiff::Streams<double> out = random_streams(layout, n, width, rng);
          // Factored, ΔT₀ ≈ (d − 1)/(v₀ |x − x₀|) makes Δu > 0 for Δτ in [−1, 1]: a wider
          // Δτ so that the concave form meets both signs.
          if (form.viscosity > 0) out.stream(layout.op(0)) *= 20;
          compare(*jet, hand, layout, first, out, rng, true);
        }
        // ∇u = 0 (plain) and the tangential gradient 0 (interface): the subgradients.
        autodiff::Streams<double> flat = random_streams(layout, n, 1, rng);
        if (form.kind != EikonalKind::kSource) {
          for (int a = 0; a < d; ++a) flat.stream(layout.tangent(a))(2, 0) = 0;
          if (form.kind == EikonalKind::kInterface && !factored)
            for (int a = 0; a < d; ++a)
              flat.stream(layout.tangent(a))(3, 0) = -0.5 * per_point(first + 3, a);
        }
        compare(*jet, hand, layout, first, flat, rng, false);
      }
    }
  }
}

TEST(JetResidual, SdfEqualsTheHandWrittenResidual) {
  std::mt19937_64 rng(8);
  const StreamLayout layout(autodiff::StreamSpec::gradient(3));
  for (const bool absolute : {true, false}) {
    for (const bool surface : {true, false}) {
      SCOPED_TRACE(std::string(surface ? "surface" : "interior") +
                   (absolute ? ", siren" : ", squares"));
      SdfWeights weights;
      weights.absolute = absolute;
      weights.alpha = 3;  // so that exp(−α|u|/2) is not flat at random u
      const Eigen::Index set = 14, first = 3, n = set - first;
      Eigen::MatrixXd normals;
      if (surface) {
        normals = random_matrix(set, 3, rng);
        normals.rowwise().normalize();
      }
      const auto jet = make_sdf_residual(normals, surface, weights);
      const reference::SdfResidual hand(normals, surface, weights);
      compare(*jet, hand, layout, first, random_streams(layout, n, 1, rng), rng, true);
      // u = 0, ∇u = 0 and |∇u| = 1: where √|·|, |·| and ĝ take a subgradient.
      autodiff::Streams<double> flat = random_streams(layout, n, 1, rng);
      flat.stream(StreamLayout::value())(0, 0) = 0;
      for (int a = 0; a < 3; ++a) flat.stream(layout.tangent(a))(1, 0) = 0;
      for (int a = 0; a < 3; ++a) flat.stream(layout.tangent(a))(2, 0) = a == 1 ? 1.0 : 0.0;
      compare(*jet, hand, layout, first, flat, rng, false);
    }
  }
}

}  // namespace
}  // namespace nfield::solvers
