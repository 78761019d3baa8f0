// SPDX-License-Identifier: MIT
//
// `functionals` of problem: pde (solvers/problems/pde_functionals.h) on a field with
// closed-form streams (tests/testing/exponential_streams.h): boundary integrals over a hole,
// a plate's outer boundary cut by `where` and box faces at a time, against independent
// quadratures of the closed forms (the trapezoidal rule on the circle, a fine midpoint rule on
// the faces); point sums against the closed form; located errors for bad items.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <string>

#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/exponential_streams.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

using testutil::Exponentials;
constexpr double kPi = std::numbers::pi;

// The metrics write_outputs adds for a field equal to f.
std::map<std::string, double> functional_metrics(const Problem& problem, const Exponentials& f) {
  OutputContext context;
  const int channels = problem.output_dim();
  context.streams = [&f, channels](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
    return testutil::exponential_streams(layout, f, x, channels);
  };
  std::vector<std::pair<std::string, double>> metrics;
  problem.write_outputs(context, metrics);
  return {metrics.begin(), metrics.end()};
}

// ∫ g ds along the segment from a to b by the midpoint rule on m cells.
double segment_integral(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::function<double(const Eigen::Vector2d&)>& g,
                        int m = 200000) {
  double s = 0;
  for (int k = 0; k < m; ++k) s += g(a + (b - a) * ((k + 0.5) / m));
  return s * (b - a).norm() / m;
}

const char* kPlate = R"yaml(problem: pde
domain:
  geometry:
    shape: difference
    shapes:
      - {shape: box, name: plate, lower: [0, 0], upper: [1, 1]}
      - {shape: disk, name: hole, center: [0.6, 0.4], radius: 0.15}
outputs: [u, v]
constants: {k: "2"}
equation:
  residuals: ["lap(u) - v", "v - u_x"]
functionals:
  around_hole: {integral: "k*u*nx + v_y*ny + lap(u)*nx", on: hole}
  left_of_plate: {integral: "v*(1 + nx)", on: plate, where: "x < 0.5"}
  difference: {value: "u + v_x", at: [[0.2, 0.2], [0.9, 0.9]], coefficients: [1, -2], reference: 1.5}
)yaml";

TEST(PdeFunctionals, IntegralsOverPartsAndPointSums) {
  const RunSetup setup = load_run(testutil::write_config("pde_functionals", kPlate), {});
  std::mt19937 rng(7);
  const Exponentials f = testutil::random_exponentials(2, 2, rng);
  const auto m = functional_metrics(*setup.problem, f);
  const auto value = [&](int c, const Eigen::Vector2d& x, auto g) { return f.sum(c, x, g); };
  const auto one = [](const Eigen::VectorXd&) { return 1.0; };

  // Around the hole: the domain's normal points into the hole, −(x − c)/r.
  const Eigen::Vector2d c(0.6, 0.4);
  double hole = 0;
  const int n = 4096;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    const Eigen::Vector2d normal(-std::cos(t), -std::sin(t)), x = c - 0.15 * normal;
    const double u = value(0, x, one), v_y = value(1, x, [](const Eigen::VectorXd& r) { return r(1); }),
                 lap = value(0, x, [](const Eigen::VectorXd& r) { return r.squaredNorm(); });
    hole += (2 * u * normal(0) + v_y * normal(1) + lap * normal(0)) * 2 * kPi * 0.15 / n;
  }
  EXPECT_NEAR(m.at("functional_around_hole"), hole, 1e-12);

  // The plate's outer boundary where x < 0.5: the left face (nx = −1: the integrand is 0) and
  // the left halves of the bottom and top faces (nx = 0).
  const auto v = [&](const Eigen::Vector2d& x) { return value(1, x, one); };
  const double left = segment_integral({0, 0}, {0.5, 0}, v) + segment_integral({0, 1}, {0.5, 1}, v);
  // The cut at x = 0.5 is resolved to one node of the face's midpoint rule.
  EXPECT_NEAR(m.at("functional_left_of_plate"), left, 2e-3);
  EXPECT_GT(std::abs(left), 1e-2);

  // Point sum: u + v_x at two points with coefficients 1 and −2, and its reference figures.
  const auto point = [&](const Eigen::Vector2d& x) {
    return value(0, x, one) + value(1, x, [](const Eigen::VectorXd& r) { return r(0); });
  };
  const double sum = point({0.2, 0.2}) - 2 * point({0.9, 0.9});
  EXPECT_NEAR(m.at("functional_difference"), sum, 1e-13);
  EXPECT_EQ(m.at("functional_difference_reference"), 1.5);
  EXPECT_NEAR(m.at("functional_difference_rel_error"), std::abs(sum - 1.5) / 1.5, 1e-13);
  EXPECT_EQ(m.count("functional_around_hole_reference"), 0u);
}

const char* kSlab = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 2], time: [0, 1]}
equation:
  residuals: ["u_t - lap(u)"]
functionals:
  flux: {integral: "u_x*nx", on: [x_min, x_max], time: 0.5, points: 20000}
  probe: {value: "u_t", at: [[0.5, 1.0, 0.25]]}
)yaml";

TEST(PdeFunctionals, BoxFacesAtATime) {
  const RunSetup setup = load_run(testutil::write_config("pde_functionals", kSlab), {});
  std::mt19937 rng(11);
  const Exponentials f = testutil::random_exponentials(3, 1, rng);
  const auto m = functional_metrics(*setup.problem, f);
  const auto u_x = [&](double x) {
    return [&f, x](const Eigen::Vector2d& p) {
      return f.sum(0, Eigen::Vector3d(x, p(1), 0.5), [](const Eigen::VectorXd& r) { return r(0); });
    };
  };
  // x_max (nx = 1) minus x_min (nx = −1); each face has 10,000 nodes: midpoint error ~1e-9.
  const double flux = segment_integral({1, 0}, {1, 2}, u_x(1)) - segment_integral({0, 0}, {0, 2}, u_x(0));
  EXPECT_NEAR(m.at("functional_flux"), flux, 1e-8);
  EXPECT_NEAR(m.at("functional_probe"),
              f.sum(0, Eigen::Vector3d(0.5, 1.0, 0.25), [](const Eigen::VectorXd& r) { return r(2); }), 1e-13);
}

TEST(PdeFunctionals, BadItemsAreLocated) {
  using testutil::expect_located_error;
  const auto with = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  const auto config = [](const std::string& name, const std::string& text) {
    return testutil::write_config("pde_functionals", text, name);
  };
  expect_located_error(config("no_time", with(kSlab, ", time: 0.5", "")),
                       {6, 9, "functionals.flux.time", "needs 'time: T' in [0, 1]"});
  expect_located_error(config("late", with(kSlab, "time: 0.5", "time: 1.5")),
                       {6, 56, "functionals.flux.time", "expected a time in [0, 1]"});
  expect_located_error(config("both", with(kSlab, "{value: \"u_t\",", "{value: \"u_t\", integral: \"u\", on: [x_min],")),
                       {7, 10, "functionals.probe", "give one of 'integral'"});
  expect_located_error(config("outside", with(kSlab, "[0.5, 1.0, 0.25]", "[0.5, 2.5, 0.25]")),
                       {7, 30, "functionals.probe.at[0]", "the point's y = 2.5 lies outside the domain's [0, 2]"});
  expect_located_error(config("short", with(kSlab, "[0.5, 1.0, 0.25]", "[0.5, 1.0]")),
                       {7, 30, "functionals.probe.at[0]", "expected a point of 3 numbers [x, y, t]"});
  expect_located_error(config("coefficients", with(kSlab, "0.25]]}", "0.25]], coefficients: [1, 2]}")),
                       {7, 63, "functionals.probe.coefficients", "expected one coefficient per point (1), got 2"});
  expect_located_error(config("no_output", with(kSlab, "{value: \"u_t\"", "{value: \"x*t\"")),
                       {7, 18, "functionals.probe.value", "the functional 'x*t' reads no output"});
  expect_located_error(config("unknown_symbol", with(kSlab, "u_x*nx", "u_x*nz")),
                       {6, 25, "functionals.flux.integral", "unknown symbol 'nz'"});
  expect_located_error(config("nx_taken", with(with(kSlab, "domain:", "outputs: [u, nx]\ndomain:"), "u_t - lap(u)",
                                               "u_t - lap(u) + nx")),
                       {7, 20, "functionals.flux.integral", "normal component 'nx' is also an output"});
  expect_located_error(config("unknown_part", with(kPlate, "on: hole", "on: hoel")),
                       {13, 62, "functionals.around_hole.on", "unknown part 'hoel' (parts: plate, hole; or boundary)"});
  expect_located_error(config("empty", with(kPlate, "around_hole: {", "around_hole: {}\n  unused: {")),
                       {13, 16, "functionals.around_hole", "give one of 'integral'"});
}

}  // namespace
}  // namespace nfield::solvers
