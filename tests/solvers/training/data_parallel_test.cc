// SPDX-License-Identifier: MIT
//
// Data-parallel training, run by CTest under `mpirun -np 2`: one step's loss and gradient
// summed over the ranks equal those of a single process (the same trainer on a serial
// communicator) on the same points, to round-off, for per-point terms (Poisson, in double
// and float) and for terms over groups (NeRF rays, split between rays); every rank ends with
// the same bits; short Adam, L-BFGS and LM stages end where one process ends. Batches are odd
// so that the ranks' shares differ in size. The comparisons hold for any R; RunsOnSeveralRanks
// asks for R >= 2 so that CTest's run cannot pass by comparing one process with itself.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "solvers/run/run.h"
#include "solvers/training/communicator.h"
#include "solvers/training/trainer.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

Communicator& world() { return world_communicator(); }

std::string rank_group() { return "data_parallel_rank" + std::to_string(world().rank()); }

// Whether every rank holds the same n values as rank 0, bit for bit.
template <typename Scalar>
bool same_on_every_rank(const Scalar* values, Eigen::Index n) {
  autodiff::Vector<Scalar> root = Eigen::Map<const autodiff::Vector<Scalar>>(values, n);
  world().broadcast(root.data(), static_cast<std::size_t>(n));
  const bool same =
      (root.array() == Eigen::Map<const autodiff::Vector<Scalar>>(values, n).array()).all();
  return !world().any(!same);
}

struct Step {
  double loss = 0;
  std::vector<double> terms;
  Eigen::VectorXd gradient;
};

// One step's loss and gradient at the field's initial parameters, over `communicator`.
template <typename Scalar>
Step one_step(const RunSetup& setup, Communicator& communicator) {
  fields::Field<Scalar> field(setup.field);
  Trainer<Scalar> trainer(*setup.problem, field, setup.training, &communicator);
  autodiff::Vector<Scalar> gradient(field.parameter_count());
  Step step;
  step.loss = trainer.loss_and_gradient_at(field.parameters().data(), gradient.data());
  step.terms = trainer.term_losses();
  step.gradient = gradient.template cast<double>();
  EXPECT_TRUE(same_on_every_rank(gradient.data(), gradient.size()));
  return step;
}

// The R-rank step against the single process's, each relative to the largest magnitude:
// the sums differ only in their order (blocks of 128 points in another grouping, then
// R partial sums), so the difference is a few ulps of the terms summed.
template <typename Scalar>
void expect_step_as_single_process(const RunSetup& setup, double tolerance) {
  SerialCommunicator serial;
  const Step parallel = one_step<Scalar>(setup, world());
  const Step single = one_step<Scalar>(setup, serial);
  ASSERT_GT(single.loss, 0);
  EXPECT_NEAR(parallel.loss, single.loss, tolerance * single.loss);
  ASSERT_EQ(parallel.terms.size(), single.terms.size());
  for (size_t k = 0; k < single.terms.size(); ++k)
    EXPECT_NEAR(parallel.terms[k], single.terms[k], tolerance * single.loss) << k;
  const double scale = single.gradient.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0);
  EXPECT_LE((parallel.gradient - single.gradient).cwiseAbs().maxCoeff(), tolerance * scale);
}

// Poisson on a small field that every optimizer can take: Adam, L-BFGS, then LM.
const char* kThreeStages = R"yaml(problem: poisson
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: "-2*pi^2*sin(pi*x)*sin(pi*y)", exact: "sin(pi*x)*sin(pi*y)"}
conditions: [{on: boundary, type: dirichlet, value: "0", weight: 10}]
field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}
training:
  precision: double
  batch: {interior: 201, boundary: 57}
  stages:
    - {optimizer: adam, steps: 5, lr: 1.0e-3}
    - {optimizer: lbfgs, steps: 5}
    - {optimizer: lm, steps: 3, backend: BACKEND}
output: {dir: unused}
)yaml";

std::string three_stages(const std::string& backend) {
  std::string text = kThreeStages;
  return text.replace(text.find("BACKEND"), 7, backend);
}

const std::filesystem::path kConfigs = std::filesystem::path(NFIELD_SOURCE_DIR) / "configs";

TEST(DataParallel, PoissonStepEqualsOneProcessInDouble) {
  const RunSetup setup = load_run(kConfigs / "poisson_2d.yaml",
                                  {"training.batch.interior=1001", "training.batch.boundary=257"});
  expect_step_as_single_process<double>(setup, 1e-12);
}

TEST(DataParallel, PoissonStepEqualsOneProcessInFloat) {
  const RunSetup setup = load_run(kConfigs / "poisson_2d.yaml",
                                  {"training.precision=float", "training.batch.interior=1001",
                                   "training.batch.boundary=257"});
  // float sums of ~10³ terms: relative round-off ~ 10³ · 6e-8 at worst.
  expect_step_as_single_process<float>(setup, 1e-4);
}

TEST(DataParallel, RayGroupsStepEqualsOneProcess) {
  const std::filesystem::path bunny =
      std::filesystem::path(NFIELD_SOURCE_DIR) / "data/multiview/bunny_blender";
  const auto config = testutil::write_config(
      rank_group(),
      "problem: nerf\n"
      "data: {train: " + (bunny / "transforms_train.json").string() + "}\n"
      "scene: {lower: [-0.6, -0.6, -0.6], upper: [0.6, 0.6, 0.6]}\n"
      "render: {samples: 16}\n"
      "field: {type: nerf, hidden: [32, 32], color_hidden: [16], "
      "encoding: {type: positional, frequencies: 6}}\n"
      "training: {precision: double, batch: {rays: 63}, stages: [{optimizer: adam, steps: 1}]}\n"
      "output: {dir: unused}\n");
  const RunSetup setup = load_run(config, {});
  expect_step_as_single_process<double>(setup, 1e-12);
}

// Each optimizer on the summed loss: after Adam (the reduced gradient), L-BFGS (Ceres on the
// reduced cost and gradient) and LM (the own one on JᵀJ and Jᵀf summed by one allreduce, or
// Ceres on the Jacobian gathered from the ranks) every rank holds the same parameters, and
// they are the single process's up to the round-off of the sums, carried through 13 steps.
void expect_three_stages_end_as_one_process(const std::string& backend) {
  const RunSetup setup = load_run(testutil::write_config(rank_group(), three_stages(backend)), {});
  SerialCommunicator serial;
  Eigen::VectorXd theta[2];
  std::vector<double> stage_losses[2];
  Communicator* communicators[2] = {&world(), &serial};
  for (int i = 0; i < 2; ++i) {
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training, communicators[i]);
    ASSERT_TRUE(trainer.run({}));
    EXPECT_EQ(trainer.step(), 13);
    theta[i] = field.parameters();
    stage_losses[i] = trainer.stage_losses();
    if (i == 0) EXPECT_TRUE(same_on_every_rank(theta[i].data(), theta[i].size()));
  }
  ASSERT_EQ(stage_losses[0].size(), 3u);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(stage_losses[0][k], stage_losses[1][k], 1e-8 * stage_losses[1][0]) << k;
  EXPECT_LE((theta[0] - theta[1]).cwiseAbs().maxCoeff(), 1e-8 * theta[1].cwiseAbs().maxCoeff());
  // The run moved: the comparison is not of two untouched initial fields.
  fields::Field<double> initial(setup.field);
  EXPECT_GT((theta[1] - initial.parameters()).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(DataParallel, AdamLbfgsLmEndAsOneProcess) { expect_three_stages_end_as_one_process("own"); }

TEST(DataParallel, AdamLbfgsCeresLmEndAsOneProcess) {
  expect_three_stages_end_as_one_process("ceres");
}

TEST(DataParallel, RunsOnSeveralRanks) {
  // CTest runs this program under mpirun -np 2; on one rank the comparisons above are void.
  if (!built_with_mpi()) GTEST_SKIP() << "built without MPI";
  EXPECT_GE(world().size(), 2);
}

TEST(DataParallel, SpreadOverRanksFindsOneRankOff) {
  // Equal values: 0. Rank r > 0 off by r·2⁻²⁰ in one value (float) or r·1e-13 (double): the
  // sum over the ranks of each one's largest difference, on every rank.
  const int r = world().rank(), size = world().size();
  double off = 0;
  for (int k = 1; k < size; ++k) off += k * 1e-13;
  std::vector<double> d = {1.0, -2.5, 3.25};
  EXPECT_EQ(spread_over_ranks(world(), d.data(), d.size()), 0.0);
  d[1] += r * 1e-13;
  EXPECT_NEAR(spread_over_ranks(world(), d.data(), d.size()), off, 1e-15);  // ulps of 2.5
  std::vector<float> f = {1.0f, 0.5f};
  EXPECT_EQ(spread_over_ranks(world(), f.data(), f.size()), 0.0);
  f[0] += static_cast<float>(r) * 0x1p-20f;
  EXPECT_EQ(spread_over_ranks(world(), f.data(), f.size()), size * (size - 1) / 2 * 0x1p-20);
  // One process: 0, with nothing to compare.
  SerialCommunicator serial;
  EXPECT_EQ(spread_over_ranks(serial, d.data(), d.size()), 0.0);
}

TEST(DataParallel, ShareOfCoversEveryRowOnce) {
  for (int size : {1, 2, 3, 7})
    for (std::ptrdiff_t n : {0, 1, 5, 6, 1001}) {
      std::ptrdiff_t next = 0;
      for (int r = 0; r < size; ++r) {
        const Share s = share_of(n, r, size);
        EXPECT_EQ(s.first, next);
        EXPECT_GE(s.count, n / size);
        EXPECT_LE(s.count, n / size + 1);
        next += s.count;
      }
      EXPECT_EQ(next, n);
    }
}

}  // namespace
}  // namespace nfield::solvers

int main(int argc, char** argv) {
  nfield::solvers::CommunicationScope communication(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
