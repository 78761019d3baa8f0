// SPDX-License-Identifier: MIT
//
// Hard conditions (solvers/core/ansatz.h, read by solvers/conditions/hard_constraints.h): the
// streams of u = A + D·N against finite differences of u itself, the adjoint against finite
// differences of a loss, exact boundary and initial data, config errors, and a short Poisson
// run where hard beats soft.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "io/vtk_image.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/conditions.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<io::Expression> expressions(const Domain& domain, std::vector<std::string> texts) {
  std::vector<io::Expression> out;
  for (auto& t : texts) out.emplace_back(t, domain.expression_variables());
  return out;
}

fields::Field<double> small_siren(int inputs) {
  fields::FieldOptions o;
  o.input_dim = inputs;
  o.hidden = {16, 16};
  o.first_omega = 2;
  o.hidden_omega = 1;
  o.seed = 3;
  return fields::Field<double>(o);
}

// Gradient and Hessian of a scalar function at p by 4th-order central differences.
void fd_derivatives(const std::function<double(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& p,
                    double h, Eigen::VectorXd& g, Eigen::MatrixXd& hess) {
  const int d = static_cast<int>(p.size());
  const int off[4] = {-2, -1, 1, 2};
  const double w1[4] = {1.0 / 12, -8.0 / 12, 8.0 / 12, -1.0 / 12};
  const double w2[4] = {-1.0 / 12, 16.0 / 12, 16.0 / 12, -1.0 / 12};
  g.setZero(d);
  hess.setZero(d, d);
  const double f0 = f(p);
  for (int a = 0; a < d; ++a) {
    hess(a, a) = -2.5 * f0;
    for (int k = 0; k < 4; ++k) {
      Eigen::VectorXd q = p;
      q(a) += off[k] * h;
      const double v = f(q);
      g(a) += w1[k] * v / h;
      hess(a, a) += w2[k] * v;
    }
    hess(a, a) /= h * h;
    for (int b = a + 1; b < d; ++b) {
      double m = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          Eigen::VectorXd q = p;
          q(a) += off[i] * h;
          q(b) += off[j] * h;
          m += w1[i] * w1[j] * f(q);
        }
      hess(a, b) = hess(b, a) = m / (h * h);
    }
  }
}

// Every stream of u = A + D·N (the field's streams mapped by the ansatz) against finite
// differences of the scalar function u(x) = A(x) + D(x) N(x) evaluated from values only.
void expect_streams_match(const Ansatz& ansatz, const fields::Field<double>& field,
                          const autodiff::StreamSpec& spec, const Eigen::MatrixXd& x,
                          const std::function<double(const Eigen::VectorXd&)>& u_of) {
  const StreamLayout layout(spec);
  Streams<double> n, u;
  field.evaluate(layout, x, n);
  ansatz.apply(layout, ansatz.streams(layout, x), 0, n, u);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::VectorXd p = x.row(r).transpose();
    Eigen::VectorXd g;
    Eigen::MatrixXd h;
    fd_derivatives(u_of, p, 1e-3, g, h);
    EXPECT_NEAR(u.stream(0)(r, 0), u_of(p), 1e-13) << "value at row " << r;
    for (int i = 0; i < layout.tangents(); ++i)
      EXPECT_NEAR(u.stream(layout.tangent(i))(r, 0), g.dot(spec.tangents.col(i)), 1e-7)
          << "tangent " << i << " at row " << r;
    const Eigen::MatrixXd ht = spec.tangents.transpose() * h * spec.tangents;
    for (int q = 0; q < layout.operators(); ++q) {
      const double want = (spec.operators[q].array() * ht.array()).sum();
      EXPECT_NEAR(u.stream(layout.op(q))(r, 0), want, 2e-6 * (1 + std::abs(want)))
          << "operator " << q << " at row " << r;
    }
  }
}

Eigen::MatrixXd random_points(const Domain& domain, int n, unsigned seed) {
  Random rng(seed);
  return domain.sample_interior(rng, n);
}

// The finite-difference derivatives of g built into the ansatz against exact ones.
TEST(HardConstraints, ExpressionJetMatchesAnalyticDerivatives) {
  const Domain domain({0.0, 0.0}, {1.0, 2.0});
  const auto g = expressions(domain, {"sin(2*x)*exp(y) + x*y^2"});
  const Ansatz ansatz(domain, 1, Ansatz::Dirichlet{{domain.face("x_min")}, g}, std::nullopt);
  const Eigen::MatrixXd x = random_points(domain, 20, 1);
  const Jet jet = ansatz.base_jets(x, true)[0];
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const double a = x(r, 0), b = x(r, 1);
    EXPECT_NEAR(jet.value(r), std::sin(2 * a) * std::exp(b) + a * b * b, 1e-14);
    EXPECT_NEAR(jet.gradient(r, 0), 2 * std::cos(2 * a) * std::exp(b) + b * b, 1e-9);
    EXPECT_NEAR(jet.gradient(r, 1), std::sin(2 * a) * std::exp(b) + 2 * a * b, 1e-9);
    EXPECT_NEAR(jet.hessian[0](r), -4 * std::sin(2 * a) * std::exp(b), 1e-7);
    EXPECT_NEAR(jet.hessian[1](r), 2 * std::cos(2 * a) * std::exp(b) + 2 * b, 1e-7);
    EXPECT_NEAR(jet.hessian[2](r), jet.hessian[1](r), 0.0);
    EXPECT_NEAR(jet.hessian[3](r), std::sin(2 * a) * std::exp(b) + 2 * a, 1e-7);
  }
}

TEST(HardConstraints, DirichletStreamsMatchFiniteDifferences) {
  const Domain domain({0.0, 0.0}, {1.0, 2.0});
  const auto g = expressions(domain, {"sin(2*x)*exp(y) + x*y^2"});
  const Ansatz ansatz(domain, 1,
                      Ansatz::Dirichlet{{domain.face("x_min"), domain.face("x_max"), domain.face("y_max")}, g},
                      std::nullopt);
  const fields::Field<double> field = small_siren(2);
  auto u_of = [&](const Eigen::VectorXd& p) {
    const double gv = std::sin(2 * p(0)) * std::exp(p(1)) + p(0) * p(1) * p(1);
    const double phi = p(0) * (1 - p(0)) * (2 - p(1)) / 2;
    return gv + phi * field.values(p.transpose())(0, 0);
  };
  const Eigen::MatrixXd x = random_points(domain, 12, 2);
  // Axes with the Laplacian.
  expect_streams_match(ansatz, field, autodiff::StreamSpec::laplacian(2), x, u_of);
  // Oblique tangent directions and a general symmetric operator over them.
  autodiff::StreamSpec oblique = autodiff::StreamSpec::values(2);
  oblique.tangents.resize(2, 3);
  oblique.tangents << 0.6, -0.8, 1.0, 0.8, 0.6, 0.5;
  Eigen::MatrixXd c(3, 3);
  c << 1.0, 0.3, -0.2, 0.3, -2.0, 0.7, -0.2, 0.7, 0.5;
  oblique.add_operator(c);
  expect_streams_match(ansatz, field, oblique, x, u_of);
}

TEST(HardConstraints, WaveStreamsMatchFiniteDifferences) {
  const Domain domain({0.0}, {1.0}, std::pair{0.0, 2.0});
  const auto u0 = expressions(domain, {"sin(pi*x) + 0.5*sin(4*pi*x)"});
  const auto v0 = expressions(domain, {"sin(2*pi*x)"});
  const Ansatz ansatz(domain, 1, Ansatz::Dirichlet{domain.faces(), expressions(domain, {"0"})},
                      Ansatz::Initial{u0, v0});
  const fields::Field<double> field = small_siren(2);
  auto u_of = [&](const Eigen::VectorXd& p) {
    const double x = p(0), tau = p(1);
    const double a = std::sin(kPi * x) + 0.5 * std::sin(4 * kPi * x) + tau * std::sin(2 * kPi * x);
    return a + x * (1 - x) * (tau / 2) * (tau / 2) * field.values(p.transpose())(0, 0);
  };
  autodiff::StreamSpec spec = autodiff::StreamSpec::gradient(2);
  Eigen::MatrixXd wave = Eigen::MatrixXd::Zero(2, 2);
  wave(0, 0) = -4.0;
  wave(1, 1) = 1.0;
  spec.add_operator(wave);
  spec.add_operator(Eigen::MatrixXd::Identity(2, 2));
  expect_streams_match(ansatz, field, spec, random_points(domain, 12, 3), u_of);

  // The saturating time factor ψ = tanh(τ/s).
  const Ansatz saturating(domain, 1, Ansatz::Dirichlet{domain.faces(), expressions(domain, {"0"})},
                          Ansatz::Initial{u0, v0, 0.3});
  auto u_sat = [&](const Eigen::VectorXd& p) {
    const double x = p(0), tau = p(1), psi = std::tanh(tau / 0.3);
    const double a = std::sin(kPi * x) + 0.5 * std::sin(4 * kPi * x) + tau * std::sin(2 * kPi * x);
    return a + x * (1 - x) * psi * psi * field.values(p.transpose())(0, 0);
  };
  expect_streams_match(saturating, field, spec, random_points(domain, 12, 4), u_sat);
}

// A nonlinear residual r = (u⁰)² + Σ_s u_s: its backward must see u, not N.
class SquareResidual final : public Residual {
 public:
  int components() const override { return 1; }
  void evaluate(Eigen::Index, const StreamLayout&, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    r = out.stream(0).array().square().matrix();
    for (int s = 0; s < out.count; ++s) r += out.stream(s);
  }
  void backward(Eigen::Index, const StreamLayout&, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    adjoint.stream(0).array() += 2 * out.stream(0).array() * r_bar.array();
    for (int s = 0; s < out.count; ++s) adjoint.stream(s) += r_bar;
  }
};

TEST(HardConstraints, AdjointMatchesFiniteDifferences) {
  const Domain domain({0.0}, {1.0}, std::pair{0.0, 1.0});
  const Ansatz::Dirichlet dirichlet{{domain.face("x_max")}, expressions(domain, {"cos(x)*(1+t)"})};
  auto ansatz = std::make_shared<const Ansatz>(domain, 1, dirichlet, std::nullopt);
  autodiff::StreamSpec spec = autodiff::StreamSpec::values(2);
  spec.tangents.resize(2, 2);
  spec.tangents << 1.0, 0.4, -0.3, 1.0;
  Eigen::MatrixXd c(2, 2);
  c << -4.0, 0.5, 0.5, 1.0;
  spec.add_operator(c);
  const StreamLayout layout(spec);
  const Eigen::Index points = 6, first = 2, block = 3;
  const Eigen::MatrixXd x = random_points(domain, static_cast<int>(points), 4);
  const AnsatzResidual residual(ansatz, std::make_unique<SquareResidual>(), layout, x);

  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Streams<double> n;
  n.resize(block, layout.count(), 1);
  for (Eigen::Index i = 0; i < n.data.size(); ++i) n.data(i) = normal(rng);
  auto loss = [&](const Streams<double>& s) {
    Eigen::MatrixXd r;
    residual.evaluate(first, layout, s, r);
    return 0.5 * r.squaredNorm();
  };
  Eigen::MatrixXd r;
  residual.evaluate(first, layout, n, r);
  Streams<double> adjoint = n;
  adjoint.data.setZero();
  residual.backward(first, layout, n, r, adjoint);
  const double h = 1e-6;
  for (Eigen::Index i = 0; i < n.data.size(); ++i) {
    Streams<double> plus = n, minus = n;
    plus.data(i) += h;
    minus.data(i) -= h;
    const double fd = (loss(plus) - loss(minus)) / (2 * h);
    EXPECT_NEAR(adjoint.data(i), fd, 1e-6 * (1 + std::abs(fd))) << "entry " << i;
  }
  // The residual really depends on the factor: far from the hard face N moves it.
  EXPECT_GT(adjoint.data.cwiseAbs().maxCoeff(), 1e-3);
}

TEST(HardConstraints, BoundaryValuesAreExact) {
  const Domain domain({-1.0, 0.0}, {2.0, 1.0});
  const auto g = expressions(domain, {"exp(x)*cos(3*y) + 0.1"});
  const std::vector<Face> hard{domain.face("x_min"), domain.face("x_max"), domain.face("y_max")};
  const Ansatz ansatz(domain, 1, Ansatz::Dirichlet{hard, g}, std::nullopt);
  Random rng(9);
  for (const Face& f : domain.faces()) {
    const Eigen::MatrixXd x = domain.sample_face(f, rng, 50);
    const Eigen::MatrixXd network = Eigen::MatrixXd::Constant(x.rows(), 1, 0.7);
    const Eigen::MatrixXd u = ansatz.values(x, network);
    const Eigen::MatrixXd want = evaluate_channels(g, x);
    const double err = (u - want).cwiseAbs().maxCoeff();
    if (f.name() == "y_min")
      EXPECT_GT(err, 1e-3) << "y_min is not a hard face";  // the factor is not zero there
    else
      EXPECT_EQ(err, 0.0) << f.name();
  }
}

class InitialData : public ::testing::TestWithParam<double> {};

TEST_P(InitialData, ValueAndVelocityAreExact) {
  const Domain domain({0.0}, {1.0}, std::pair{0.5, 1.5});
  const auto u0 = expressions(domain, {"sin(pi*x) + 0.5*sin(4*pi*x)"});
  const auto v0 = expressions(domain, {"x*(1-x)*exp(x)"});
  const Ansatz ansatz(domain, 1, Ansatz::Dirichlet{domain.faces(), expressions(domain, {"0"})},
                      Ansatz::Initial{u0, v0, GetParam()});
  Random rng(11);
  const Eigen::MatrixXd x = domain.sample_initial(rng, 64);
  ASSERT_EQ(x(0, 1), 0.5);
  const fields::Field<double> field = small_siren(2);
  const StreamLayout layout(autodiff::StreamSpec::gradient(2));
  Streams<double> n, u;
  field.evaluate(layout, x, n);
  ansatz.apply(layout, ansatz.streams(layout, x), 0, n, u);
  const Eigen::VectorXd want_u = evaluate_channels(u0, x), want_v = evaluate_channels(v0, x);
  EXPECT_LT((u.stream(0).col(0) - want_u).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((u.stream(layout.tangent(1)).col(0) - want_v).cwiseAbs().maxCoeff(), 1e-15);
  // Later times are free: the network moves u there.
  Eigen::MatrixXd later = x;
  later.col(1).setConstant(1.2);
  const Eigen::MatrixXd n_later = field.values(later);
  EXPECT_GT((ansatz.values(later, n_later) - ansatz.values(later, 0 * n_later)).norm(), 1e-3);
}

// 0: ψ = τ/T; 0.2: ψ = tanh(τ/0.2).
INSTANTIATE_TEST_SUITE_P(HardConstraints, InitialData, ::testing::Values(0.0, 0.2));

// Orders above two (Taylor streams) are rejected, not silently mapped wrong.
TEST(HardConstraints, TaylorStreamsAreRejected) {
  const Domain domain({0.0}, {1.0});
  auto ansatz = std::make_shared<const Ansatz>(
      domain, 1, Ansatz::Dirichlet{domain.faces(), expressions(domain, {"0"})}, std::nullopt);
  LossTerm term;
  term.name = "biharmonic";
  term.spec = autodiff::StreamSpec::values(1);
  term.spec.set_taylor(Eigen::MatrixXd::Ones(1, 1), 4);
  try {
    with_ansatz({term}, ansatz);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Taylor"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ansatz->streams(StreamLayout(term.spec), Eigen::MatrixXd::Zero(3, 1)),
               std::invalid_argument);
}

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  return testutil::write_config("hard_constraints", text, name);
}

const char* kWaveHead = R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation: {speed: 2}
training: {batch: {interior: 16, boundary: 8, initial: 8}, stages: [{optimizer: adam, steps: 1}]}
)yaml";

// The ConfigError of a wave config with these conditions ("" when it loads).
std::string wave_error(const std::string& name, const std::string& conditions) {
  try {
    load_run(write_config(name, std::string(kWaveHead) + "conditions:\n" + conditions), {});
  } catch (const io::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(HardConstraints, ConfigErrors) {
  std::string e = wave_error("neumann", "  - {on: boundary, type: neumann, value: \"0\", enforce: hard}\n");
  EXPECT_NE(e.find("neumann.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("Neumann condition cannot be hard"), std::string::npos) << e;
  e = wave_error("bad_enforce", "  - {on: boundary, type: dirichlet, value: \"0\", enforce: exact}\n");
  EXPECT_NE(e.find("enforce"), std::string::npos) << e;
  EXPECT_NE(e.find("soft, hard"), std::string::npos) << e;
  e = wave_error("two_values", "  - {on: x_min, type: dirichlet, value: \"0\", enforce: hard}\n"
                               "  - {on: x_max, type: dirichlet, value: \"1\", enforce: hard}\n");
  EXPECT_NE(e.find("same value"), std::string::npos) << e;
  e = wave_error("velocity_alone", "  - {on: initial, type: velocity, value: \"0\", enforce: hard}\n");
  EXPECT_NE(e.find("needs the initial value hard"), std::string::npos) << e;
  e = wave_error("incompatible", "  - {on: boundary, type: dirichlet, value: \"0\", enforce: hard}\n"
                                 "  - {on: initial, type: value, value: \"cos(pi*x)\", enforce: hard}\n");
  EXPECT_NE(e.find("must equal the hard Dirichlet value"), std::string::npos) << e;
  e = wave_error("moving_velocity", "  - {on: boundary, type: dirichlet, value: \"0\", enforce: hard}\n"
                                    "  - {on: initial, type: value, value: \"sin(pi*x)\", enforce: hard}\n"
                                    "  - {on: initial, type: velocity, value: \"1\", enforce: hard}\n");
  EXPECT_NE(e.find("velocity must vanish"), std::string::npos) << e;
  e = wave_error("time_g", "  - {on: boundary, type: dirichlet, value: \"t\", enforce: hard}\n"
                           "  - {on: initial, type: value, value: \"0\", enforce: hard}\n");
  EXPECT_NE(e.find("depends on t"), std::string::npos) << e;
  e = wave_error("time_scale", "  - {on: initial, type: value, value: \"0\", enforce: hard, time_scale: -1}\n");
  EXPECT_NE(e.find("time_scale"), std::string::npos) << e;
  e = wave_error("soft_time_scale", "  - {on: initial, type: value, value: \"0\", time_scale: 0.1}\n");
  EXPECT_NE(e.find("unknown key 'time_scale'"), std::string::npos) << e;
  e = wave_error("weight", "  - {on: boundary, type: dirichlet, value: \"0\", enforce: hard, weight: 3}\n");
  EXPECT_NE(e.find("takes no weight"), std::string::npos) << e;
  // Compatible data loads, and hard conditions give no loss terms.
  e = wave_error("ok", "  - {on: boundary, type: dirichlet, value: \"0\", enforce: hard}\n"
                       "  - {on: initial, type: value, value: \"sin(pi*x)\", enforce: hard}\n"
                       "  - {on: initial, type: velocity, value: \"0\", enforce: hard}\n");
  EXPECT_EQ(e, "");
  const RunSetup ok = load_run(write_config("ok", std::string(kWaveHead) + "conditions:\n"
                       "  - {on: boundary, type: dirichlet, value: \"0\", enforce: hard}\n"
                       "  - {on: initial, type: value, value: \"sin(pi*x)\", enforce: hard}\n"), {});
  ASSERT_NE(ok.problem->ansatz(), nullptr);
  EXPECT_EQ(ok.problem->loss_terms().size(), 1u);
}

// Poisson on [0,1]², u* = sin(πx) sin(πy) + x² + y, g = x² + y on the boundary: the same
// short run with hard conditions ends with a smaller error than with soft ones, and an exact
// boundary.
double poisson_error(const std::string& enforce, double& boundary_error) {
  RunSetup setup = load_run(write_config("poisson_" + enforce, R"yaml(
problem: poisson
domain: {lower: [0, 0], upper: [1, 1]}
equation:
  source: "-2*pi^2*sin(pi*x)*sin(pi*y) + 2"
  exact: "sin(pi*x)*sin(pi*y) + x^2 + y"
conditions:
  - {on: boundary, type: dirichlet, value: "x^2 + y", enforce: )yaml" + enforce + R"yaml(}
field: {type: siren, hidden: [16, 16], first_omega: 2, hidden_omega: 1}
training:
  seed: 0
  threads: 1
  precision: double
  batch: {interior: 128, boundary: 64}
  stages:
    - {optimizer: adam, steps: 100, lr: 5.0e-3}
    - {optimizer: lbfgs, steps: 150}
)yaml"), {});
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  EXPECT_TRUE(trainer.run({}));
  const auto ansatz = setup.problem->ansatz();
  auto u_of = [&](const Eigen::MatrixXd& x) {
    const Eigen::MatrixXd n = field.values(x);
    return ansatz ? ansatz->values(x, n) : n;
  };
  Eigen::MatrixXd x(41 * 41, 2);
  for (int j = 0; j < 41; ++j)
    for (int i = 0; i < 41; ++i) x.row(j * 41 + i) << i / 40.0, j / 40.0;
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  Random rng(2);
  const Eigen::MatrixXd xb = setup.problem->domain().sample_faces(setup.problem->domain().faces(), rng, 200);
  boundary_error = (u_of(xb) - setup.problem->exact(xb)).cwiseAbs().maxCoeff();
  return (u_of(x) - exact).norm() / exact.norm();
}

TEST(HardConstraints, PoissonHardBeatsSoft) {
  double soft_boundary = 0, hard_boundary = 0;
  const double soft = poisson_error("soft", soft_boundary);
  const double hard = poisson_error("hard", hard_boundary);
  std::printf("poisson 2D: soft rel_l2 %.3e (boundary %.1e), hard rel_l2 %.3e (boundary %.1e)\n",
              soft, soft_boundary, hard, hard_boundary);
  EXPECT_LT(hard, soft);
  EXPECT_LT(hard_boundary, 1e-13);
  EXPECT_GT(soft_boundary, 1e-6);
}

// The written outputs see u, not N: after a short run (and again through nfield eval's
// evaluate_checkpoint), the grid's u equals g on the boundary points to rounding.
TEST(HardConstraints, GridOutputsAndEvalSeeTheAnsatz) {
  const std::filesystem::path dir = testutil::scratch_dir("hard_constraints");
  RunSetup setup = load_run(write_config("outputs", R"yaml(
problem: poisson
domain: {lower: [0, 0], upper: [1, 2]}
equation: {source: "2 + 2*x", exact: "x^2 + y + x*y^2"}
conditions:
  - {on: boundary, type: dirichlet, value: "x^2 + y + x*y^2", enforce: hard}
field: {type: siren, hidden: [8], first_omega: 2, hidden_omega: 1}
training:
  precision: float
  batch: {interior: 32}
  stages: [{optimizer: adam, steps: 5, lr: 1.0e-2}]
output: {grid: [9, 17], png: false}
)yaml"), {}, dir / "outputs_run");
  ASSERT_EQ(execute_run(setup), 0);
  evaluate_checkpoint(dir / "outputs_run" / "checkpoint.h5", 9, dir / "outputs_eval");
  for (const auto& path : {dir / "outputs_run" / "solution.vti", dir / "outputs_eval" / "solution.vti"}) {
    const io::ImageData image = io::read_vti(path);
    const Eigen::MatrixXd x = image.grid.points(2);
    const Eigen::VectorXd u = image.arrays.at("u");
    double boundary = 0, interior = 0;
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      const double a = x(r, 0), b = x(r, 1);
      const double err = std::abs(u(r) - (a * a + b + a * b * b));
      const bool on_face = a == 0 || a == 1 || b == 0 || b == 2;
      (on_face ? boundary : interior) = std::max(on_face ? boundary : interior, err);
    }
    EXPECT_LT(boundary, 1e-12) << path;
    EXPECT_GT(interior, 1e-4) << path << ": the network contributes inside";
  }
}

}  // namespace
}  // namespace nfield::solvers
