// SPDX-License-Identifier: MIT
//
// Conditions by name (solvers/conditions/condition_list.h): each type's residual vanishes on
// a field that satisfies it and not on one that does not (per-output Dirichlet on two
// outputs, Neumann and Robin with outward normals, initial value and rate per output, the
// pde boundary residual), periodic pairs and their adjoint, a short periodic run whose
// error falls, hard per-output Dirichlet, and the refused items with their locations.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "fields/field.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/conditions/periodic.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

using autodiff::StreamLayout;
using autodiff::Streams;

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  return testutil::write_config("conditions", text, name);
}

// u_c(x) = exp(r_c · x) + k_c: closed-form streams for any layout without Taylor streams.
struct Exponential {
  std::vector<Eigen::VectorXd> rate;
  std::vector<double> shift;
};

Streams<double> streams_of(const StreamLayout& layout, const Exponential& f, const Eigen::MatrixXd& x) {
  const autodiff::StreamSpec& spec = layout.spec();
  const int channels = static_cast<int>(f.rate.size());
  Streams<double> s;
  s.resize(x.rows(), layout.count(), channels);
  for (Eigen::Index n = 0; n < x.rows(); ++n)
    for (int c = 0; c < channels; ++c) {
      const Eigen::VectorXd& r = f.rate[static_cast<size_t>(c)];
      const double e = std::exp(r.dot(x.row(n).transpose()));
      s.stream(0)(n, c) = e + f.shift[static_cast<size_t>(c)];
      const Eigen::VectorXd g = spec.tangents.transpose() * r;
      for (int i = 0; i < layout.tangents(); ++i) s.stream(layout.tangent(i))(n, c) = g(i) * e;
      for (int q = 0; q < layout.operators(); ++q)
        s.stream(layout.op(q))(n, c) = g.dot(spec.operators[static_cast<size_t>(q)] * g) * e;
    }
  return s;
}

// Term `name`'s residual at `n` of its points on field f.
Eigen::MatrixXd residual_on(const LossTerm& term, const Exponential& f, int n = 16) {
  Random rng(7);
  const TermPoints points = term.sample(rng, n);
  const StreamLayout layout(term.spec);
  Eigen::MatrixXd r;
  term.residual(points)->evaluate(0, layout, streams_of(layout, f, points.x), r);
  return r;
}

const LossTerm& term_named(const std::vector<LossTerm>& terms, const std::string& name) {
  for (const LossTerm& t : terms)
    if (t.name == name) return t;
  throw std::logic_error("no term " + name);
}

TEST(Conditions, PerOutputDirichletOnTwoOutputs) {
  const RunSetup setup = load_run(write_config("two_outputs", R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
outputs: [u, v]
equation:
  residuals: ["lap(u) - v", "lap(v)"]
conditions:
  - {on: boundary, type: dirichlet, value: {u: "exp(0.5*x - 0.25*y) + 1", v: "exp(-0.3*x + 0.7*y) + 2"}}
  - {on: [x_min], type: dirichlet, value: {v: "exp(0.7*y) + 2"}, weight: 3}
)yaml"), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  Exponential f{{Eigen::Vector2d(0.5, -0.25), Eigen::Vector2d(-0.3, 0.7)}, {1, 2}};
  const Eigen::MatrixXd both = residual_on(term_named(terms, "dirichlet"), f);
  const Eigen::MatrixXd v_only = residual_on(term_named(terms, "dirichlet_1"), f);
  EXPECT_EQ(term_named(terms, "dirichlet_1").weight, 3);
  ASSERT_EQ(both.cols(), 2);
  ASSERT_EQ(v_only.cols(), 1);  // u is free on x_min in this item
  EXPECT_LT(both.cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT(v_only.cwiseAbs().maxCoeff(), 1e-13);
  f.shift[1] = 2.5;  // v off by 0.5: only v's components see it
  EXPECT_LT(residual_on(term_named(terms, "dirichlet"), f).col(0).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_NEAR(residual_on(term_named(terms, "dirichlet"), f).col(1).minCoeff(), 0.5, 1e-13);
  EXPECT_NEAR(residual_on(term_named(terms, "dirichlet_1"), f).cwiseAbs().minCoeff(), 0.5, 1e-13);
}

// u = exp(0.5x − 0.25y) + 1: ∂u/∂n = −u_x on x_min; Robin a u + b ∂u/∂n with b varying in
// x on y_max (n = +e_y) and constant on x_max.
TEST(Conditions, NeumannAndRobinUseOutwardNormals) {
  const RunSetup setup = load_run(write_config("robin", R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
constants: {a: 2}
equation:
  residuals: ["lap(u) - 0.3125*exp(0.5*x - 0.25*y)"]
conditions:
  - {on: [x_min], type: neumann, value: {u: "-0.5*exp(-0.25*y)"}}
  - {on: [y_max], type: robin, a: a, b: "1 + x", value: {u: "a*(exp(0.5*x - 0.25) + 1) - 0.25*(1 + x)*exp(0.5*x - 0.25)"}}
  - {on: [x_max], type: robin, a: 2, b: 3, value: "2*(exp(0.5 - 0.25*y) + 1) + 1.5*exp(0.5 - 0.25*y)"}
)yaml"), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  Exponential f{{Eigen::Vector2d(0.5, -0.25)}, {1}};
  for (const char* name : {"pde", "neumann", "robin_1", "robin_2"}) {
    const Eigen::MatrixXd r = residual_on(term_named(terms, name), f);
    EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-12) << name;
  }
  f.rate[0] = Eigen::Vector2d(0.5, 0.25);  // another field: every condition sees it
  for (const char* name : {"neumann", "robin_1", "robin_2"})
    EXPECT_GT(residual_on(term_named(terms, name), f).cwiseAbs().maxCoeff(), 1e-2) << name;
}

TEST(Conditions, InitialValueAndRatePerOutput) {
  const RunSetup setup = load_run(write_config("initial", R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0, 1]}
outputs: [u, v]
equation:
  residuals: ["u_t - v", "v_t - u_xx"]
conditions:
  - {on: initial, type: value, value: {v: "exp(-0.3*x) + 2"}}
  - {on: initial, type: velocity, value: {u: "0.4*exp(0.2*x)"}}
)yaml"), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  Exponential f{{Eigen::Vector2d(0.2, 0.4), Eigen::Vector2d(-0.3, 0.6)}, {1, 2}};
  const Eigen::MatrixXd value = residual_on(term_named(terms, "initial"), f);
  const Eigen::MatrixXd rate = residual_on(term_named(terms, "initial_velocity_1"), f);
  ASSERT_EQ(value.cols(), 1);
  ASSERT_EQ(rate.cols(), 1);
  EXPECT_LT(value.cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT(rate.cwiseAbs().maxCoeff(), 1e-13);
  f.rate[0](1) = 0.5;  // u_t(x, 0) now 0.5 e^{0.2x}; v unchanged
  EXPECT_LT(residual_on(term_named(terms, "initial"), f).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_GT(residual_on(term_named(terms, "initial_velocity_1"), f).cwiseAbs().minCoeff(), 0.09);
}

// type: residual on faces reads outputs and derivatives: u_x + u − 1 = 0 for u = e^{−x} + 1.
TEST(Conditions, BoundaryResidualItem) {
  const RunSetup setup = load_run(write_config("residual", R"yaml(problem: pde
domain: {lower: [0], upper: [2]}
equation:
  residuals: ["u_xx - exp(-x)"]
conditions:
  - {on: [x_min], type: dirichlet, value: "2"}
  - {on: [x_max], type: residual, residual: "u_x + u - 1", weight: 5}
)yaml"), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  const LossTerm& term = term_named(terms, "boundary_residual_1");
  EXPECT_EQ(term.batch_key, "boundary");
  EXPECT_EQ(term.weight, 5);
  Random rng(1);
  EXPECT_TRUE((term.sample(rng, 4).x.col(0).array() == 2).all());
  Exponential f{{Eigen::VectorXd::Constant(1, -1.0)}, {1}};
  EXPECT_LT(residual_on(term, f).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT(residual_on(term_named(terms, "pde"), f).cwiseAbs().maxCoeff(), 1e-14);
  f.shift[0] = 1.5;
  EXPECT_NEAR(residual_on(term, f).cwiseAbs().minCoeff(), 0.5, 1e-14);
}

// Pairs (x, 0) and (x, 2) with u = sin(πy) + x², period 2 in y: r = 0; u = y: r ≠ 0.
TEST(Conditions, PeriodicPairsMatchValueAndSlope) {
  const RunSetup setup = load_run(write_config("periodic", R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 2]}
outputs: [u, v]
equation:
  residuals: ["lap(u) - v", "v - 2"]
conditions:
  - {on: [y_max, y_min], type: periodic, outputs: [u]}
)yaml"), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  const LossTerm& term = term_named(terms, "periodic");
  EXPECT_EQ(term.batch_key, "boundary");
  Random rng(3);
  const TermPoints p = term.sample(rng, 6);
  ASSERT_EQ(p.x.rows(), 12);
  ASSERT_EQ(p.groups.size(), 7u);
  for (Eigen::Index k = 0; k < 6; ++k) {
    EXPECT_EQ(p.groups[static_cast<size_t>(k)], 2 * k);
    EXPECT_EQ(p.x(2 * k, 0), p.x(2 * k + 1, 0));
    EXPECT_EQ(p.x(2 * k, 1), 0);
    EXPECT_EQ(p.x(2 * k + 1, 1), 2);
  }
  const StreamLayout layout(term.spec);
  ASSERT_EQ(layout.tangents(), 1);
  auto fill = [&](auto u, auto u_y) {
    Streams<double> s;
    s.resize(p.x.rows(), layout.count(), 2);
    for (Eigen::Index n = 0; n < p.x.rows(); ++n) {
      s.stream(0)(n, 0) = u(p.x(n, 0), p.x(n, 1));
      s.stream(layout.tangent(0))(n, 0) = u_y(p.x(n, 0), p.x(n, 1));
      s.stream(0)(n, 1) = p.x(n, 1);  // v is not tied: it may differ
      s.stream(layout.tangent(0))(n, 1) = 1;
    }
    return s;
  };
  const double pi = std::numbers::pi;
  const auto residual = term.residual(p);
  ASSERT_EQ(residual->components(), 2);
  Eigen::MatrixXd r;
  const Streams<double> periodic = fill([&](double x, double y) { return std::sin(pi * y) + x * x; },
                                        [&](double, double y) { return pi * std::cos(pi * y); });
  residual->evaluate(0, layout, periodic, r);
  ASSERT_EQ(r.rows(), 6);
  EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-14);
  const Streams<double> ramp = fill([](double, double y) { return y; }, [](double, double) { return 1.0; });
  residual->evaluate(0, layout, ramp, r);
  EXPECT_TRUE((r.col(0).array() == -2).all());
  EXPECT_TRUE((r.col(1).array() == 0).all());
  // The residual is linear in the streams: Σ r̄ ⊙ r(s) = Σ adjoint ⊙ s.
  std::mt19937 gen(4);
  std::normal_distribution<double> normal;
  Streams<double> s = periodic;
  for (Eigen::Index i = 0; i < s.data.size(); ++i) s.data(i) = normal(gen);
  residual->evaluate(0, layout, s, r);
  const Eigen::MatrixXd r_bar = Eigen::MatrixXd::NullaryExpr(r.rows(), r.cols(), [&] { return normal(gen); });
  Streams<double> adjoint = s;
  adjoint.data.setZero();
  residual->backward(0, layout, s, r_bar, adjoint);
  EXPECT_NEAR((r_bar.array() * r.array()).sum(), (adjoint.data.array() * s.data.array()).sum(), 1e-12);
  // A block from point 4 holds groups 2 … 4: the same rows as the whole set's.
  Streams<double> block;
  block.resize(6, layout.count(), 2);
  for (int k = 0; k < layout.count(); ++k) block.stream(k) = s.stream(k).middleRows(4, 6);
  Eigen::MatrixXd rb;
  residual->evaluate(4, layout, block, rb);
  ASSERT_EQ(rb.rows(), 3);
  EXPECT_EQ(rb, r.middleRows(2, 3));
}

// u'' + u = (1 − 4π²) sin 2πx on [0, 1] with periodic ends: the periodic item is all that
// rules out A cos x + B sin x, and a short Adam run through the trainer (groups of points)
// brings the error down.
// rel_l2 before and after a short Adam run of u'' + u = (1 − 4π²) sin 2πx on [0, 1] with
// the periodic item at `weight`.
std::pair<double, double> periodic_run(const std::string& weight) {
  RunSetup setup = load_run(write_config("periodic_run_" + weight, R"yaml(problem: pde
domain: {lower: [0], upper: [1]}
equation:
  residuals: ["u_xx + u - (1 - 4*pi^2)*sin(2*pi*x)"]
conditions:
  - {on: [x_min, x_max], type: periodic, weight: )yaml" + weight + R"yaml(}
reference: {exact: "sin(2*pi*x)"}
field: {type: siren, hidden: [24, 24], first_omega: 3, hidden_omega: 1}
training:
  seed: 0
  threads: 1
  precision: double
  batch: {interior: 128, boundary: 16}
  stages:
    - {optimizer: adam, steps: 400, lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}
)yaml"), {});
  fields::Field<double> field(setup.field);
  const Eigen::MatrixXd x = Eigen::VectorXd::LinSpaced(101, 0, 1);
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  const double before = (field.values(x) - exact).norm() / exact.norm();
  Trainer<double> trainer(*setup.problem, field, setup.training);
  EXPECT_TRUE(trainer.run({}));
  return {before, (field.values(x) - exact).norm() / exact.norm()};
}

// The periodic item is all that rules out A cos x + B sin x: with it a short Adam run
// through the trainer (groups of points) brings the error down; without it (weight 0) not.
TEST(Conditions, PeriodicRunLowersTheError) {
  const auto [before, after] = periodic_run("10");
  const auto [before_free, after_free] = periodic_run("0");
  std::printf("periodic u'' + u = f, 400 Adam steps: rel_l2 %.3e -> %.3e (weight 0: %.3e -> %.3e)\n", before,
              after, before_free, after_free);
  EXPECT_LT(after, before / 10);
  EXPECT_GT(after_free, 3 * after);
}

// A periodic term (groups of two points) under a hard initial value: the ansatz applies
// point by point, the pairs still match, and a short Adam run lowers the error of the heat
// equation's decaying mode u = exp(−4π²νt) sin 2πx.
TEST(Conditions, PeriodicUnderHardInitialValue) {
  RunSetup setup = load_run(write_config("periodic_hard", R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0, 1]}
constants: {nu: 0.01}
equation:
  residuals: ["u_t - nu*u_xx"]
conditions:
  - {on: [x_min, x_max], type: periodic}
  - {on: initial, type: value, value: "sin(2*pi*x)", enforce: hard}
reference: {exact: "exp(-4*pi^2*nu*t)*sin(2*pi*x)"}
field: {type: siren, hidden: [16, 16], first_omega: 2, hidden_omega: 1}
training:
  seed: 0
  threads: 1
  precision: double
  batch: {interior: 128, boundary: 32}
  stages:
    - {optimizer: adam, steps: 200, lr: 3.0e-3}
)yaml"), {});
  ASSERT_NE(setup.problem->ansatz(), nullptr);
  fields::Field<double> field(setup.field);
  Eigen::MatrixXd x(11 * 6, 2);
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 11; ++i) x.row(j * 11 + i) << i / 10.0, j / 5.0;
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  const auto error = [&] {
    return (setup.problem->ansatz()->values(x, field.values(x)) - exact).norm() / exact.norm();
  };
  const double before = error();
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const double after = error();
  std::printf("heat, periodic + hard initial value, 200 Adam steps: rel_l2 %.3e -> %.3e\n", before, after);
  EXPECT_LT(after, before / 3);
}

TEST(Conditions, HardPerOutputDirichlet) {
  const std::string head = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
outputs: [u, v]
equation:
  residuals: ["lap(u) - v", "lap(v)"]
conditions:
)yaml";
  const RunSetup hard = load_run(
      write_config("hard_both", head + "  - {on: boundary, type: dirichlet, value: {u: \"x\", v: \"0\"}, enforce: hard}\n"), {});
  ASSERT_NE(hard.problem->ansatz(), nullptr);
  EXPECT_EQ(hard.problem->loss_terms().size(), 2u);  // the residuals only
  Eigen::MatrixXd x(2, 2);
  x << 0.0, 0.3, 1.0, 0.6;
  const Eigen::MatrixXd u = hard.problem->ansatz()->values(x, Eigen::MatrixXd::Constant(2, 2, 5.0));
  EXPECT_NEAR(u(0, 0), 0, 1e-15);
  EXPECT_NEAR(u(1, 0), 1, 1e-15);
  EXPECT_NEAR(u(1, 1), 0, 1e-15);
  testutil::expect_located_error(
      write_config("hard_one", head + "  - {on: boundary, type: dirichlet, value: {u: \"x\"}, enforce: hard}\n"),
      {7, 44, "conditions[0].value", "a hard condition gives every output a value (outputs: u, v)"});
}

// Each refused item, located at its key.
TEST(Conditions, RefusedItemsAreLocated) {
  using testutil::expect_located_error;
  const std::string head = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
outputs: [u, v]
equation:
  residuals: ["lap(u) - v", "lap(v)"]
conditions:
)yaml";
  auto item = [&](const std::string& name, const std::string& text) { return write_config(name, head + "  - " + text + "\n"); };
  expect_located_error(item("unknown_output", "{on: boundary, type: dirichlet, value: {u: \"0\", w: \"1\"}}"),
                       {7, 56, "conditions[0].value.w", "'w' is no output (outputs: u, v)"});
  expect_located_error(item("unknown_face", "{on: [x_min, z_max], type: neumann, value: \"0\"}"),
                       {7, 10, "conditions[0].on", "unknown face 'z_max'"});
  expect_located_error(item("not_opposite", "{on: [x_min, y_max], type: periodic}"),
                       {7, 10, "conditions[0].on", "a periodic condition pairs two opposite faces of one axis (e.g. [x_min, x_max]); got x_min, y_max"});
  expect_located_error(item("one_face", "{on: [x_max], type: periodic}"),
                       {7, 10, "conditions[0].on", "pairs two opposite faces"});
  expect_located_error(item("periodic_output", "{on: [x_min, x_max], type: periodic, outputs: [p]}"),
                       {7, 51, "conditions[0].outputs", "'p' is no output (outputs: u, v)"});
  expect_located_error(item("hard_robin", "{on: [x_max], type: robin, a: 1, b: 1, value: \"0\", enforce: hard}"),
                       {7, 65, "conditions[0].enforce", "a Robin condition cannot be hard"});
  expect_located_error(item("hard_periodic", "{on: [x_min, x_max], type: periodic, enforce: hard}"),
                       {7, 51, "conditions[0].enforce", "a periodic condition cannot be hard"});
  expect_located_error(item("robin_without_b", "{on: [x_max], type: robin, a: 1, value: \"0\"}"),
                       {7, 5, "conditions[0].b", "missing required key 'b'"});
  expect_located_error(item("bad_residual", "{on: [x_max], type: residual, residual: \"u_x + q\"}"),
                       {7, 52, "conditions[0].residual", "unknown symbol 'q'"});
  expect_located_error(item("unknown_key", "{on: [x_max], type: dirichlet, value: \"0\", values: \"1\"}"),
                       {7, 48, "conditions[0].values", "unknown key 'values'"});
  expect_located_error(item("bad_type", "{on: [x_max], type: mixed, value: \"0\"}"),
                       {7, 25, "conditions[0].type", "dirichlet, neumann, robin, periodic, residual"});
  // Levenberg–Marquardt takes no periodic term (groups of points): refused at load.
  expect_located_error(write_config("periodic_lm", head + "  - {on: [x_min, x_max], type: periodic}\n" +
                                                       "training:\n  stages: [{optimizer: lm, steps: 3}]\n"),
                       {9, 24, "training.stages[0].optimizer", "loss term 'periodic' reads groups of points"});
  // Residual items belong to problem: pde.
  expect_located_error(write_config("poisson_residual", R"yaml(problem: poisson
domain: {lower: [0], upper: [1]}
equation: {source: "0"}
conditions:
  - {on: boundary, type: residual, residual: "u_x"}
)yaml"),
                       {5, 26, "conditions[0].type", "expected one of dirichlet, neumann, robin, periodic;"});
  // The wave equation's finite-difference reference takes no Robin item.
  expect_located_error(write_config("wave_robin", R"yaml(problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation: {speed: 1, reference: finite_difference}
conditions:
  - {on: [x_min], type: dirichlet, value: "0"}
  - {on: [x_max], type: robin, a: 1, b: 1, value: "0"}
  - {on: initial, type: value, value: "sin(pi*x)"}
  - {on: initial, type: velocity, value: "0"}
)yaml"),
                       {6, 25, "conditions[1].type", "takes dirichlet, neumann and initial conditions only"});
}

}  // namespace
}  // namespace nfield::solvers
