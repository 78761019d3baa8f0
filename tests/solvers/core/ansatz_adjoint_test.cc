// SPDX-License-Identifier: MIT
//
// The hard-condition ansatz u = A + D·N (solvers/core/ansatz.h) on random
// layouts: `apply` (the product rule in double) and `adjoint` (from the rule's bilinear
// coefficients, read off ceres::Jet passes) against the hand-written formulas they
// replaced, kept here as the reference; the adjoint against central differences of the
// forward map; the dot-product identity <ū, J n> = <Jᵀ ū, n>; the coefficients themselves.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "solvers/conditions/hard_constraints.h"

namespace nfield::solvers {
namespace {

// The product rule as written before ansatz_product_rule, over whole streams.
void reference_apply(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
                     const Streams<double>& n, Streams<double>& u) {
  const Eigen::Index p = n.points;
  u.resize(p, n.count, n.width());
  auto A = [&](int k) { return s.base.stream(k).middleRows(first, p); };
  auto D = [&](int k) { return s.factor.stream(k).col(0).segment(first, p).array(); };
  const auto n0 = n.stream(0).array();
  const auto d0 = D(0);
  u.stream(0) = A(0).array() + n0.colwise() * d0;
  for (int i = 0; i < layout.tangents(); ++i) {
    const int k = layout.tangent(i);
    u.stream(k) = A(k).array() + n0.colwise() * D(k) + n.stream(k).array().colwise() * d0;
  }
  for (int q = 0; q < layout.operators(); ++q) {
    const int k = layout.op(q);
    auto out = u.stream(k);
    out = A(k).array() + n0.colwise() * D(k) + n.stream(k).array().colwise() * d0;
    const Eigen::MatrixXd& c = layout.spec().operators[q];
    for (int i = 0; i < layout.tangents(); ++i)
      for (int j = 0; j < layout.tangents(); ++j)
        if (c(i, j) != 0)
          out.array() += (2.0 * c(i, j)) *
                         (n.stream(layout.tangent(j)).array().colwise() * D(layout.tangent(i)));
  }
}

// The hand-written adjoint the Jet pass replaced (the transpose in the header).
void reference_adjoint(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
                       const Streams<double>& u_bar, Streams<double>& n_bar) {
  const Eigen::Index p = u_bar.points;
  auto D = [&](int k) { return s.factor.stream(k).col(0).segment(first, p).array(); };
  const auto d0 = D(0);
  auto n0 = n_bar.stream(0);
  n0.array() += u_bar.stream(0).array().colwise() * d0;
  for (int i = 0; i < layout.tangents(); ++i) {
    const int k = layout.tangent(i);
    n0.array() += u_bar.stream(k).array().colwise() * D(k);
    n_bar.stream(k).array() += u_bar.stream(k).array().colwise() * d0;
  }
  for (int q = 0; q < layout.operators(); ++q) {
    const int k = layout.op(q);
    const auto ub = u_bar.stream(k).array();
    n0.array() += ub.colwise() * D(k);
    n_bar.stream(k).array() += ub.colwise() * d0;
    const Eigen::MatrixXd& c = layout.spec().operators[q];
    for (int i = 0; i < layout.tangents(); ++i)
      for (int j = 0; j < layout.tangents(); ++j)
        if (c(i, j) != 0)
          n_bar.stream(layout.tangent(j)).array() +=
              (2.0 * c(i, j)) * (ub.colwise() * D(layout.tangent(i)));
  }
}

std::vector<io::Expression> expressions(const Domain& domain, std::vector<std::string> texts) {
  std::vector<io::Expression> out;
  for (auto& t : texts) out.emplace_back(t, domain.expression_variables());
  return out;
}

Streams<double> random_streams(Eigen::Index points, int count, Eigen::Index width,
                               std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Streams<double> s;
  s.resize(points, count, width);
  for (Eigen::Index i = 0; i < s.data.size(); ++i) s.data(i) = normal(rng);
  return s;
}

// Value, gradient, Laplacian, the wave operator, and random ones: T random directions
// with up to three random symmetric operators over them (some entries zero, as in ∂xx), and
// one of more than 8 streams (J then takes two Jet passes).
std::vector<autodiff::StreamSpec> layouts(int d, std::mt19937& rng) {
  std::vector<autodiff::StreamSpec> out{autodiff::StreamSpec::values(d),
                                        autodiff::StreamSpec::gradient(d),
                                        autodiff::StreamSpec::laplacian(d)};
  autodiff::StreamSpec wave = autodiff::StreamSpec::gradient(d);
  Eigen::MatrixXd c = -4.0 * Eigen::MatrixXd::Identity(d, d);
  c(d - 1, d - 1) = 1;
  wave.add_operator(c);
  out.push_back(wave);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::uniform_int_distribution<int> ops(0, 3);
  for (int tangents = 1; tangents <= d + 2; ++tangents) {
    autodiff::StreamSpec spec = autodiff::StreamSpec::values(d);
    spec.tangents = Eigen::MatrixXd::NullaryExpr(d, tangents, [&] { return uniform(rng); });
    for (int q = tangents == d + 2 ? 5 : ops(rng); q > 0; --q) {
      Eigen::MatrixXd m = Eigen::MatrixXd::NullaryExpr(tangents, tangents, [&] {
        const double v = uniform(rng);
        return std::abs(v) < 0.3 ? 0.0 : v;
      });
      spec.add_operator(0.5 * (m + m.transpose()));
    }
    out.push_back(spec);
  }
  return out;
}

struct Case {
  std::string name;
  Domain domain;
  Ansatz ansatz;
};

// Dirichlet alone, initial data alone (both time factors), and both, with 1–3 channels.
std::vector<Case> cases() {
  std::vector<Case> out;
  {
    const Domain d({-1.0, 0.0}, {2.0, 1.0});
    out.push_back({"dirichlet 2D, 2 channels", d,
                   Ansatz(d, 2, Ansatz::Dirichlet{{d.face("x_min"), d.face("y_max")},
                                                  expressions(d, {"exp(x)*cos(3*y)", "x*y^2"})},
                          std::nullopt)});
  }
  {
    const Domain d({0.0}, {1.0}, std::pair{0.5, 1.5});
    out.push_back({"initial 1D + t, tanh", d,
                   Ansatz(d, 1, std::nullopt,
                          Ansatz::Initial{expressions(d, {"sin(pi*x)"}),
                                          expressions(d, {"x*(1-x)"}), 0.2})});
  }
  {
    const Domain d({0.0, 0.0}, {1.0, 2.0}, std::pair{0.0, 0.5});
    out.push_back({"dirichlet + initial 2D + t, 3 channels", d,
                   Ansatz(d, 3, Ansatz::Dirichlet{d.faces(), expressions(d, {"0", "x", "y^2"})},
                          Ansatz::Initial{expressions(d, {"sin(pi*x)*y", "x*cos(y)", "y^2"}),
                                          expressions(d, {"x*(1-x)", "0", "exp(-x)"}), 0})});
  }
  return out;
}

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / (1 + b.cwiseAbs().maxCoeff());
}

TEST(AnsatzAdjoint, JetAdjointMatchesHandWrittenAndFiniteDifferences) {
  std::mt19937 rng(17);
  int checked = 0;
  for (const Case& c : cases()) {
    const int d = c.domain.input_dim();
    Random sampler(3);
    // A block of 2 packs of 16 points (apply's vectorized path) and 5 single ones.
    const Eigen::Index points = 60, first = 7, block = 37;
    const Eigen::MatrixXd x = c.domain.sample_interior(sampler, static_cast<int>(points));
    for (const autodiff::StreamSpec& spec : layouts(d, rng)) {
      const StreamLayout layout(spec);
      const std::string where = c.name + ", " + std::to_string(layout.tangents()) + " tangents, " +
                                std::to_string(layout.operators()) + " operators";
      const AnsatzStreams s = c.ansatz.streams(layout, x);
      const int width = c.ansatz.channels();
      const Streams<double> n = random_streams(block, layout.count(), width, rng);
      const Streams<double> u_bar = random_streams(block, layout.count(), width, rng);

      // apply: the templated rule in double against the old whole-stream formula.
      Streams<double> u, u_ref;
      c.ansatz.apply(layout, s, first, n, u);
      reference_apply(layout, s, first, n, u_ref);
      EXPECT_LT(relative(u.data, u_ref.data), 1e-14) << where;

      // adjoint against the hand-written transpose, with the coefficients s carries and
      // with those computed on the call. They add to n_bar: start from the same contents.
      Streams<double> start = random_streams(block, layout.count(), width, rng);
      Streams<double> jet = start, ref = start, on_call = start;
      c.ansatz.adjoint(layout, s, first, u_bar, jet);
      reference_adjoint(layout, s, first, u_bar, ref);
      EXPECT_LT(relative(jet.data, ref.data), 1e-14) << where;
      AnsatzStreams bare = s;
      bare.terms.clear();
      c.ansatz.adjoint(layout, bare, first, u_bar, on_call);
      EXPECT_EQ(on_call.data, jet.data) << where;

      // Central differences of L(n) = <ū, apply(n)>. apply is affine in n, so they have no
      // truncation error at any step: only rounding, of about ε Σ|ū ⊙ u| / h.
      const Eigen::MatrixXd grad = jet.data - start.data;
      auto loss = [&](const Streams<double>& m) {
        Streams<double> out;
        c.ansatz.apply(layout, s, first, m, out);
        return (u_bar.data.array() * out.data.array()).sum();
      };
      const double h = 0.25;
      const double scale = 1 + (u_bar.data.array() * u.data.array()).abs().sum();
      for (Eigen::Index i = 0; i < n.data.size(); ++i) {
        Streams<double> plus = n, minus = n;
        plus.data(i) += h;
        minus.data(i) -= h;
        const double fd = (loss(plus) - loss(minus)) / (2 * h);
        EXPECT_NEAR(grad(i), fd, 1e-13 * scale / h) << where << ", entry " << i;
      }

      // <ū, apply(n) − apply(0)> = <adjoint(ū), n>: the linear part (A drops out).
      Streams<double> zero = n, u0;
      zero.data.setZero();
      c.ansatz.apply(layout, s, first, zero, u0);
      const double lhs = (u_bar.data.array() * (u.data - u0.data).array()).sum();
      const double rhs = (grad.array() * n.data.array()).sum();
      EXPECT_NEAR(lhs, rhs, 1e-13 * scale) << where;
      ++checked;
    }
  }
  EXPECT_EQ(checked, (4 + 4) + (4 + 4) + (4 + 5));  // layouts per case: 4 + d + 2
}

// The coefficients M_ijk for the 2D Laplacian layout: D⁰N⁰ in u⁰; D⁽ⁱ⁾N⁰ and D⁰N⁽ⁱ⁾ in
// u⁽ⁱ⁾; ΔD N⁰, D⁰ ΔN and 2 D⁽ⁱ⁾N⁽ⁱ⁾ in Δu; nothing else.
TEST(AnsatzAdjoint, BilinearTermsOfTheLaplacian) {
  const StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  const int v = 0, x = layout.tangent(0), y = layout.tangent(1), lap = layout.op(0);
  std::vector<std::tuple<int, int, int, double>> want{
      {v, v, v, 1},     {x, v, x, 1},     {x, x, v, 1},     {y, v, y, 1},    {y, y, v, 1},
      {lap, v, lap, 1}, {lap, lap, v, 1}, {lap, x, x, 2.0}, {lap, y, y, 2.0}};
  std::vector<std::tuple<int, int, int, double>> got;
  for (const AnsatzTerm& t : Ansatz::bilinear_terms(layout))
    got.emplace_back(t.u, t.n, t.d, t.coefficient);
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, want);
}

}  // namespace
}  // namespace nfield::solvers
