// SPDX-License-Identifier: MIT
//
// Inverse problems of `problem: pde` (solvers/core/unknowns.h, solvers/problems/pde_data.h): the
// gradient of the loss with respect to unknown constants (free, positive through log, bounded
// through a sigmoid) against central differences, through the trainer's loss (Adam, L-BFGS)
// and through the own Levenberg–Marquardt's Jacobian columns (Jᵀf); a resumed run with
// unknowns ends bit for bit as an uninterrupted one (their values and Adam moments in the
// checkpoint); the synthetic data's noise level; a short identification run whose parameter
// error falls by a stated factor, with its metrics.json and plot; every refused input located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/problems/pde_data.h"
#include "solvers/run/run.h"
#include "solvers/training/lm_terms.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/resume_check.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

// u' = a u on [0, 1] with u = exp(2x) measured: a = 2. Three unknowns, one of each
// parametrisation (b and c enter through (b − 1.5)·c·u, which the data cannot pin; the
// gradient checks do not care).
const char* kConfig = R"yaml(problem: pde
domain: {lower: [0], upper: [1]}
constants:
  a: {unknown: true, initial: 1.0, positive: true, true: 2.0, lr: 2.0e-2}
  b: {unknown: true, initial: 1.2, bounds: [1, 2]}
  c: {unknown: true, initial: 2.0}
equation:
  residuals: ["u_x - a*u + (b - 1.5)*c*u"]
data:
  exact: {u: "exp(2*x)", points: 40, noise: 0.0, seed: 3}
field: {type: mlp, hidden: [12, 12], seed: 1}
training:
  seed: 0
  precision: double
  threads: 1
  batch: {interior: 32}
  stages: [{optimizer: adam, steps: 12, lr: 1.0e-2}]
output: {grid: [9], png: false}
)yaml";

fs::path write_config(const std::string& text, const std::string& name) {
  const fs::path dir = testutil::scratch_dir("inverse") / name;
  fs::create_directories(dir);
  std::ofstream(dir / "config.yaml") << text;
  return dir / "config.yaml";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("no '" + from + "' in the config");
  return text.replace(at, from.size(), to);
}

TEST(InverseGradient, UnknownConstantsMatchCentralDifferences) {
  const RunSetup setup = load_run(write_config(kConfig, "gradient"), {});
  ASSERT_NE(setup.problem->unknowns(), nullptr);
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  const Eigen::Index n = field.network_parameter_count();
  ASSERT_EQ(field.parameter_count(), n + 3);
  Eigen::VectorXd theta = field.parameters(), gradient(theta.size()), scratch(theta.size());
  trainer.loss_and_gradient_at(theta.data(), gradient.data());
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-6;
    Eigen::VectorXd plus = theta, minus = theta;
    plus(n + i) += h;
    minus(n + i) -= h;
    const double fd = (trainer.loss_and_gradient_at(plus.data(), scratch.data()) -
                       trainer.loss_and_gradient_at(minus.data(), scratch.data())) / (2 * h);
    // Rounding of the differences: about ε·L/h ≈ 1e-9.
    EXPECT_NEAR(gradient(n + i), fd, 1e-6 * std::abs(fd) + 1e-8) << "unknown " << i;
    EXPECT_GT(std::abs(fd), 1e-5) << "unknown " << i << ": the check needs a gradient";
  }
}

TEST(InverseGradient, LevenbergMarquardtColumnsMatchCentralDifferences) {
  const RunSetup setup = load_run(write_config(kConfig, "lm"), {});
  fields::Field<double> field(setup.field);
  TrainedUnknowns<double> unknowns(setup.problem->unknowns(), field, 1);
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 2u);  // pde, data
  Random rng(5);
  std::vector<autodiff::StreamLayout> layouts;
  std::vector<autodiff::Matrix<double>> points;
  std::vector<std::unique_ptr<Residual>> residuals;
  for (const LossTerm& t : terms) {
    const TermPoints p = t.sample(rng, 24);
    layouts.emplace_back(t.spec);
    points.push_back(p.x);
    residuals.push_back(t.residual(p));
  }
  std::vector<LeastSquaresTerm<double>> least_squares;
  for (std::size_t k = 0; k < terms.size(); ++k)
    least_squares.push_back({&layouts[k], &points[k], residuals[k].get(), terms[k].weight});
  TermsNormalEquations<double> problem(field, least_squares, world_communicator(), 1, &unknowns);
  const Eigen::VectorXd theta = field.parameters();
  Eigen::MatrixXd jtj;
  Eigen::VectorXd jtf;
  problem.normal_equations(theta, jtj, jtf);
  const Eigen::Index n = field.network_parameter_count();
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-6;
    Eigen::VectorXd plus = theta, minus = theta;
    plus(n + i) += h;
    minus(n + i) -= h;
    // cost = ½‖f‖², so ∂cost/∂ρ = (Jᵀf)_ρ.
    const double fd = (problem.cost(plus) - problem.cost(minus)) / (2 * h);
    EXPECT_NEAR(jtf(n + i), fd, 1e-6 * std::max(1.0, std::abs(fd))) << "unknown " << i;
    EXPECT_GT(jtj(n + i, n + i), 0) << "unknown " << i << ": its Jacobian column is zero";
  }
}

TEST(InverseResume, ResumedRunWithUnknownsIsBitExact) {
  const fs::path path = write_config(kConfig, "resume");
  const RunSetup setup = load_run(path, {});
  ASSERT_NO_FATAL_FAILURE(testutil::expect_resume_is_bit_exact<double>(
      setup, path.parent_path() / "half.h5", 5, [](const testutil::FinishedRuns<double>& runs) {
        // The unknowns moved (a's own lr is 2e-2), and the trajectory came back with the checkpoint.
        const fields::Field<double>& full = runs.whole_field;
        EXPECT_NE(full.parameters()(full.network_parameter_count()), std::log(1.0));
        ASSERT_EQ(runs.resumed.unknowns().trajectory().size(), runs.whole.unknowns().trajectory().size());
        EXPECT_EQ(runs.resumed.unknowns().trajectory().back().values,
                  runs.whole.unknowns().trajectory().back().values);
      }));
}

// Relative Gaussian noise: noisy − clean has standard deviation noise·std(clean). With
// N = 20000 draws the sample standard deviation is within 3/√(2N) ≈ 2.1 % of the true one
// (three standard errors), and the sample mean within 3σ/√N.
TEST(InverseData, SyntheticNoiseHasItsStatedLevel) {
  const Eigen::Index n = 20000;
  Eigen::MatrixXd clean(n, 1);
  for (Eigen::Index i = 0; i < n; ++i) clean(i, 0) = std::sin(0.001 * static_cast<double>(i)) * 3 + 1;
  const double mean = clean.mean();
  const double std = std::sqrt((clean.array() - mean).square().sum() / static_cast<double>(n));
  Random rng(11);
  const Eigen::MatrixXd noisy = PdeData::add_noise(clean, 0.05, rng);
  const Eigen::ArrayXd e = (noisy - clean).col(0).array();
  const double sigma = 0.05 * std;
  const double sample_std = std::sqrt((e - e.mean()).square().sum() / static_cast<double>(n - 1));
  EXPECT_NEAR(sample_std / sigma, 1.0, 3 / std::sqrt(2.0 * static_cast<double>(n)));
  EXPECT_NEAR(e.mean(), 0.0, 3 * sigma / std::sqrt(static_cast<double>(n)));
  Random again(11);
  EXPECT_EQ(PdeData::add_noise(clean, 0.05, again), noisy);  // the seed decides every draw
}

// a from 1 to about 2 in a short run: its relative error falls from 0.5 by at least 20 times;
// metrics.json has the unknown with its truth, error and trajectory, and unknowns.png.
TEST(InverseRun, IdentificationErrorFalls) {
  std::string text = replaced(kConfig, "  b: {unknown: true, initial: 1.2, bounds: [1, 2]}\n  c: {unknown: true, initial: 2.0}\n", "");
  text = replaced(text, " + (b - 1.5)*c*u", "");
  text = replaced(text, "[{optimizer: adam, steps: 12, lr: 1.0e-2}]",
                  "[{optimizer: adam, steps: 300, lr: 1.0e-2}, {optimizer: lbfgs, steps: 100}]");
  const fs::path path = write_config(text, "identify");
  RunSetup setup = load_run(path, {"output.dir=" + (path.parent_path() / "out").string()});
  ASSERT_EQ(execute_run(setup), 0);
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(path.parent_path() / "out" / "metrics.json"));
  ASSERT_TRUE(m.contains("unknowns")) << m.dump();
  const nlohmann::json& a = m["unknowns"]["a"];
  EXPECT_EQ(a["true"], 2.0);
  EXPECT_EQ(a["initial"], 1.0);
  const double error = a["rel_error"];
  EXPECT_LT(error, 0.5 / 20) << "a = " << a["value"];
  EXPECT_NEAR(error, std::abs(a["value"].get<double>() - 2) / 2, 1e-15);
  ASSERT_GE(a["trajectory"].size(), 2u);
  EXPECT_EQ(a["trajectory"][0][0], 1);
  EXPECT_TRUE(fs::exists(path.parent_path() / "out" / "unknowns.png"));
}

TEST(InverseInput, RefusedInputsAreLocated) {
  using testutil::expect_located_error;
  const fs::path dir = testutil::scratch_dir("inverse") / "refused";
  fs::create_directories(dir);
  std::ofstream(dir / "outside.csv") << "x,u\n0.5,1\n1.5,2\n";
  std::ofstream(dir / "no_u.csv") << "x,v\n0.5,1\n";
  std::ofstream(dir / "text.csv") << "x,u\n0.5,one\n";
  const auto config = [&](const std::string& name, const std::string& from, const std::string& to) {
    const fs::path path = dir / (name + ".yaml");
    std::ofstream(path) << replaced(kConfig, from, to);
    return path;
  };
  const std::string exact = "  exact: {u: \"exp(2*x)\", points: 40, noise: 0.0, seed: 3}";
  expect_located_error(config("outside", exact, "  file: outside.csv"),
                       {10, 9, "data.file", "outside.csv:3: the point (x) = (1.5) lies outside the box"});
  expect_located_error(config("no_column", exact, "  file: no_u.csv"), {10, 9, "data.file", "no column 'u'"});
  expect_located_error(config("text", exact, "  file: text.csv"), {10, 9, "data.file", "text.csv:2"});
  expect_located_error(config("truth_known", "c: {unknown: true, initial: 2.0}", "c: {unknown: false, true: 2.0}"),
                       {6, 29, "constants.c.true", "'c' is known"});
  expect_located_error(config("bounds", "bounds: [1, 2]", "bounds: [2, 1]"),
                       {5, 44, "constants.b.bounds", "lower < upper"});
  expect_located_error(config("outside_bounds", "initial: 1.2, bounds", "initial: 2.5, bounds"),
                       {5, 31, "constants.b.initial", "strictly inside bounds [1, 2]"});
  expect_located_error(config("not_positive", "initial: 1.0, positive", "initial: 0.0, positive"),
                       {4, 31, "constants.a.initial", "> 0 (positive: true)"});
  expect_located_error(config("both_weights", "seed: 3}", "seed: 3}\n  weight: 2\n  sigma: 0.1"),
                       {12, 10, "data.sigma", "weight or sigma, not both"});
}

// An unknown constant no residual reads: a warning on stderr, not an error.
TEST(InverseInput, UnusedUnknownIsAWarning) {
  const fs::path path = write_config(replaced(kConfig, "c: {unknown: true, initial: 2.0}",
                                              "c: {unknown: true, initial: 2.0}\n  d: {unknown: true, initial: 1}"),
                                     "unused");
  ::testing::internal::CaptureStderr();
  const RunSetup setup = load_run(path, {});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("warning: unknown constant 'd' is read by no residual"), std::string::npos) << err;
  EXPECT_NE(err.find("config.yaml:7:"), std::string::npos) << err;
  EXPECT_EQ(setup.problem->unknowns()->count(), 4);
}

}  // namespace
}  // namespace nfield::solvers
