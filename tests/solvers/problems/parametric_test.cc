// SPDX-License-Identifier: MIT
//
// Parametric fields (issue 28, item 4; solvers/core/domain.h, parameters): a constant given as a
// range is one more input column that every sampler draws from its range, that expressions
// read by name, that the derivative streams leave passive (a residual equals the fixed-constant
// problem's at the same value to rounding), whose held-out values each get their own reference
// and grid errors, and whose config errors are located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "fields/field.h"
#include "solvers/core/domain.h"
#include "solvers/output/grid_output.h"
#include "solvers/problems/burgers_reference.h"
#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = testutil::test_folder("parametric_test");
  const std::filesystem::path path = dir / (name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

const char* kBurgers = R"yaml(problem: pde
domain: {lower: [-1], upper: [1], time: [0, 1]}
constants:
  nu: {range: [0.005, 0.05], sampling: log}
equation:
  residuals: ["u_t + u*u_x - nu*u_xx"]
reference:
  solution: burgers_sine
  nu: nu
  held_out: {nu: [0.006, 0.01, 0.04]}
)yaml";

// Every sampler fills the parameter column from its range; the coordinates keep their rules.
TEST(Parametric, SamplersDrawTheParameterColumn) {
  for (const bool log : {false, true}) {
    Domain domain({-1.0}, {1.0}, std::pair{0.0, 1.0});
    domain.add_parameter({"nu", 0.005, 0.05, log});
    ASSERT_EQ(domain.input_dim(), 3);
    ASSERT_EQ(domain.coordinate_dim(), 2);
    EXPECT_EQ(domain.input_names(), (std::vector<std::string>{"x", "t", "nu"}));
    Random rng(7);
    const Eigen::Index n = 4000;
    const Eigen::MatrixXd interior = domain.sample_interior(rng, n);
    const Eigen::MatrixXd faces = domain.sample_faces(domain.faces(), rng, n);
    const Eigen::MatrixXd initial = domain.sample_initial(rng, n);
    EXPECT_TRUE((faces.col(0).array().abs() == 1).all());
    EXPECT_TRUE((initial.col(1).array() == 0).all());
    const double middle = log ? std::sqrt(0.005 * 0.05) : 0.0275;
    EXPECT_DOUBLE_EQ(domain.parameter_middles()(0), middle);
    for (const Eigen::MatrixXd* x : {&interior, &faces, &initial}) {
      ASSERT_EQ(x->cols(), 3);
      EXPECT_GE(x->col(2).minCoeff(), 0.005);
      EXPECT_LE(x->col(2).maxCoeff(), 0.05);
      // Half the points below the middle of the range (the geometric one for log).
      const double below = (x->col(2).array() < middle).cast<double>().mean();
      EXPECT_NEAR(below, 0.5, 0.03) << (log ? "log" : "uniform");
    }
  }
  Domain domain({0.0}, {1.0});
  EXPECT_THROW(domain.add_parameter({"nu", 0.05, 0.005, false}), std::invalid_argument);
  EXPECT_THROW(domain.add_parameter({"nu", 0.0, 1.0, true}), std::invalid_argument);
  EXPECT_THROW(domain.add_parameter({"x", 0.0, 1.0, false}), std::invalid_argument);
}

// The residual of the parametric problem at (x, t, ν) equals the fixed-ν problem's at (x, t)
// for the same field: the ν column is passive (no tangent along it) and `nu` reads it.
TEST(Parametric, PassiveColumnGivesTheFixedResidual) {
  const RunSetup parametric = load_run(write_config("passive", kBurgers), {});
  const std::string fixed_text = replaced(
      replaced(kBurgers, "nu: {range: [0.005, 0.05], sampling: log}", "nu: 0.0123"),
      "  held_out: {nu: [0.006, 0.01, 0.04]}\n", "");
  const RunSetup fixed = load_run(write_config("fixed", fixed_text), {});
  const LossTerm p = parametric.problem->loss_terms()[0], f = fixed.problem->loss_terms()[0];
  ASSERT_EQ(p.spec.tangents.rows(), 3);
  ASSERT_EQ(f.spec.tangents.rows(), 2);
  EXPECT_TRUE(p.spec.tangents.row(2).isZero()) << "a tangent along the ν column";
  EXPECT_EQ(p.spec.tangents.topRows(2), f.spec.tangents);

  // A field of (x, t, ν); the fixed problem sees it at ν = 0.0123 through the same layout.
  fields::FieldOptions options;
  options.input_dim = 3;
  options.output_dim = 1;
  options.hidden = {16, 16};
  options.seed = 5;
  const fields::Field<double> field(options);
  Random rng(3);
  const Eigen::MatrixXd xt = fixed.problem->domain().sample_interior(rng, 64);
  Eigen::MatrixXd x(xt.rows(), 3);
  x << xt, Eigen::VectorXd::Constant(xt.rows(), 0.0123);
  const autodiff::StreamLayout layout(p.spec);
  autodiff::Streams<double> streams;
  field.evaluate(layout, x, streams);
  Eigen::MatrixXd rp, rf;
  p.residual(x)->evaluate(0, layout, streams, rp);
  f.residual(xt)->evaluate(0, autodiff::StreamLayout(f.spec), streams, rf);
  ASSERT_EQ(rp.rows(), 64);
  EXPECT_GT(rf.norm(), 1e-3);
  EXPECT_LT((rp - rf).norm(), 1e-14 * rf.norm());

  // The column reaches the expression: r(ν') − r(ν) = −(ν' − ν) u_xx with the streams fixed.
  Eigen::MatrixXd shifted = x, rs;
  shifted.col(2).array() += 0.01;
  p.residual(shifted)->evaluate(0, layout, streams, rs);
  const Eigen::MatrixXd change = rs - rp;
  EXPECT_GT(change.norm(), 1e-6);
  // u_xx from the fixed problem: r = u_t + u u_x − ν u_xx is linear in ν.
  Eigen::MatrixXd r0;
  Eigen::MatrixXd zero_nu = x;
  zero_nu.col(2).setZero();
  p.residual(zero_nu)->evaluate(0, layout, streams, r0);
  const Eigen::MatrixXd u_xx = (r0 - rp) / 0.0123;
  EXPECT_LT((change + 0.01 * u_xx).norm(), 1e-10 * change.norm());
}

// Each held-out value is compared with its own Cole–Hopf solution.
TEST(Parametric, HeldOutValuesHaveTheirOwnReference) {
  const RunSetup setup = load_run(write_config("held_out", kBurgers), {});
  const std::vector<Eigen::VectorXd> held = setup.problem->held_out_parameters();
  ASSERT_EQ(held.size(), 3u);
  EXPECT_EQ(held[1](0), 0.01);
  Eigen::MatrixXd x(3, 3);
  x << -0.5, 0.4, 0.006, 0.3, 0.5, 0.01, -0.2, 0.9, 0.04;
  const Eigen::MatrixXd u = setup.problem->exact(x);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    EXPECT_EQ(u(i, 0), burgers_sine_solution(x(i, 0), x(i, 1), {.nu = x(i, 2)}));
  EXPECT_NE(u(0, 0), burgers_sine_solution(-0.5, 0.4, {.nu = 0.01}));

  // A "field" that is the exact solution at ν = 0.01 whatever its ν column: the held-out
  // value 0.01 has no error, the others the distance between two members of the family.
  const Problem& problem = *setup.problem;
  const StreamEvaluator at_001 = [](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& points) {
    Eigen::MatrixXd xt(points.rows(), 2);
    xt << points.col(0), points.col(1);
    autodiff::Streams<double> s;
    s.resize(points.rows(), layout.count(), 1);
    s.data.setZero();
    s.stream(0) = burgers_sine_solution(xt, {.nu = 0.01});
    return s;
  };
  OutputOptions output;
  output.grid = {41};
  output.frames = 3;
  const GridMetrics m = grid_error(problem, at_001, output);
  ASSERT_EQ(m.held_out.size(), 3u);
  EXPECT_EQ(m.held_out[1].parameters, (std::vector<std::pair<std::string, double>>{{"nu", 0.01}}));
  EXPECT_EQ(m.held_out[1].rel_l2, 0.0);
  EXPECT_GT(m.held_out[0].rel_l2, 1e-3);
  EXPECT_GT(m.held_out[2].rel_l2, m.held_out[0].rel_l2);  // 0.04 lies farther from 0.01
  EXPECT_EQ(m.rel_l2, m.held_out[2].rel_l2);              // the worst
  EXPECT_EQ(m.held_out[2].dir, "held_out_nu_0.04");
}

TEST(Parametric, ConfigErrorsAreLocated) {
  using testutil::expect_located_error;
  const std::string range = "nu: {range: [0.005, 0.05], sampling: log}";
  expect_located_error(write_config("reversed", replaced(kBurgers, range, "nu: {range: [0.05, 0.005]}")),
                       {4, 15, "constants.nu.range", "expected [lower, upper] with lower < upper, got [0.05, 0.005]"});
  expect_located_error(write_config("text", replaced(kBurgers, range, "nu: {range: [small, 0.05]}")),
                       {4, 16, "constants.nu.range[0]", "expected a number, got 'small'"});
  expect_located_error(write_config("unknown", replaced(kBurgers, range, "nu: {range: [0.005, 0.05], unknown: true}")),
                       {4, 39, "constants.nu.unknown", "declared as a range (a field input) and as unknown"});
  expect_located_error(write_config("log_zero", replaced(kBurgers, range, "nu: {range: [0, 0.05], sampling: log}")),
                       {4, 36, "constants.nu.sampling", "log sampling needs a range with lower > 0"});
  expect_located_error(write_config("outside", replaced(kBurgers, "0.006, 0.01, 0.04", "0.006, 0.1, 0.04")),
                       {10, 18, "reference.held_out.nu", "held-out value 0.1 lies outside the range"});
  expect_located_error(write_config("not_a_parameter", replaced(kBurgers, "{nu: [0.006", "{mu: [0.006")),
                       {10, 18, "reference.held_out.mu", "'mu' is no parameter (parameters: nu)"});
}

}  // namespace
}  // namespace nfield::solvers
