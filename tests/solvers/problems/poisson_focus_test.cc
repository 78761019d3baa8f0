// SPDX-License-Identifier: MIT
//
// Poisson's `equation.focus` (solvers/problems/poisson.cc): each item adds the residual's term
// pde_BATCH on points uniform over its region (Domain::sample_interior_where): every point
// inside the domain and the region, the share in a sub-region its area share (to 4 standard
// errors), the same residual as `pde`; refused inputs are located.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

const char* const kLShape = R"yaml(problem: poisson
domain:
  geometry: {shape: polygon, name: wall, vertices: [[-1, -1], [0, -1], [0, 0], [1, 0], [1, 1], [-1, 1]]}
equation:
  source: "0"
  exact: "x + y"
  focus:
    - {where: "x^2 + y^2 < 0.04", batch: corner, weight: 3}
    - {where: "x^2 + y^2 < 0.0025"}
conditions:
  - {on: wall, type: dirichlet, value: "x + y"}
field: {type: siren, hidden: [8], first_omega: 2}
training: {seed: 0, threads: 1, batch: {interior: 64, boundary: 64, corner: 64, focus_1: 64}, stages: [{optimizer: adam, steps: 1}]}
)yaml";

std::string with(const std::string& from, const std::string& to) {
  std::string t = kLShape;
  t.replace(t.find(from), from.size(), to);
  return t;
}

const LossTerm& term_named(const std::vector<LossTerm>& terms, const std::string& name) {
  for (const LossTerm& t : terms)
    if (t.name == name) return t;
  throw std::logic_error("no term " + name);
}

TEST(PoissonFocus, TermsDrawUniformPointsInTheirRegions) {
  const RunSetup setup = load_run(testutil::write_config("poisson_focus", kLShape), {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  const LossTerm& pde = term_named(terms, "pde");
  const LossTerm& corner = term_named(terms, "pde_corner");
  const LossTerm& inner = term_named(terms, "pde_focus_1");
  EXPECT_EQ(corner.batch_key, "corner");
  EXPECT_EQ(inner.batch_key, "focus_1");
  EXPECT_DOUBLE_EQ(corner.weight, 3);
  EXPECT_DOUBLE_EQ(inner.weight, 1);
  EXPECT_EQ(corner.spec.operators.size(), pde.spec.operators.size());  // the same residual
  Random rng(7);
  const Eigen::Index n = 4000;
  const Eigen::MatrixXd x = corner.sample(rng, n).x;
  ASSERT_EQ(x.rows(), n);
  EXPECT_TRUE(setup.problem->domain().contains_rows(x).all());
  const Eigen::ArrayXd r2 = x.col(0).array().square() + x.col(1).array().square();
  EXPECT_TRUE((r2 < 0.04).all());
  // Uniform over the three-quarter disk of radius 0.2: a share 1/4 within radius 0.1.
  const double share = static_cast<double>((r2 < 0.01).count()) / static_cast<double>(n);
  EXPECT_NEAR(share, 0.25, 4 * std::sqrt(0.25 * 0.75 / static_cast<double>(n)));
  // Outside the notch (x > 0, y < 0) only.
  EXPECT_FALSE(((x.col(0).array() > 1e-12) && (x.col(1).array() < -1e-12)).any());
  const Eigen::MatrixXd y = inner.sample(rng, 500).x;
  EXPECT_TRUE((y.col(0).array().square() + y.col(1).array().square() < 0.0025).all());
}

TEST(PoissonFocus, RefusedInputsAreLocated) {
  using testutil::expect_located_error;
  expect_located_error(testutil::write_config("poisson_focus", with("x^2 + y^2 < 0.04", "x > 2"), "empty"),
                       {8, 15, "equation.focus[0].where", "no point of 2^14"});
  expect_located_error(testutil::write_config("poisson_focus", with("batch: corner", "batch: interior"), "taken"),
                       {8, 42, "equation.focus[0].batch", "is taken"});
  expect_located_error(testutil::write_config("poisson_focus", with("weight: 3", "weight: -1"), "weight"),
                       {8, 58, "equation.focus[0].weight", "weight >= 0"});
  expect_located_error(testutil::write_config("poisson_focus", with("weight: 3", "wieght: 3"), "key"),
                       {8, 50, "equation.focus[0].wieght", "valid keys: where, weight, batch"});
  expect_located_error(testutil::write_config("poisson_focus", with("x^2 + y^2 < 0.04", "x <* 1"), "expr"),
                       {8, 19, "equation.focus[0].where", "Unexpected operator"});
}

}  // namespace
}  // namespace nfield::solvers
