// SPDX-License-Identifier: MIT
//
// The eikonal problem (solvers/problems/eikonal.cc): the nonlinear residual's backward pass is the
// adjoint of its evaluate (central differences, plain and factored, 2D and 3D); the exact
// first-arrival time of the two-layer medium equals a brute-force search over interface
// crossing points (direct, head and refracted waves) and satisfies |∇T| = 1/v; a short
// factored run learns the constant-speed cone; the per-stage error of a factored run is the
// travel time's, the same as the final one after the last stage; a viscosity list changes ε
// from stage to stage, and so does a viscosity_form list; the concave form counts negative
// Laplacians only; the interface term is zero for the exact two-layer field and penalizes an
// interface that emits waves into the source's layer faster than the far layer carries
// them; cusp features with from_stage stay at zero through the stages before it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  return testutil::write_config("eikonal", text, name);
}

const LossTerm& term_named(const std::vector<LossTerm>& terms, const std::string& name) {
  const auto term = std::find_if(terms.begin(), terms.end(),
                                 [&](const LossTerm& t) { return t.name == name; });
  if (term == terms.end()) throw std::logic_error("no loss term " + name);
  return *term;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// Σ r̄ ⊙ r(out) for the residual on points [first, first + out.points).
double pairing(const Residual& residual, Eigen::Index first, const autodiff::StreamLayout& layout,
               const autodiff::Streams<double>& out, const Eigen::MatrixXd& r_bar) {
  Eigen::MatrixXd r;
  residual.evaluate(first, layout, out, r);
  return (r.array() * r_bar.array()).sum();
}

// backward() against central differences of evaluate(), entry by entry of the streams, on
// the block of points [first, first + count) of the set.
void check_adjoint(const Residual& residual, const autodiff::StreamLayout& layout,
                   Eigen::Index first, Eigen::Index count, std::mt19937_64& rng, int width = 1) {
  autodiff::Streams<double> out;
  out.resize(count, layout.count(), width);
  for (Eigen::Index i = 0; i < out.data.size(); ++i) out.data.data()[i] = uniform(rng, -1, 1);
  Eigen::MatrixXd r_bar(count, residual.components());
  for (Eigen::Index i = 0; i < r_bar.size(); ++i) r_bar.data()[i] = uniform(rng, -1, 1);
  autodiff::Streams<double> adjoint;
  adjoint.resize(count, layout.count(), width);
  adjoint.data.setZero();
  residual.backward(first, layout, out, r_bar, adjoint);
  const double h = 1e-6;
  double worst = 0;
  for (Eigen::Index i = 0; i < out.data.size(); ++i) {
    autodiff::Streams<double> plus = out, minus = out;
    plus.data.data()[i] += h;
    minus.data.data()[i] -= h;
    const double fd = (pairing(residual, first, layout, plus, r_bar) -
                       pairing(residual, first, layout, minus, r_bar)) / (2 * h);
    worst = std::max(worst, std::abs(fd - adjoint.data.data()[i]) / (1 + std::abs(fd)));
  }
  EXPECT_LT(worst, 1e-7);
}

// The "pde", "outflow" and "source" terms of a config.
void check_pde_adjoint(const std::string& config) {
  const RunSetup setup = load_run(write_config("adjoint", config), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.at(0).name, "pde");
  ASSERT_EQ(terms.at(1).name, "outflow");
  ASSERT_EQ(terms.at(2).name, "source");
  const int width = setup.problem->output_dim();
  std::mt19937_64 rng(5);
  Random sampler(3);
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(terms[k].name);
    const Eigen::MatrixXd x = terms[k].sample(sampler, 24);
    const auto residual = terms[k].residual(x);
    const autodiff::StreamLayout layout(terms[k].spec);
    check_adjoint(*residual, layout, 0, 24, rng, width);
    check_adjoint(*residual, layout, 8, 16, rng, width);  // a later block: per-point data by index
  }
}

TEST(Eikonal, ResidualAdjointMatchesFiniteDifferences) {
  for (const char* factored : {"false", "true"}) {
    SCOPED_TRACE(factored);
    check_pde_adjoint(std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.25], speed: "1 + 0.5*x*y", outflow_weight: 1, factored: )") + factored + R"(}
training: {batch: {interior: 64, boundary: 64, source: 1}}
)");
    check_pde_adjoint(std::string(R"(
problem: eikonal
domain: {lower: [-1, -1, -1], upper: [1, 1, 1]}
equation:
  source: [0.1, -0.2, 0.3]
  layers: {axis: z, interface: 0.5, speeds: [1, 3]}
  outflow_weight: 1
  factored: )") + factored + R"(
training: {batch: {interior: 64, boundary: 64, source: 1}}
)");
    // The interface term, source below and above the plane.
    for (const char* source : {"[0.5, 0.25]", "[0.4, 0.7]"}) {
      SCOPED_TRACE(source);
      const RunSetup setup = load_run(write_config("interface_adjoint", std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: )") + source + R"(
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
  interface_weight: 1
  factored: )" + factored + R"(
training: {batch: {interior: 64, boundary: 64, source: 1, interface: 24}}
)"), {});
      const std::vector<LossTerm> terms = setup.problem->loss_terms();
      const LossTerm& interface = term_named(terms, "interface");
      Random sampler(4);
      const auto residual = interface.residual(interface.sample(sampler, 24));
      const autodiff::StreamLayout layout(interface.spec);
      std::mt19937_64 rng(6);
      check_adjoint(*residual, layout, 0, 24, rng);
      check_adjoint(*residual, layout, 8, 16, rng);
    }
    // The viscous term (Laplacian stream), both forms.
    for (const char* form : {"laplacian", "concave"}) {
      SCOPED_TRACE(form);
      check_pde_adjoint(std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: [0.5, 0.25]
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
  viscosity: 0.05
  viscosity_form: )") + form + R"(
  factored: )" + factored + R"(
training: {batch: {interior: 64, boundary: 64, source: 1}}
)");
    }
  }
}

// `viscosity_form: concave`: the term is ε min(0, Δu), with the whole Laplacian of
// u = T₀ (1 + τ) when factored, ΔT₀ = 1/(v₀ r) in 2D included; its adjoint is zero where
// Δu ≥ 0.
TEST(Eikonal, ConcaveViscosityCountsNegativeLaplaciansOnly) {
  for (const bool factored : {false, true}) {
    SCOPED_TRACE(factored);
    const RunSetup setup = load_run(write_config("concave", std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.25], speed: "2", viscosity: 0.1, viscosity_form: Concave, factored: )") +
                                                        (factored ? "true" : "false") + R"(}
training: {batch: {interior: 16, boundary: 16, source: 1}}
)"), {});
    const LossTerm pde = setup.problem->loss_terms().at(0);
    const autodiff::StreamLayout layout(pde.spec);
    Eigen::MatrixXd x(2, 2);
    x << 0.8, 0.65, 0.2, 0.1;
    const auto residual = pde.residual(x);
    autodiff::Streams<double> out;
    out.resize(2, layout.count(), 1);
    out.data.setZero();
    const double v0 = 2, tau = 0.25, grad_tau[2] = {0.3, -0.2};
    out.stream(autodiff::StreamLayout::value()).setConstant(tau);
    out.stream(layout.tangent(0)).setConstant(grad_tau[0]);
    out.stream(layout.tangent(1)).setConstant(grad_tau[1]);
    for (const double stream_laplacian : {-40.0, 3.0}) {
      SCOPED_TRACE(stream_laplacian);
      out.stream(layout.op(0)).setConstant(stream_laplacian);
      Eigen::MatrixXd r;
      residual->evaluate(0, layout, out, r);
      Eigen::MatrixXd r_bar = Eigen::MatrixXd::Ones(2, 1);
      autodiff::Streams<double> adjoint;
      adjoint.resize(2, layout.count(), 1);
      adjoint.data.setZero();
      residual->backward(0, layout, out, r_bar, adjoint);
      for (Eigen::Index p = 0; p < 2; ++p) {
        const double ex = x(p, 0) - 0.5, ey = x(p, 1) - 0.25, dist = std::hypot(ex, ey);
        const double t0 = dist / v0, gx = ex / (dist * v0), gy = ey / (dist * v0);
        double grad_norm, laplacian;
        if (factored) {
          grad_norm = std::hypot((1 + tau) * gx + t0 * grad_tau[0], (1 + tau) * gy + t0 * grad_tau[1]);
          laplacian = (1 + tau) / (v0 * dist) + 2 * (gx * grad_tau[0] + gy * grad_tau[1]) +
                      t0 * stream_laplacian;
        } else {
          grad_norm = std::hypot(grad_tau[0], grad_tau[1]);
          laplacian = stream_laplacian;
        }
        EXPECT_NEAR(r(p, 0), grad_norm - 1 / v0 - 0.1 * std::min(0.0, laplacian), 1e-13);
        const double laplacian_adjoint = adjoint.stream(layout.op(0))(p, 0);
        if (laplacian < 0)
          EXPECT_NEAR(laplacian_adjoint, -0.1 * (factored ? t0 : 1.0), 1e-13);
        else
          EXPECT_EQ(laplacian_adjoint, 0);
      }
    }
  }
}

// The "pde" residuals of a two-stage config at 8 points with |∇u| = 1 and Δu = 2 (plain
// form): before any begin_stage call, then in stage 0 and stage 1.
std::vector<Eigen::MatrixXd> residuals_per_stage(const std::string& name,
                                                 const std::string& equation) {
  const RunSetup setup = load_run(write_config(name, R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: )" + equation + R"(
training:
  batch: {interior: 16, boundary: 16, source: 1}
  stages: [{optimizer: adam, steps: 1}, {optimizer: adam, steps: 1}]
)"), {});
  LossTerm pde = setup.problem->loss_terms().at(0);
  EXPECT_TRUE(static_cast<bool>(pde.begin_stage));
  const autodiff::StreamLayout layout(pde.spec);
  EXPECT_EQ(layout.operators(), 1);  // the Laplacian stream, for the viscous stage
  Random sampler(2);
  const Eigen::MatrixXd x = pde.sample(sampler, 8);
  autodiff::Streams<double> out;
  out.resize(8, layout.count(), 1);
  out.data.setZero();
  out.stream(layout.tangent(0)).setConstant(0.6);
  out.stream(layout.tangent(1)).setConstant(0.8);  // |∇u| = 1
  out.stream(layout.op(0)).setConstant(2.0);       // Δu = 2
  std::vector<Eigen::MatrixXd> r(3);
  pde.residual(x)->evaluate(0, layout, out, r[0]);
  for (int stage = 0; stage < 2; ++stage) {
    if (pde.begin_stage) pde.begin_stage(stage);
    pde.residual(x)->evaluate(0, layout, out, r[stage + 1]);
  }
  return r;
}

// A viscosity list gives ε per stage: the residual follows begin_stage, and before any call
// it is the last stage's (what the outputs after training use).
TEST(Eikonal, ViscosityPerStage) {
  const auto r = residuals_per_stage(
      "viscosity_stages", R"({source: [0.5, 0.25], speed: "1", factored: false, viscosity: [0.5, 0]})");
  EXPECT_NEAR(r[0].cwiseAbs().maxCoeff(), 0, 1e-15);  // last stage: ε = 0
  for (Eigen::Index p = 0; p < 8; ++p) EXPECT_NEAR(r[1](p, 0), -0.5 * 2.0, 1e-15);
  EXPECT_NEAR(r[2].cwiseAbs().maxCoeff(), 0, 1e-15);
}

// A viscosity_form list gives the form per stage: with Δu = 2 > 0 the concave stage has no
// viscous term, the laplacian one has.
TEST(Eikonal, ViscosityFormPerStage) {
  const auto r = residuals_per_stage(
      "viscosity_form_stages",
      R"({source: [0.5, 0.25], speed: "1", viscosity: 0.5, viscosity_form: [laplacian, concave]})");
  EXPECT_NEAR(r[0].cwiseAbs().maxCoeff(), 0, 1e-15);  // last stage: concave
  for (Eigen::Index p = 0; p < 8; ++p) EXPECT_NEAR(r[1](p, 0), -0.5 * 2.0, 1e-15);
  EXPECT_NEAR(r[2].cwiseAbs().maxCoeff(), 0, 1e-15);
}

TEST(Eikonal, SourceTermAndFactoredExact) {
  for (const bool factored : {false, true}) {
    const RunSetup setup = load_run(write_config("source", std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.25], speed: "2", factored: )") + (factored ? "true" : "false") + R"(}
training: {batch: {interior: 64, boundary: 16, source: 3}}
)"), {});
    const auto terms = setup.problem->loss_terms();
    ASSERT_EQ(terms.size(), 3u);  // pde, outflow, source
    const LossTerm& source = terms[2];
    EXPECT_EQ(source.name, "source");
    EXPECT_EQ(source.batch_key, "source");
    Random rng(1);
    const Eigen::MatrixXd x = source.sample(rng, 3);
    ASSERT_EQ(x.rows(), 3);
    for (Eigen::Index p = 0; p < 3; ++p) EXPECT_EQ(x.row(p), Eigen::RowVector2d(0.5, 0.25));
    const autodiff::StreamLayout layout(source.spec);
    autodiff::Streams<double> out;
    out.resize(3, layout.count(), 1);
    out.data.setConstant(0.75);
    Eigen::MatrixXd r;
    source.residual(x)->evaluate(0, layout, out, r);
    EXPECT_NEAR(r(0, 0), 0.75, 1e-15);
    // Exact: u = |x − x₀|/2, or τ ≡ 0 when factored (u = T₀ (1 + τ)).
    Eigen::MatrixXd points(2, 2);
    points << 0.1, 0.9, 0.5, 0.25;
    const Eigen::MatrixXd exact = setup.problem->exact(points);
    if (factored) {
      EXPECT_FALSE(setup.problem->has_exact());  // the travel-time metrics come from write_outputs
      EXPECT_NEAR(exact(0, 0), 0, 1e-14);
      EXPECT_EQ(exact(1, 0), 0);
    } else {
      EXPECT_TRUE(setup.problem->has_exact());
      EXPECT_NEAR(exact(0, 0), std::hypot(0.4, 0.65) / 2, 1e-14);
      EXPECT_EQ(exact(1, 0), 0);
    }
  }
}

TEST(Eikonal, OutflowPenalizesIncomingWaves) {
  const RunSetup setup = load_run(write_config("outflow", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.25], speed: "2", outflow_weight: 1}
training: {batch: {interior: 64, boundary: 64, source: 1}}
)"), {});
  const auto terms = setup.problem->loss_terms();
  const LossTerm& outflow = terms.at(1);
  ASSERT_EQ(outflow.batch_key, "boundary");
  Random rng(6);
  const Eigen::MatrixXd x = outflow.sample(rng, 100);
  const autodiff::StreamLayout layout(outflow.spec);
  // Streams of ±u, u = |x − x₀|/2 (the exact solution and its mirror image).
  for (const double sign : {1.0, -1.0}) {
    autodiff::Streams<double> out;
    out.resize(x.rows(), layout.count(), 1);
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::Vector2d e = x.row(p).transpose() - Eigen::Vector2d(0.5, 0.25);
      out.stream(0)(p, 0) = sign * e.norm() / 2;
      for (int a = 0; a < 2; ++a) out.stream(layout.tangent(a))(p, 0) = sign * e(a) / (2 * e.norm());
    }
    Eigen::MatrixXd r;
    outflow.residual(x)->evaluate(0, layout, out, r);
    if (sign > 0)
      EXPECT_EQ(r.cwiseAbs().maxCoeff(), 0);
    else
      EXPECT_LT(r.maxCoeff(), 0);  // every boundary point sees the mirrored wave come in
  }
}

// Brute force in 2D, interface y = c: the best of the direct ray, every path through one
// interface point p (receivers across), and every path x₀ → (p, c) → (q, c) → x along the
// interface in the other layer (receivers on the source's side), by coarse-to-fine grid
// search over p (and q); the travel times are convex in (p, q).
double brute_force_time(double v_source, double v_other, double c, const Eigen::Vector2d& x0,
                        const Eigen::Vector2d& x) {
  const bool same = (x0(1) < c) == (x(1) < c);
  const double v_receiver = same ? v_source : v_other;
  auto leg = [c](const Eigen::Vector2d& a, double p) { return std::hypot(a(0) - p, a(1) - c); };
  double best = same ? (x - x0).norm() / v_source : std::numeric_limits<double>::infinity();
  if (!same) {
    double lo = -3, hi = 4;
    for (int level = 0; level < 8; ++level) {
      const int n = 2001;
      double arg = lo, value = std::numeric_limits<double>::infinity();
      for (int i = 0; i < n; ++i) {
        const double p = lo + (hi - lo) * i / (n - 1);
        const double t = leg(x0, p) / v_source + leg(x, p) / v_receiver;
        if (t < value) value = t, arg = p;
      }
      best = std::min(best, value);
      const double step = (hi - lo) / (n - 1);
      lo = arg - 3 * step;
      hi = arg + 3 * step;
    }
    return best;
  }
  double plo = -3, phi = 4, qlo = -3, qhi = 4;
  const int n = 801;
  std::vector<double> tp(n), tq(n);
  for (int level = 0; level < 8; ++level) {
    for (int i = 0; i < n; ++i) {
      tp[i] = leg(x0, plo + (phi - plo) * i / (n - 1)) / v_source;
      tq[i] = leg(x, qlo + (qhi - qlo) * i / (n - 1)) / v_source;
    }
    int bi = 0, bj = 0;
    double value = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      const double p = plo + (phi - plo) * i / (n - 1);
      for (int j = 0; j < n; ++j) {
        const double q = qlo + (qhi - qlo) * j / (n - 1);
        const double t = tp[i] + std::abs(q - p) / v_other + tq[j];
        if (t < value) value = t, bi = i, bj = j;
      }
    }
    best = std::min(best, value);
    const double sp = (phi - plo) / (n - 1), sq = (qhi - qlo) / (n - 1);
    const double bp = plo + sp * bi, bq = qlo + sq * bj;
    plo = bp - 3 * sp, phi = bp + 3 * sp, qlo = bq - 3 * sq, qhi = bq + 3 * sq;
  }
  return best;
}

std::string layered_config(double v1, double v2, const std::string& source = "[0.5, 0.25]") {
  char text[512];
  std::snprintf(text, sizeof text, R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: %s
  layers: {axis: y, interface: 0.5, speeds: [%g, %g]}
training: {batch: {interior: 64, source: 1}}
)", source.c_str(), v1, v2);
  return text;
}

TEST(Eikonal, LayeredExactMatchesBruteForce) {
  struct Case {
    double v1, v2;
    std::string source;
  };
  // Slow source layer (head waves), fast source layer, source above the interface.
  for (const Case& c : {Case{1, 2, "[0.5, 0.25]"}, Case{2, 1, "[0.5, 0.25]"}, Case{1, 3, "[0.3, 0.8]"}}) {
    SCOPED_TRACE(c.source + " " + std::to_string(c.v1) + " " + std::to_string(c.v2));
    const RunSetup setup = load_run(write_config("layered", layered_config(c.v1, c.v2, c.source)), {});
    std::mt19937_64 rng(11);
    Eigen::MatrixXd x(40, 2);
    for (Eigen::Index p = 0; p < x.rows(); ++p) x.row(p) << uniform(rng, 0, 1), uniform(rng, 0, 1);
    // Receivers where head waves arrive first (slow layer near the interface, far off).
    x.row(0) << 0.0, 0.45;
    x.row(1) << 1.0, 0.49;
    x.row(2) << 0.02, 0.3;
    const Eigen::VectorXd t = setup.problem->exact(x).col(0);
    const Eigen::Vector2d x0 = c.source == "[0.5, 0.25]" ? Eigen::Vector2d(0.5, 0.25) : Eigen::Vector2d(0.3, 0.8);
    const double v_source = x0(1) < 0.5 ? c.v1 : c.v2, v_other = x0(1) < 0.5 ? c.v2 : c.v1;
    int head_first = 0;
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::Vector2d xp = x.row(p).transpose();
      const double brute = brute_force_time(v_source, v_other, 0.5, x0, xp);
      EXPECT_NEAR(t(p), brute, 1e-9 * (1 + brute)) << "at " << xp.transpose();
      const bool same = (x0(1) < 0.5) == (xp(1) < 0.5);
      if (same && t(p) < (xp - x0).norm() / v_source - 1e-9) ++head_first;
    }
    if (v_other > v_source) EXPECT_GE(head_first, 3);  // the head wave cases are exercised
    if (v_other < v_source) EXPECT_EQ(head_first, 0);
  }
}

TEST(Eikonal, LayeredExactIn3DIsTheRotated2DSolution) {
  const RunSetup flat = load_run(write_config("flat", layered_config(1, 2)), {});
  const RunSetup solid = load_run(write_config("solid", R"(
problem: eikonal
domain: {lower: [0, 0, 0], upper: [1, 1, 1]}
equation:
  source: [0.5, 0.25, 0.4]
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
training: {batch: {interior: 64, source: 1}}
)"), {});
  std::mt19937_64 rng(2);
  Eigen::MatrixXd x(30, 3), x2(30, 2);
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    x.row(p) << uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1);
    x2.row(p) << 0.5 + std::hypot(x(p, 0) - 0.5, x(p, 2) - 0.4), x(p, 1);
  }
  const Eigen::VectorXd t3 = solid.problem->exact(x).col(0), t2 = flat.problem->exact(x2).col(0);
  EXPECT_LT((t3 - t2).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Eikonal, LayeredExactSolvesTheEikonalEquation) {
  for (const auto& [v1, v2] : {std::pair{1.0, 2.0}, std::pair{2.0, 1.0}}) {
    const RunSetup setup = load_run(write_config("gradient", layered_config(v1, v2)), {});
    const Eigen::Vector2d x0(0.5, 0.25);
    std::mt19937_64 rng(3);
    const double h = 1e-6;
    int checked = 0;
    for (int k = 0; k < 400; ++k) {
      const Eigen::Vector2d x(uniform(rng, 0, 1), uniform(rng, 0, 1));
      if ((x - x0).norm() < 0.05 || std::abs(x(1) - 0.5) < 0.01) continue;
      Eigen::MatrixXd stencil(4, 2);
      stencil << x(0) + h, x(1), x(0) - h, x(1), x(0), x(1) + h, x(0), x(1) - h;
      const Eigen::VectorXd t = setup.problem->exact(stencil).col(0);
      const double gx = (t(0) - t(1)) / (2 * h), gy = (t(2) - t(3)) / (2 * h);
      const double slowness = 1 / (x(1) < 0.5 ? v1 : v2);
      EXPECT_NEAR(std::hypot(gx, gy), slowness, 1e-6) << "at " << x.transpose();
      ++checked;
    }
    EXPECT_GT(checked, 300);
  }
}

// Interface points lie on the source's side of the plane, 1e-6 of the box off it. For the
// exact travel time (plain form, streams by hand) the term is zero on both of its branches:
// waves that cross the interface (∂u/∂n > 0) and the head wave (∂u/∂n < 0, tangential
// slowness 1/v_far). A field whose interface emits into the source's layer with a
// tangential slowness below 1/v_far (an interface "faster" than the far layer) is penalized
// by |∂u/∂n| (1/v_far − |∇_t u|).
TEST(Eikonal, InterfaceTermPenalizesAnInterfaceFasterThanTheFarLayer) {
  const RunSetup setup = load_run(write_config("interface", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: [0.5, 0.25]
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
  interface_weight: 1
training: {batch: {interior: 64, boundary: 16, source: 1, interface: 200}}
)"), {});
  const auto terms = setup.problem->loss_terms();
  const LossTerm& interface = term_named(terms, "interface");
  EXPECT_EQ(interface.batch_key, "interface");
  Random rng(3);
  const Eigen::MatrixXd x = interface.sample(rng, 200);
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    EXPECT_DOUBLE_EQ(x(p, 1), 0.5 - 1e-6);
    EXPECT_TRUE(x(p, 0) >= 0 && x(p, 0) <= 1);
  }
  const autodiff::StreamLayout layout(interface.spec);
  const double far = 0.5;  // 1/v above the plane
  // Streams of a field with gradient g at every point.
  auto residuals = [&](const std::function<Eigen::Vector2d(double)>& g) {
    autodiff::Streams<double> out;
    out.resize(x.rows(), layout.count(), 1);
    out.data.setZero();
    for (Eigen::Index p = 0; p < x.rows(); ++p)
      for (int a = 0; a < 2; ++a) out.stream(layout.tangent(a))(p, 0) = g(x(p, 0))(a);
    Eigen::MatrixXd r;
    interface.residual(x)->evaluate(0, layout, out, r);
    return r;
  };
  // The exact first arrival just below the plane, by finite differences of the built-in one.
  const double h = 1e-7;
  auto exact_gradient = [&](double xp) {
    auto t = [&](double a, double b) {
      return setup.problem->exact((Eigen::MatrixXd(1, 2) << a, b).finished())(0, 0);
    };
    const double y = 0.5 - 1e-6;
    return Eigen::Vector2d((t(xp + h, y) - t(xp - h, y)) / (2 * h),
                           (t(xp, y + h / 10) - t(xp, y - h / 10)) / (h / 5));
  };
  const Eigen::MatrixXd exact = residuals(exact_gradient);
  EXPECT_LT(exact.cwiseAbs().maxCoeff(), 1e-6);
  int head = 0;  // points where the exact field leaves the interface downwards
  for (Eigen::Index p = 0; p < x.rows(); ++p) head += exact_gradient(x(p, 0))(1) < 0;
  EXPECT_GT(head, 40);
  EXPECT_LT(head, 160);
  // A head wave whose tangential slowness is 0.4 < 1/2: r = 0.9165 · (0.5 − 0.4) everywhere.
  const double normal = std::sqrt(1 - 0.4 * 0.4);
  const Eigen::MatrixXd fast = residuals([&](double xp) {
    return Eigen::Vector2d(xp > 0.5 ? 0.4 : -0.4, -normal);
  });
  for (Eigen::Index p = 0; p < x.rows(); ++p) EXPECT_NEAR(fast(p, 0), normal * (far - 0.4), 1e-15);
  // The same field going up through the interface is not the term's business.
  const Eigen::MatrixXd up = residuals([&](double) { return Eigen::Vector2d(0.4, normal); });
  EXPECT_EQ(up.cwiseAbs().maxCoeff(), 0);
}

TEST(Eikonal, ConfigErrors) {
  EXPECT_THROW(load_run(write_config("both", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.5], speed: "1", layers: {axis: y, interface: 0.5, speeds: [1, 2]}}
training: {batch: {interior: 64, source: 1}}
)"), {}), io::ConfigError);
  EXPECT_THROW(load_run(write_config("outside", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [1.5, 0.5], speed: "1"}
training: {batch: {interior: 64, source: 1}}
)"), {}), io::ConfigError);
  EXPECT_THROW(load_run(write_config("no_source_batch", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.5], speed: "1"}
training: {batch: {interior: 64}}
)"), {}), io::ConfigError);
  try {
    load_run(write_config("viscosity_count", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.5], speed: "1", viscosity: [0.01, 0.001, 0]}
training: {batch: {interior: 64, source: 1}, stages: [{optimizer: adam, steps: 1}, {optimizer: adam, steps: 1}]}
)"), {});
    ADD_FAILURE() << "a viscosity list of the wrong length was accepted";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("viscosity"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("one value per training stage (2)"), std::string::npos) << e.what();
  }
  for (const auto& [form, message] :
       {std::pair{"viscous", "expected one of laplacian, concave; got 'viscous'"},
        std::pair{"[concave, upwind]", "expected one of laplacian, concave; got 'upwind'"},
        std::pair{"[concave]", "one value per training stage (2)"}}) {
    SCOPED_TRACE(form);
    try {
      load_run(write_config("viscosity_form", std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.5], speed: "1", viscosity: 0.01, viscosity_form: )") + form + R"(}
training: {batch: {interior: 64, source: 1}, stages: [{optimizer: adam, steps: 1}, {optimizer: adam, steps: 1}]}
)"), {});
      ADD_FAILURE() << "accepted";
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("viscosity_form"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(":4:"), std::string::npos) << e.what();  // line 4
    }
  }
  for (const auto& [equation, message] :
       {std::pair{"{source: [0.5, 0.5], speed: \"1\", interface_weight: 1}", "needs `layers`"},
        std::pair{"{source: [0.5, 0.25], layers: {axis: y, interface: 0.5, speeds: [1, 2]}, "
                  "interface_weight: -1}",
                  "expected a weight >= 0"}}) {
    SCOPED_TRACE(equation);
    try {
      load_run(write_config("interface_weight", std::string(R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: )") + equation + R"(
training: {batch: {interior: 64, source: 1, interface: 8}}
)"), {});
      ADD_FAILURE() << "accepted";
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("interface_weight"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(":4:"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(load_run(write_config("negative_viscosity", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.5], speed: "1", viscosity: -0.1}
training: {batch: {interior: 64, source: 1}}
)"), {}), io::ConfigError);
}

TEST(Eikonal, TinyFactoredRunLearnsTheCone) {
  const std::filesystem::path out = testutil::scratch_dir("eikonal") / "tiny_out";
  std::filesystem::remove_all(out);
  RunSetup setup = load_run(write_config("tiny", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.3, 0.6], speed: "2", factored: true}
field: {type: siren, hidden: [32, 32], first_omega: 3, hidden_omega: 1}
training:
  seed: 1
  threads: 2
  batch: {interior: 512, boundary: 128, source: 1}
  stages:
    - {optimizer: adam, steps: 500, lr: 2.0e-3, schedule: cosine, lr_final: 1.0e-4}
output: {grid: [32, 32], png: false}
)"), {}, out);
  ASSERT_EQ(execute_run(setup), 0);
  std::ifstream metrics(out / "metrics.json");
  const std::string text((std::istreambuf_iterator<char>(metrics)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"rel_l2\": ");
  ASSERT_NE(at, std::string::npos) << text;
  const double rel_l2 = std::stod(text.substr(at + 10));
  std::printf("tiny factored eikonal run: travel time rel_l2 %.3e\n", rel_l2);
  EXPECT_LT(rel_l2, 5e-2);
  EXPECT_TRUE(std::filesystem::exists(out / "travel_time.vti"));
  std::filesystem::remove_all(out);
}

// The factored network gives τ, so the grid does not compare it; the per-stage rel_l2 must
// still be the travel time's, after Adam and after LM, and the last one the final metric.
TEST(Eikonal, FactoredStageErrorsAreTheTravelTimeError) {
  const std::filesystem::path out = testutil::scratch_dir("eikonal") / "stages_out";
  std::filesystem::remove_all(out);
  RunSetup setup = load_run(write_config("stages", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: [0.5, 0.25]
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
  factored: true
field: {type: mlp, hidden: [8], activation: tanh}
training:
  seed: 2
  precision: double
  threads: 1
  batch: {interior: 128, boundary: 32, source: 1}
  stages:
    - {optimizer: adam, steps: 30, lr: 1.0e-2}
    - {optimizer: lm, steps: 5}
output: {grid: [17, 17], png: false}
)"), {}, out);
  ASSERT_EQ(execute_run(setup), 0);
  std::ifstream file(out / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(file);
  ASSERT_TRUE(metrics.contains("rel_l2")) << metrics.dump(2);
  const nlohmann::json& stages = metrics["stages"];
  ASSERT_EQ(stages.size(), 2u) << metrics.dump(2);
  for (const auto& stage : stages) {
    ASSERT_TRUE(stage.contains("rel_l2")) << metrics.dump(2);
    EXPECT_TRUE(std::isfinite(stage["rel_l2"].get<double>()));
    EXPECT_GT(stage["rel_l2"].get<double>(), 0);
  }
  // LM moved the field, so the two errors differ: the first is not the final one reused.
  EXPECT_NE(stages[0]["rel_l2"].get<double>(), stages[1]["rel_l2"].get<double>());
  EXPECT_EQ(stages[1]["rel_l2"].get<double>(), metrics["rel_l2"].get<double>());
  std::filesystem::remove_all(out);
}

// Cusp features with from_stage: 1 in a two-stage run: through Adam (stage 0) their
// first-layer weights stay exactly zero while the others train; LM (stage 1) trains them.
TEST(Eikonal, LateCuspFeaturesEnterAtTheirStage) {
  const RunSetup setup = load_run(write_config("late_cusp", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: [0.5, 0.25]
  layers: {axis: y, interface: 0.5, speeds: [1, 2]}
  factored: true
  interface_weight: 1
field: {type: mlp, hidden: [6], activation: tanh, encoding: {type: cusp, axis: y, at: [0.5], from_stage: 1}}
training:
  seed: 2
  precision: double
  threads: 1
  batch: {interior: 128, boundary: 32, source: 1, interface: 32}
  stages:
    - {optimizer: adam, steps: 30, lr: 1.0e-2}
    - {optimizer: lm, steps: 5}
)"), {});
  fields::Field<double> field(setup.field);
  const Eigen::VectorXd initial = field.parameters();
  // The first layer's weights are 6 × 3 column-major; column 2 multiplies |y − 0.5|.
  auto cusp_weights = [&] { return field.parameters().segment(2 * 6, 6); };
  ASSERT_EQ(cusp_weights().norm(), 0);
  std::vector<Eigen::VectorXd> after;
  Trainer<double> trainer(*setup.problem, field, setup.training);
  typename Trainer<double>::Callbacks callbacks;
  callbacks.stage_error = [&] {
    after.push_back(field.parameters());
    return 0.0;
  };
  ASSERT_TRUE(trainer.run(callbacks));
  ASSERT_EQ(after.size(), 2u);
  EXPECT_EQ(after[0].segment(2 * 6, 6).norm(), 0);
  EXPECT_GT((after[0] - initial).norm(), 1e-2);  // the rest did train
  EXPECT_GT(after[1].segment(2 * 6, 6).norm(), 0);
  // from_stage must name a stage the run has.
  try {
    load_run(write_config("late_cusp_beyond", R"(
problem: eikonal
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: [0.5, 0.25], layers: {axis: y, interface: 0.5, speeds: [1, 2]}}
field: {type: mlp, hidden: [6], encoding: {type: cusp, axis: y, at: [0.5], from_stage: 1}}
training: {batch: {interior: 64, boundary: 16, source: 1}}
)"), {});
    ADD_FAILURE() << "accepted";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("from_stage"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("number of training stages, 1"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(":5:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nfield::solvers
