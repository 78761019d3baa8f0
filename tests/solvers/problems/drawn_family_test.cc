// SPDX-License-Identifier: MIT
//
// Families of PDE instances drawn from ranges (solvers/problems/drawn_family.h): the draws lie
// in their ranges, follow the seed and reach each instance's own problem (a point source at
// each drawn place); a short meta-learning run over the family scores its held-out instances
// by their grid rel_l2 (lower is better) and writes their grid files, and so does a latent-code
// run with its held-out code fits; every key's errors are located.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/expression.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/problems/drawn_family.h"
#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

// Line 6 is family.draw's source_center, 7 its instances.
const char* kDraw = "source_center: {range: [[-0.3, -0.2], [0.3, 0.2]]}";

std::string family_config(const std::string& draw = kDraw, const std::string& training = "") {
  return "problem: helmholtz\n"
         "domain: {lower: [-1, -1], upper: [1, 1]}\n"
         "equation:\n"
         "  wavenumber: 4\n"
         "  family:\n"
         "    draw: {" + draw + "}\n"
         "    instances: 5\n"
         "    held_out: 2\n"
         "    seed: 3\n"
         "  complex: true\n"
         "  source_width: 0.1\n"
         "  pml_width: 0.4\n"
         "conditions: [{on: boundary, type: dirichlet, value: \"0\"}]\n"
         "field: {type: siren, hidden: [16, 16], first_omega: 5, hidden_omega: 1}\n"
         "training:\n"
         "  threads: 1\n"
         "  batch: {interior: 256, boundary: 64, source: 64}\n" + training +
         "output: {grid: [24, 24]}\n";
}

const char* kMeta = "  meta: {algorithm: reptile, steps: 2}\n";

TEST(DrawnFamily, DrawsLieInTheirRangesAndReachEachInstance) {
  const RunSetup setup = load_run(testutil::write_config("drawn_family", family_config(kDraw, kMeta)), {});
  const auto training = instances(*setup.problem, false), held_out = instances(*setup.problem, true);
  ASSERT_EQ(training.size(), 5U);
  ASSERT_EQ(held_out.size(), 2U);
  EXPECT_EQ(training[3].name, "instance_003");
  EXPECT_EQ(held_out[1].name, "held_out_001");
  // The free-space solution moves with its source: instance k's exact solution at x₀ₖ + d is
  // instance 0's at x₀₀ + d, and differs from it at the same point.
  const auto source = [](const ProblemInstance& instance) {
    return Eigen::RowVector2d(instance.values[0].second, instance.values[1].second);
  };
  const Eigen::RowVector2d d(0.15, -0.1);
  const Eigen::MatrixXd first = training[0].problem->exact(Eigen::MatrixXd(source(training[0]) + d));
  for (const auto* list : {&training, &held_out})
    for (const ProblemInstance& instance : *list) {
      ASSERT_EQ(instance.values.size(), 2U);
      EXPECT_EQ(instance.values[0].first, "source_center_0");
      const Eigen::RowVector2d x0 = source(instance);
      EXPECT_TRUE(x0(0) >= -0.3 && x0(0) <= 0.3 && x0(1) >= -0.2 && x0(1) <= 0.2) << instance.name << ": " << x0;
      const Eigen::MatrixXd moved = instance.problem->exact(Eigen::MatrixXd(x0 + d));
      EXPECT_LT((moved - first).norm(), 1e-9 * first.norm()) << instance.name;
      if (&instance != &training[0]) {
        const Eigen::MatrixXd fixed = instance.problem->exact(Eigen::MatrixXd(source(training[0]) + d));
        EXPECT_GT((fixed - first).norm(), 1e-3 * first.norm()) << instance.name;
      }
    }
  EXPECT_NE(training[0].values[0].second, training[1].values[0].second);
  // The same seed, the same instances.
  const RunSetup again = load_run(testutil::write_config("drawn_family_again", family_config(kDraw, kMeta)), {});
  EXPECT_EQ(instances(*again.problem, true)[1].values, held_out[1].values);
}

// With `frame: source` every instance is posed about its own source: its box is the
// config's moved by −x₀ₖ, and the free-space solution is one function of x′ = x − x₀ₖ.
TEST(DrawnFamily, SourceFrameGivesEveryInstanceTheSameFreeSpaceField) {
  std::string config = family_config(kDraw, kMeta);
  config.replace(config.find("  complex: true\n"), 0, "  frame: source\n");
  const RunSetup setup = load_run(testutil::write_config("drawn_family_frame", config), {});
  const Eigen::MatrixXd x = 0.5 * Eigen::MatrixXd::Random(20, 2);
  const auto training = instances(*setup.problem, false);
  ASSERT_EQ(training.size(), 5U);
  const Eigen::MatrixXd first = training[0].problem->exact(x);
  for (const ProblemInstance& instance : training) {
    const double x0 = instance.values[0].second, y0 = instance.values[1].second;
    EXPECT_EQ(instance.problem->domain().lower(), (std::vector<double>{-1 - x0, -1 - y0})) << instance.name;
    EXPECT_EQ(instance.problem->domain().upper(), (std::vector<double>{1 - x0, 1 - y0})) << instance.name;
    EXPECT_LT((instance.problem->exact(x) - first).norm(), 1e-12 * first.norm()) << instance.name;
  }
}

TEST(DrawnFamily, MetaRunScoresHeldOutInstancesByTheirGridError) {
  const fs::path dir = testutil::scratch_dir("drawn_family_meta");
  const std::string training =
      "  meta: {algorithm: reptile, steps: 4, tasks_per_step: 2, inner_steps: 2, inner_optimizer: adam, inner_lr: 1.0e-2, "
      "curve_steps: 6}\n"
      "  stages: [{optimizer: adam, steps: 8, lr: 1.0e-2}]\n";
  std::string text = family_config(kDraw, training);
  text.replace(text.find("output: {"), 9, "output: {dir: " + (dir / "run").string() + ", ");
  RunSetup setup = load_run(testutil::write_config("drawn_family_meta", text), {});
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "run/metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["held_out_figure"], "rel_l2");
  ASSERT_EQ(metrics["held_out"].size(), 2U);
  for (const auto& h : metrics["held_out"]) {
    EXPECT_TRUE(h.contains("source_center_1")) << h.dump();
    EXPECT_TRUE(h.contains("meta_steps_to_standard_final")) << h.dump();
    EXPECT_GT(h["standard_final"].get<double>(), 0.0);
  }
  EXPECT_TRUE(fs::exists(dir / "run/held_out/held_out_000/meta_0/solution.vti"));
  EXPECT_TRUE(fs::exists(dir / "run/held_out/held_out_001/standard_6/solution.vti"));  // at curve_steps
}

TEST(DrawnFamily, LatentRunFitsHeldOutCodesAndReportsTheirGridError) {
  const fs::path dir = testutil::scratch_dir("drawn_family_latent");
  const std::string training =
      "  auto_decoder: {instances_per_step: 2, fit_steps: 4, interpolation_steps: 2}\n"
      "  stages: [{optimizer: adam, steps: 6, lr: 1.0e-2}]\n";
  std::string text = family_config(kDraw, training);
  text.replace(text.find("first_omega: 5"), 14, "first_omega: 5, latent: {size: 2}");
  text.replace(text.find("output: {"), 9, "output: {dir: " + (dir / "run").string() + ", ");
  RunSetup setup = load_run(testutil::write_config("drawn_family_latent", text), {});
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "run/metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  ASSERT_EQ(metrics["held_out"].size(), 2U);
  ASSERT_EQ(metrics["training"].size(), 5U);
  for (const auto& h : metrics["held_out"]) {
    EXPECT_TRUE(h.contains("source_center_0")) << h.dump();
    EXPECT_GT(h["rel_l2"].get<double>(), 0.0) << h.dump();
    EXPECT_EQ(h["rel_l2_zero_code"].is_number(), true) << h.dump();
  }
  EXPECT_TRUE(metrics["held_out_summary"].contains("rel_l2"));
  EXPECT_TRUE(fs::exists(dir / "run/training/instance_004/solution.vti"));
  EXPECT_TRUE(fs::exists(dir / "run/held_out/held_out_001/solution.vti"));
}

// A Gaussian random field drawn as a sine series: u solves Δu = f (central differences of the
// expressions) and vanishes on the box's faces; draws differ.
TEST(DrawnFamily, SineSeriesSolvesPoissonOnItsBox) {
  std::mt19937_64 engine(4);
  const std::vector<double> lower{0.0, -1.0}, upper{1.0, 2.0};
  const SineSeriesDraw a = draw_sine_series(lower, upper, 4, 2.0, 1.0, engine);
  const SineSeriesDraw b = draw_sine_series(lower, upper, 4, 2.0, 1.0, engine);
  EXPECT_NE(a.field, b.field);
  const io::Expression f(a.field, {"x", "y"}), u(a.solution, {"x", "y"});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(0.05, 0.95), uy(-0.95, 1.95);
  double largest = 0, worst = 0;
  const double h = 1e-3;
  for (int n = 0; n < 50; ++n) {
    const double x = ux(rng), y = uy(rng);
    const auto at = [&](double px, double py) { return u.evaluate(std::vector<double>{px, py}); };
    const double laplacian = (at(x + h, y) + at(x - h, y) + at(x, y + h) + at(x, y - h) - 4 * at(x, y)) / (h * h);
    const double fx = f.evaluate(std::vector<double>{x, y});
    largest = std::max(largest, std::abs(fx));
    worst = std::max(worst, std::abs(laplacian - fx));
  }
  EXPECT_GT(largest, 0.1);
  EXPECT_LT(worst, 1e-4 * largest);
  for (double t : {0.0, 0.3, 0.77, 1.0}) {
    EXPECT_NEAR(u.evaluate(std::vector<double>{0.0, -1.0 + 3 * t}), 0.0, 1e-12);
    EXPECT_NEAR(u.evaluate(std::vector<double>{1.0, -1.0 + 3 * t}), 0.0, 1e-12);
    EXPECT_NEAR(u.evaluate(std::vector<double>{t, -1.0}), 0.0, 1e-12);
    EXPECT_NEAR(u.evaluate(std::vector<double>{t, 2.0}), 0.0, 1e-12);
  }
}

std::string poisson_family(const std::string& draw, const std::string& equation_extra = "") {
  return "problem: poisson\n"
         "domain: {lower: [0, 0], upper: [1, 1]}\n"
         "equation:\n"
         "  family:\n"
         "    draw: {" + draw + "}\n"
         "    instances: 3\n" + equation_extra +
         "conditions: [{on: boundary, type: dirichlet, value: \"0\"}]\n"
         "field: {type: siren, hidden: [8]}\n"
         "training: {meta: {algorithm: reptile, steps: 2}, stages: [{optimizer: adam, steps: 4, lr: 1.0e-3}]}\n";
}

TEST(DrawnFamily, PoissonSourcesFromAGaussianRandomField) {
  const RunSetup setup = load_run(
      testutil::write_config("drawn_family_poisson",
                             poisson_family("source: {sine_series: {modes: 3, decay: 2, solution: exact}}")),
      {});
  const auto training = instances(*setup.problem, false);
  ASSERT_EQ(training.size(), 3U);
  Eigen::MatrixXd points(3, 2);
  points << 0.3, 0.6, 0.0, 0.4, 0.5, 1.0;
  const Eigen::MatrixXd u0 = training[0].problem->exact(points), u1 = training[1].problem->exact(points);
  EXPECT_GT(std::abs(u0(0, 0) - u1(0, 0)), 1e-6);  // each instance its own source
  EXPECT_NEAR(u0(1, 0), 0.0, 1e-12);                // zero on the faces
  EXPECT_NEAR(u1(2, 0), 0.0, 1e-12);
  const auto check = [](const std::string& text, const testutil::Located& want) {
    testutil::expect_located_error(testutil::write_config("drawn_family_poisson_errors", text), want);
  };
  check(poisson_family("source: {sine_series: {modes: 3, solution: exact}}", "  exact: \"0\"\n"),
        {5, 55, "equation.family.draw.source.sine_series.solution", "is set too"});
  check(poisson_family("source: {sine_series: {modes: 0}}"),
        {5, 42, "equation.family.draw.source.sine_series.modes", "[1, 32]"});
  check(poisson_family("source: {sine_series: {modes: 3}, range: [0, 1]}"),
        {5, 34, "equation.family.draw.source.sine_series", "not both"});
}

TEST(DrawnFamily, KeysAreLocated) {
  const auto check = [](const std::string& text, const testutil::Located& want) {
    testutil::expect_located_error(testutil::write_config("drawn_family_errors", text), want);
  };
  check(family_config("source_center: {range: [[0.3, -0.2], [-0.3, 0.2]]}"),
        {6, 35, "equation.family.draw.source_center.range", "lower <= upper"});
  check(family_config("source_center: {range: [[-0.3], [0.3, 0.2]]}"),
        {6, 35, "equation.family.draw.source_center.range", "one length"});
  check(family_config("source_width: {range: [0.05, 0.1]}"),
        {6, 26, "equation.family.draw.source_width", "is set too"});
  check(family_config("source_center: {rnge: [[-0.3, -0.2], [0.3, 0.2]]}"),
        {6, 28, "equation.family.draw.source_center.rnge", "unknown key 'rnge' (valid keys: range, sine_series)"});
  // A value the problem refuses (a source outside the domain), drawn for some instance.
  check(family_config("source_center: {range: [[-3, -0.2], [0.3, 0.2]]}"),
        {6, 27, "equation.family.draw.source_center", "inside the domain"});
  std::string zero = family_config();
  zero.replace(zero.find("instances: 5"), 12, "instances: 0");
  check(zero, {7, 16, "equation.family.instances", "[1, 100000]"});
  std::string unknown = family_config();
  unknown.replace(unknown.find("seed: 3"), 7, "sed: 3");
  check(unknown, {9, 5, "equation.family.sed", "unknown key"});
}

}  // namespace
}  // namespace nfield::solvers
