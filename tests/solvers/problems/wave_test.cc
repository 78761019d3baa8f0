// SPDX-License-Identifier: MIT
//
// The wave problem (solvers/problems/wave.cc): its residuals vanish on exact solutions fed in as
// hand-built derivative streams (whatever the stream layout of each term), do not vanish on
// wrong ones, and a tiny training run learns a standing wave.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <string>

#include <nlohmann/json.hpp>

#include "io/vtk_image.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

constexpr double kPi = std::numbers::pi;

// An analytic function of the inputs with its gradient and Hessian.
struct Analytic {
  std::function<double(const Eigen::VectorXd&)> value;
  std::function<Eigen::VectorXd(const Eigen::VectorXd&)> gradient;
  std::function<Eigen::MatrixXd(const Eigen::VectorXd&)> hessian;
};

// u = a sin(kx πx) cos(ω t) in 1D + time (inputs x, t).
Analytic mode_1d(double a, double kx, double omega) {
  return {[=](const Eigen::VectorXd& p) { return a * std::sin(kx * kPi * p(0)) * std::cos(omega * p(1)); },
          [=](const Eigen::VectorXd& p) {
            Eigen::VectorXd g(2);
            g << a * kx * kPi * std::cos(kx * kPi * p(0)) * std::cos(omega * p(1)),
                -a * omega * std::sin(kx * kPi * p(0)) * std::sin(omega * p(1));
            return g;
          },
          [=](const Eigen::VectorXd& p) {
            const double k = kx * kPi, sx = std::sin(k * p(0)), cx = std::cos(k * p(0));
            const double st = std::sin(omega * p(1)), ct = std::cos(omega * p(1));
            Eigen::MatrixXd h(2, 2);
            h << -a * k * k * sx * ct, -a * k * omega * cx * st,
                -a * k * omega * cx * st, -a * omega * omega * sx * ct;
            return h;
          }};
}

Analytic operator+(const Analytic& f, const Analytic& g) {
  return {[=](const Eigen::VectorXd& p) { return f.value(p) + g.value(p); },
          [=](const Eigen::VectorXd& p) { return Eigen::VectorXd(f.gradient(p) + g.gradient(p)); },
          [=](const Eigen::VectorXd& p) { return Eigen::MatrixXd(f.hessian(p) + g.hessian(p)); }};
}

// u = sin(πx) sin(πy) cos(ω t) (inputs x, y, t).
Analytic mode_2d(double omega) {
  return {[=](const Eigen::VectorXd& p) {
            return std::sin(kPi * p(0)) * std::sin(kPi * p(1)) * std::cos(omega * p(2));
          },
          [=](const Eigen::VectorXd& p) {
            const double sx = std::sin(kPi * p(0)), cx = std::cos(kPi * p(0));
            const double sy = std::sin(kPi * p(1)), cy = std::cos(kPi * p(1));
            const double st = std::sin(omega * p(2)), ct = std::cos(omega * p(2));
            Eigen::VectorXd g(3);
            g << kPi * cx * sy * ct, kPi * sx * cy * ct, -omega * sx * sy * st;
            return g;
          },
          [=](const Eigen::VectorXd& p) {
            const double sx = std::sin(kPi * p(0)), cx = std::cos(kPi * p(0));
            const double sy = std::sin(kPi * p(1)), cy = std::cos(kPi * p(1));
            const double st = std::sin(omega * p(2)), ct = std::cos(omega * p(2));
            const double pp = kPi * kPi;
            Eigen::MatrixXd h(3, 3);
            h << -pp * sx * sy * ct, pp * cx * cy * ct, -kPi * omega * cx * sy * st,
                pp * cx * cy * ct, -pp * sx * sy * ct, -kPi * omega * sx * cy * st,
                -kPi * omega * cx * sy * st, -kPi * omega * sx * cy * st, -omega * omega * sx * sy * ct;
            return h;
          }};
}

// The streams a field equal to u would output for `layout` at points x: value,
// tangents vᵢ·∇u, operator streams Σᵢⱼ Cᵢⱼ vᵢᵀ H vⱼ.
autodiff::Streams<double> analytic_streams(const autodiff::StreamLayout& layout, const Analytic& u,
                                           const Eigen::MatrixXd& x) {
  EXPECT_EQ(layout.taylor_dirs(), 0);
  const autodiff::StreamSpec& spec = layout.spec();
  autodiff::Streams<double> s;
  s.resize(x.rows(), layout.count(), 1);
  for (Eigen::Index n = 0; n < x.rows(); ++n) {
    const Eigen::VectorXd p = x.row(n).transpose();
    s.stream(autodiff::StreamLayout::value())(n, 0) = u.value(p);
    const Eigen::VectorXd g = u.gradient(p);
    const Eigen::MatrixXd h = u.hessian(p);
    for (int i = 0; i < layout.tangents(); ++i) s.stream(layout.tangent(i))(n, 0) = spec.tangents.col(i).dot(g);
    // H in tangent coordinates: Vᵀ H V.
    const Eigen::MatrixXd ht = spec.tangents.transpose() * h * spec.tangents;
    for (int q = 0; q < layout.operators(); ++q)
      s.stream(layout.op(q))(n, 0) = (spec.operators[q].array() * ht.array()).sum();
  }
  return s;
}

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  return testutil::write_config("wave", text, name);
}

const LossTerm& term_named(const std::vector<LossTerm>& terms, const std::string& prefix) {
  for (const LossTerm& t : terms)
    if (t.name.rfind(prefix, 0) == 0) return t;
  throw std::runtime_error("no loss term " + prefix);
}

// Largest |r| over the term's own sample points, for u fed in as analytic streams.
double max_residual(const Problem& problem, const LossTerm& term, const Analytic& u, Eigen::Index n = 257) {
  Random rng(7);
  const Eigen::MatrixXd x = term.sample(rng, n);
  EXPECT_EQ(x.cols(), problem.domain().input_dim());
  const autodiff::StreamLayout layout(term.spec);
  const autodiff::Streams<double> streams = analytic_streams(layout, u, x);
  const auto residual = term.residual(x);
  Eigen::MatrixXd r;
  residual->evaluate(0, layout, streams, r);
  EXPECT_EQ(r.rows(), n);
  EXPECT_EQ(r.cols(), 1);
  return r.cwiseAbs().maxCoeff();
}

// Scale for relative checks: largest |u_tt| over the interior samples.
double max_utt(const Problem& problem, const Analytic& u) {
  Random rng(11);
  const Eigen::MatrixXd x = problem.domain().sample_interior(rng, 257);
  const int t = problem.domain().time_column();
  double m = 0;
  for (Eigen::Index n = 0; n < x.rows(); ++n) m = std::max(m, std::abs(u.hessian(x.row(n).transpose())(t, t)));
  return m;
}

const char* kStandingWave1d = R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation:
  speed: 2
  exact: "sin(pi*x)*cos(2*pi*t) + 0.5*sin(4*pi*x)*cos(8*pi*t)"
conditions:
  - {on: boundary, type: dirichlet, value: "0"}
  - {on: initial, type: value, value: "sin(pi*x) + 0.5*sin(4*pi*x)", weight: 10}
  - {on: initial, type: velocity, value: "0", weight: 10}
)yaml";

const Analytic kStanding = mode_1d(1.0, 1.0, 2 * kPi) + mode_1d(0.5, 4.0, 8 * kPi);

TEST(Wave, StandingWaveResidualVanishes) {
  const RunSetup setup = load_run(write_config("standing", kStandingWave1d), {});
  const Problem& problem = *setup.problem;
  const auto terms = problem.loss_terms();
  ASSERT_EQ(terms[0].name, "pde");
  // Constant speed: one operator stream over (x, t).
  EXPECT_EQ(terms[0].spec.operators.size(), 1u);
  const double scale = max_utt(problem, kStanding);
  ASSERT_GT(scale, 100.0);
  EXPECT_LT(max_residual(problem, terms[0], kStanding), 1e-9 * scale);
  // Each mode alone is a solution too (the equation is linear and f = 0).
  EXPECT_LT(max_residual(problem, terms[0], mode_1d(1.0, 4.0, 8 * kPi)), 1e-9 * scale);
  // Wrong: right shape, wrong time frequency (c = 1 instead of 2), and the wrong speed.
  EXPECT_GT(max_residual(problem, terms[0], mode_1d(1.0, 1.0, kPi)), 0.5 * 3 * kPi * kPi);
  EXPECT_GT(max_residual(problem, terms[0], mode_1d(1.0, 4.0, 4 * kPi)), 10.0);
  // The exact solution meets its conditions.
  EXPECT_LT(max_residual(problem, term_named(terms, "dirichlet"), kStanding), 1e-12);
  EXPECT_LT(max_residual(problem, term_named(terms, "initial"), kStanding), 1e-12);
  EXPECT_LT(max_residual(problem, term_named(terms, "initial_velocity"), kStanding), 1e-12);
  EXPECT_TRUE(problem.has_exact());
  Random rng(3);
  const Eigen::MatrixXd x = problem.domain().sample_interior(rng, 50);
  const Eigen::MatrixXd e = problem.exact(x);
  for (Eigen::Index n = 0; n < x.rows(); ++n) EXPECT_NEAR(e(n, 0), kStanding.value(x.row(n).transpose()), 1e-12);
}

TEST(Wave, InitialVelocityResidual) {
  // u = sin(πx) (cos 2πt + sin 2πt), c = 2: u_t(x, 0) = 2π sin(πx).
  const Analytic u = mode_1d(1.0, 1.0, 2 * kPi) + Analytic{
      [](const Eigen::VectorXd& p) { return std::sin(kPi * p(0)) * std::sin(2 * kPi * p(1)); },
      [](const Eigen::VectorXd& p) {
        Eigen::VectorXd g(2);
        g << kPi * std::cos(kPi * p(0)) * std::sin(2 * kPi * p(1)),
            2 * kPi * std::sin(kPi * p(0)) * std::cos(2 * kPi * p(1));
        return g;
      },
      [](const Eigen::VectorXd& p) {
        const double sx = std::sin(kPi * p(0)), cx = std::cos(kPi * p(0));
        const double st = std::sin(2 * kPi * p(1)), ct = std::cos(2 * kPi * p(1));
        Eigen::MatrixXd h(2, 2);
        h << -kPi * kPi * sx * st, 2 * kPi * kPi * cx * ct, 2 * kPi * kPi * cx * ct,
            -4 * kPi * kPi * sx * st;
        return h;
      }};
  const RunSetup setup = load_run(write_config("velocity", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation: {speed: 2}
conditions:
  - {on: boundary, type: dirichlet, value: "0"}
  - {on: initial, type: value, value: "sin(pi*x)"}
  - {on: initial, type: velocity, value: "2*pi*sin(pi*x)"}
)yaml"), {});
  const auto terms = setup.problem->loss_terms();
  const LossTerm& velocity = term_named(terms, "initial_velocity");
  EXPECT_EQ(velocity.batch_key, "initial");
  EXPECT_LT(max_residual(*setup.problem, velocity, u), 1e-12);
  EXPECT_LT(max_residual(*setup.problem, term_named(terms, "initial"), u), 1e-12);
  EXPECT_LT(max_residual(*setup.problem, terms[0], u), 1e-9 * max_utt(*setup.problem, u));
  // The standing wave starts at rest: its velocity residual is the whole 2π sin(πx).
  EXPECT_GT(max_residual(*setup.problem, velocity, mode_1d(1.0, 1.0, 2 * kPi)), 0.9 * 2 * kPi);
}

TEST(Wave, VaryingSpeedUsesTwoStreams) {
  // c(x) = 1 + x, u = sin(πx) cos t: f = u_tt − c²u_xx = (−1 + (1 + x)²π²) sin(πx) cos t.
  const RunSetup setup = load_run(write_config("varying", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 2]}
equation:
  speed: "1 + x"
  source: "(-1 + (1 + x)^2*pi^2)*sin(pi*x)*cos(t)"
)yaml"), {});
  const auto terms = setup.problem->loss_terms();
  EXPECT_EQ(terms[0].spec.operators.size(), 2u);
  const Analytic u = mode_1d(1.0, 1.0, 1.0);
  const double scale = 4 * kPi * kPi;
  EXPECT_LT(max_residual(*setup.problem, terms[0], u), 1e-9 * scale);
  // The same u with c = 1 everywhere would leave (2x + x²)π² sin(πx) cos t.
  const RunSetup wrong = load_run(write_config("varying_wrong", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 2]}
equation:
  speed: 1
  source: "(-1 + (1 + x)^2*pi^2)*sin(pi*x)*cos(t)"
)yaml"), {});
  EXPECT_GT(max_residual(*wrong.problem, wrong.problem->loss_terms()[0], u), 1.0);
}

TEST(Wave, TwoDimensionalResidualVanishes) {
  // u = sin(πx) sin(πy) cos(√2 π t), c = 1.
  const RunSetup setup = load_run(write_config("mode2d", R"yaml(
problem: wave
domain: {lower: [0, 0], upper: [1, 1], time: [0, 0.5]}
equation: {speed: 1}
conditions:
  - {on: boundary, type: dirichlet, value: "0"}
)yaml"), {});
  const auto terms = setup.problem->loss_terms();
  ASSERT_EQ(setup.problem->domain().input_dim(), 3);
  const double scale = 2 * kPi * kPi;
  EXPECT_LT(max_residual(*setup.problem, terms[0], mode_2d(std::sqrt(2.0) * kPi)), 1e-9 * scale);
  EXPECT_GT(max_residual(*setup.problem, terms[0], mode_2d(kPi)), 0.1 * scale);
  EXPECT_LT(max_residual(*setup.problem, term_named(terms, "dirichlet"), mode_2d(kPi)), 1e-12);
}

TEST(Wave, ConfigErrors) {
  EXPECT_THROW(load_run(write_config("no_time", R"yaml(
problem: wave
domain: {lower: [0], upper: [1]}
equation: {speed: 1}
)yaml"), {}),
               io::ConfigError);
  EXPECT_THROW(load_run(write_config("bad_speed", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation: {speed: -1}
)yaml"), {}),
               io::ConfigError);
  EXPECT_THROW(load_run(write_config("unknown_key", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 1]}
equation: {speed: 1, sourse: "0"}
)yaml"), {}),
               io::ConfigError);
}

// A tiny training run: the first standing mode u = sin(πx) cos(2πt), c = 2, over half a
// period. Bound: rel_l2 < 5e-2 on a 64 × 9 grid (seeds 0–3 give 0.7–1.7e-2; about 2 s of CPU).
TEST(Wave, TinyTrainingLearnsStandingWave) {
  RunSetup setup = load_run(write_config("tiny", R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 0.5]}
equation:
  speed: 2
  exact: "sin(pi*x)*cos(2*pi*t)"
conditions:
  - {on: boundary, type: dirichlet, value: "0", weight: 100}
  - {on: initial, type: value, value: "sin(pi*x)", weight: 100}
  - {on: initial, type: velocity, value: "0", weight: 100}
field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}
training:
  seed: 1
  batch: {interior: 128, boundary: 32, initial: 32}
  stages:
    - {optimizer: adam, steps: 100, lr: 1.0e-2, schedule: cosine, lr_final: 1.0e-4}
    - {optimizer: lbfgs, steps: 200, memory: 50}
)yaml"), {});
  const auto started = std::chrono::steady_clock::now();
  fields::Field<float> field(setup.field);
  Trainer<float> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  Eigen::MatrixXd x(64 * 9, 2);
  for (int k = 0; k < 9; ++k)
    for (int i = 0; i < 64; ++i) x.row(k * 64 + i) << i / 63.0, 0.5 * k / 8.0;
  const Eigen::MatrixXd u = field.values(x.cast<float>()).cast<double>();
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  const double rel_l2 = (u - exact).norm() / exact.norm();
  std::printf("tiny wave run: rel_l2 %.3e in %.1f s\n", rel_l2, wall);
  EXPECT_LT(rel_l2, 5e-2);
}

// `equation.reference`: the finite-difference reference replaces `exact` in the metrics, frame
// by frame. It matches the standing mode it should reproduce, and a tiny run's errors per
// frame land in metrics.json and in the field data of each frame's .vti.
constexpr const char* kReferenceRun = R"yaml(
problem: wave
domain: {lower: [0], upper: [1], time: [0, 0.5]}
equation:
  speed: 2
  reference: {cells: 1024}
conditions:
  - {on: boundary, type: dirichlet, value: "0", weight: 100}
  - {on: initial, type: value, value: "sin(pi*x)", weight: 100}
  - {on: initial, type: velocity, value: "0", weight: 100}
field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}
training:
  seed: 1
  batch: {interior: 128, boundary: 32, initial: 32}
  stages:
    - {optimizer: adam, steps: 100, lr: 1.0e-2, schedule: cosine, lr_final: 1.0e-4}
    - {optimizer: lbfgs, steps: 200, memory: 50}
output: {grid: [64], frames: 5, png: false}
)yaml";

TEST(Wave, ReferenceGivesErrorsPerFrame) {
  const std::filesystem::path out = testutil::scratch_dir("wave") / "reference_out";
  std::filesystem::remove_all(out);
  RunSetup setup = load_run(write_config("reference", kReferenceRun), {}, out);
  ASSERT_TRUE(setup.problem->has_exact());
  Eigen::MatrixXd x(50 * 7, 2);
  for (int k = 0; k < 7; ++k)
    for (int i = 0; i < 50; ++i) x.row(k * 50 + i) << (i + 0.3) / 50.0, 0.5 * (k + 0.1) / 7.0;
  Eigen::VectorXd mode(x.rows());
  for (Eigen::Index r = 0; r < x.rows(); ++r) mode(r) = std::sin(kPi * x(r, 0)) * std::cos(2 * kPi * x(r, 1));
  EXPECT_LT((setup.problem->exact(x).col(0) - mode).cwiseAbs().maxCoeff(), 1e-4);

  ASSERT_EQ(execute_run(setup), 0);
  std::ifstream file(out / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(file);
  const auto frames = metrics["frame_rel_l2"].get<std::vector<double>>();
  const auto times = metrics["frame_times"].get<std::vector<double>>();
  ASSERT_EQ(frames.size(), 5u);
  ASSERT_EQ(times.size(), 5u);
  EXPECT_DOUBLE_EQ(times[4], 0.5);
  EXPECT_DOUBLE_EQ(metrics["max_frame_rel_l2"].get<double>(), *std::max_element(frames.begin(), frames.end()));
  EXPECT_LT(metrics["rel_l2"].get<double>(), 5e-2);
  for (int k = 0; k < 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.vti", k);
    const io::ImageData image = io::read_vti(out / name);
    ASSERT_EQ(image.field_data.count("rel_l2"), 1u) << name;
    EXPECT_DOUBLE_EQ(image.field_data.at("rel_l2"), frames[k]) << name;
  }
  std::filesystem::remove_all(out);
}

TEST(Wave, ReferenceConfigErrors) {
  const std::string base = kReferenceRun;
  const auto rejects = [&](const std::string& name, const std::string& from, const std::string& to,
                           const std::string& message) {
    std::string text = base;
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    try {
      load_run(write_config(name, text), {});
      ADD_FAILURE() << name << ": expected a ConfigError";
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << name << ": " << e.what();
    }
  };
  rejects("both", "reference: {cells: 1024}", "reference: finite_difference\n  exact: \"0\"", "not both");
  rejects("method", "reference: {cells: 1024}", "reference: spectral", "reference");
  rejects("cells", "cells: 1024", "cells: 2", "cells");
  rejects("cfl", "cells: 1024", "cfl: 1.5", "cfl");
  rejects("key", "cells: 1024", "cels: 1024", "cels");
  rejects("face", "on: boundary, type: dirichlet", "on: x_min, type: dirichlet", "x_max has none");
  rejects("velocity", "  - {on: initial, type: velocity, value: \"0\", weight: 100}\n", "", "initial velocity");
  rejects("twice", "  - {on: initial, type: velocity",
          "  - {on: x_max, type: neumann, value: \"0\"}\n  - {on: initial, type: velocity", "x_max has a condition");
}

}  // namespace
}  // namespace nfield::solvers
