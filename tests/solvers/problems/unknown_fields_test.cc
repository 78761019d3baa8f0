// SPDX-License-Identifier: MIT
//
// Unknown fields of `problem: pde` (`unknown_fields:`, solvers/problems/pde.cc): an extra
// output of the field that residuals read with its derivatives. The loss gradient with
// respect to the parameters that feed it (and the rest) against central differences, through
// the trainer's loss and through the own Levenberg–Marquardt's Jᵀf; a resumed run ends bit for
// bit as an uninterrupted one; a short identification run lowers its error by a stated factor
// and writes it beside u (grid arrays, rel_l2_a); every refused input located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "solvers/run/run.h"
#include "solvers/training/lm_terms.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/resume_check.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

// (u_x − a u)_x = 0 on [0, 1] with u = exp(x²) measured and a known at x = 0: a = 2x.
const char* kConfig = R"yaml(problem: pde
domain: {lower: [0], upper: [1]}
unknown_fields:
  a: {true: "2*x"}
equation:
  residuals: ["u_xx - a*u_x - a_x*u", "u_x - a*u"]
conditions:
  - {on: [x_min], type: dirichlet, value: {a: "0"}}
reference:
  exact: "exp(x^2)"
data:
  exact: {u: reference, points: 40, seed: 3}
field: {type: mlp, hidden: [12, 12], seed: 1}
training:
  seed: 0
  precision: double
  threads: 1
  batch: {interior: 32, boundary: 4}
  stages: [{optimizer: adam, steps: 12, lr: 1.0e-2}]
output: {grid: [33], png: false}
)yaml";

fs::path write_config(const std::string& text, const std::string& name) {
  const fs::path dir = testutil::scratch_dir("unknown_fields") / name;
  fs::create_directories(dir);
  std::ofstream(dir / "config.yaml") << text;
  return dir / "config.yaml";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("no '" + from + "' in the config");
  return text.replace(at, from.size(), to);
}

// The network's last parameters: the output layer (weights, then biases, or interleaved: the
// check takes the last 26 = 2 × 12 weights + 2 biases, which include every parameter that feeds
// a alone), and a spread of the hidden ones.
std::vector<Eigen::Index> checked_parameters(Eigen::Index n) {
  std::vector<Eigen::Index> which;
  for (Eigen::Index i = n - 26; i < n; ++i) which.push_back(i);
  for (Eigen::Index i = 0; i < n - 26; i += 17) which.push_back(i);
  return which;
}

TEST(UnknownFields, AreOutputsAfterTheOutputs) {
  const RunSetup setup = load_run(write_config(kConfig, "outputs"), {});
  EXPECT_EQ(setup.problem->output_names(), (std::vector<std::string>{"u", "a"}));
  EXPECT_EQ(setup.problem->unknowns(), nullptr);  // no unknown constants
  ASSERT_TRUE(setup.problem->has_exact());
  Eigen::MatrixXd x(2, 1);
  x << 0.25, 0.5;
  const Eigen::MatrixXd exact = setup.problem->exact(x);
  ASSERT_EQ(exact.cols(), 2);
  EXPECT_DOUBLE_EQ(exact(0, 0), std::exp(0.0625));
  EXPECT_DOUBLE_EQ(exact(1, 1), 1.0);
}

TEST(UnknownFields, GradientMatchesCentralDifferences) {
  const RunSetup setup = load_run(write_config(kConfig, "gradient"), {});
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  Eigen::VectorXd theta = field.parameters(), gradient(theta.size()), scratch(theta.size());
  trainer.loss_and_gradient_at(theta.data(), gradient.data());
  int nonzero = 0;
  for (const Eigen::Index i : checked_parameters(theta.size())) {
    const double h = 1e-6;
    Eigen::VectorXd plus = theta, minus = theta;
    plus(i) += h;
    minus(i) -= h;
    const double fd = (trainer.loss_and_gradient_at(plus.data(), scratch.data()) -
                       trainer.loss_and_gradient_at(minus.data(), scratch.data())) / (2 * h);
    // Rounding of the differences: about ε·L/h ≈ 1e-9.
    EXPECT_NEAR(gradient(i), fd, 1e-6 * std::abs(fd) + 1e-8) << "parameter " << i;
    nonzero += std::abs(fd) > 1e-5 ? 1 : 0;
  }
  EXPECT_GT(nonzero, 20) << "the check needs gradients";
}

TEST(UnknownFields, LevenbergMarquardtMatchesCentralDifferences) {
  const RunSetup setup = load_run(write_config(kConfig, "lm"), {});
  fields::Field<double> field(setup.field);
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 4u);  // pde, pde_1, dirichlet, data
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
  TermsNormalEquations<double> problem(field, least_squares, world_communicator(), 1);
  const Eigen::VectorXd theta = field.parameters();
  Eigen::MatrixXd jtj;
  Eigen::VectorXd jtf;
  problem.normal_equations(theta, jtj, jtf);
  for (const Eigen::Index i : checked_parameters(theta.size())) {
    const double h = 1e-6;
    Eigen::VectorXd plus = theta, minus = theta;
    plus(i) += h;
    minus(i) -= h;
    // cost = ½‖f‖², so ∂cost/∂θ = (Jᵀf)_θ.
    const double fd = (problem.cost(plus) - problem.cost(minus)) / (2 * h);
    EXPECT_NEAR(jtf(i), fd, 1e-6 * std::max(1.0, std::abs(fd))) << "parameter " << i;
  }
}

TEST(UnknownFields, ResumedRunIsBitExact) {
  const fs::path path = write_config(kConfig, "resume");
  const RunSetup setup = load_run(path, {});
  ASSERT_NO_FATAL_FAILURE(testutil::expect_resume_is_bit_exact<double>(setup, path.parent_path() / "half.h5", 5));
}

// rel_l2 of a over the output grid, from the untrained field and after Adam and LM: it falls
// by at least 20 times (measured 2026-11-26: 1.01 → 1.27e-2, 79 times); the grid files carry a,
// exact_a and error_a, metrics.json rel_l2_a.
TEST(UnknownFields, IdentificationErrorFalls) {
  const std::string text = replaced(kConfig, "[{optimizer: adam, steps: 12, lr: 1.0e-2}]",
                                    "[{optimizer: adam, steps: 300, lr: 1.0e-2}, {optimizer: lm, steps: 150}]");
  const fs::path path = write_config(text, "identify");
  RunSetup setup = load_run(path, {"output.dir=" + (path.parent_path() / "out").string()});
  Eigen::MatrixXd x(33, 1);
  for (Eigen::Index i = 0; i < 33; ++i) x(i, 0) = static_cast<double>(i) / 32;
  const Eigen::VectorXd a_true = setup.problem->exact(x).col(1);
  const fields::Field<double> untrained(setup.field);
  const double before = (untrained.values(x).col(1) - a_true).norm() / a_true.norm();
  ASSERT_EQ(execute_run(setup), 0);
  const fs::path out = path.parent_path() / "out";
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(out / "metrics.json"));
  ASSERT_TRUE(m.contains("rel_l2_a")) << m.dump();
  const double after = m["rel_l2_a"];
  std::printf("rel_l2 of a: %.3e untrained, %.3e trained (%.0f times lower)\n", before, after, before / after);
  EXPECT_LT(after, before / 20);
  EXPECT_LT(m["rel_l2_u"].get<double>(), 1e-2);
  std::ifstream vti(out / "solution.vti");
  const std::string grid((std::istreambuf_iterator<char>(vti)), std::istreambuf_iterator<char>());
  for (const char* name : {"Name=\"a\"", "Name=\"exact_a\"", "Name=\"error_a\""})
    EXPECT_NE(grid.find(name), std::string::npos) << name;
}

TEST(UnknownFields, RefusedInputsAreLocated) {
  using testutil::expect_located_error;
  const fs::path dir = testutil::scratch_dir("unknown_fields") / "refused";
  fs::create_directories(dir);
  const auto config = [&](const std::string& name, const std::string& from, const std::string& to) {
    const fs::path path = dir / (name + ".yaml");
    std::ofstream(path) << replaced(kConfig, from, to);
    return path;
  };
  const std::string field = "  a: {true: \"2*x\"}";
  // Keys of a network of its own without `hidden` (tests/solvers/problems/unknown_field_networks_test.cc).
  expect_located_error(config("inputs", field, "  a: {true: \"2*x\", inputs: [x]}"),
                       {4, 28, "unknown_fields.a.inputs", "needs a network of its own"});
  expect_located_error(config("positive", field, "  a: {positive: true}"),
                       {4, 17, "unknown_fields.a.positive", "needs a network of its own"});
  expect_located_error(config("key", field, "  a: {true: \"2*x\", lr: 0.1}"),
                       {4, 20, "unknown_fields.a.lr", "lr"});
  expect_located_error(config("taken", field, "  u: {}"), {4, 6, "unknown_fields.u", "is an output already"});
  expect_located_error(config("reserved", field, "  x: {}"), {4, 6, "unknown_fields.x", "is taken"});
  expect_located_error(config("underscore", field, "  a_b: {}"), {4, 8, "unknown_fields.a_b", "letters and digits"});
  expect_located_error(config("truth_syntax", "2*x", "2*q"), {4, 16, "unknown_fields.a.true", "unknown symbol 'q'"});
  expect_located_error(config("no_reference", "reference:\n  exact: \"exp(x^2)\"\n", ""),
                       {4, 13, "unknown_fields.a.true", "needs reference.exact"});
  expect_located_error(config("one_truth", field, field + "\n  b: {}"),
                       {5, 6, "unknown_fields.b", "give every unknown field its truth"});
  expect_located_error(config("hard", "type: dirichlet, value: {a: \"0\"}",
                              "type: dirichlet, value: {a: \"0\", u: \"1\"}, enforce: hard"),
                       {4, 3, "unknown_fields", "soft conditions only"});
  expect_located_error(config("empty", field, "  {}"), {4, 3, "unknown_fields", "expected a mapping of field names"});
}

// A field no residual reads: a warning on stderr, not an error.
TEST(UnknownFields, UnreadFieldIsAWarning) {
  const std::string text = replaced(replaced(kConfig, "  a: {true: \"2*x\"}", "  a: {true: \"2*x\"}\n  b: {true: \"1\"}"),
                                    "u: reference,", "u: reference,");
  const fs::path path = write_config(text, "unread");
  ::testing::internal::CaptureStderr();
  const RunSetup setup = load_run(path, {});
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("warning: unknown field 'b' is read by no residual"), std::string::npos) << err;
  EXPECT_NE(err.find("config.yaml:5:"), std::string::npos) << err;
  EXPECT_EQ(setup.problem->output_dim(), 3);
}

}  // namespace
}  // namespace nfield::solvers
