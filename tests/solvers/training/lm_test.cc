// SPDX-License-Identifier: MIT
//
// The Levenberg–Marquardt stage (optimizer: lm): on a small 2D Poisson problem it lowers
// the error of an Adam-trained field by a large factor; its steps, stops and checkpoints
// follow the trainer's callbacks; resample_every splits it into segments on new point sets;
// a stage that converges early counts as finished; its config keys are validated and
// written back.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "io/config.h"
#include "io/hdf5_file.h"
#include "solvers/training/optimizers.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

std::filesystem::path write_config(const std::string& text) { return testutil::write_config("lm", text); }

// −Δu = 2π² sin(πx) sin(πy) on [0, 1]², u = 0 on the boundary; written as Δu = f.
std::string poisson_config(const std::string& field, const std::string& batch,
                           const std::string& stages) {
  return "problem: poisson\n"                                               // 1
         "domain: {lower: [0, 0], upper: [1, 1]}\n"                         // 2
         "equation:\n"                                                      // 3
         "  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n"                      // 4
         "  exact: \"sin(pi*x)*sin(pi*y)\"\n"                               // 5
         "conditions:\n"                                                    // 6
         "  - {on: boundary, type: dirichlet, value: \"0\", weight: 10}\n"  // 7
         "field: " + field + "\n"                                           // 8
         "training:\n"                                                      // 9
         "  seed: 3\n"                                                      // 10
         "  precision: double\n"                                            // 11
         "  threads: 1\n"                                                   // 12
         "  batch: " + batch + "\n"                                         // 13
         "  stages:\n"                                                      // 14
         + stages +                                                         // 15…
         "output: {grid: [5, 5]}\n";
}

constexpr const char* kSmallMlp = "{type: mlp, activation: tanh, hidden: [16, 16]}";

// Relative L2 error against sin(πx) sin(πy) on a 41 × 41 grid.
template <typename Scalar>
double relative_l2(const fields::Field<Scalar>& field) {
  const int n = 41;
  Eigen::MatrixXd x(n * n, 2);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) x.row(i * n + j) << i / (n - 1.0), j / (n - 1.0);
  const Eigen::VectorXd exact =
      ((std::numbers::pi * x.col(0).array()).sin() * (std::numbers::pi * x.col(1).array()).sin())
          .matrix();
  const Eigen::VectorXd u = field.values(x.cast<Scalar>()).col(0).template cast<double>();
  return (u - exact).norm() / exact.norm();
}

template <typename Scalar>
void expect_lm_refines_adam(double factor) {
  const std::string adam = "    - {optimizer: adam, steps: 300, lr: 1.0e-2, schedule: cosine, lr_final: 1.0e-3}\n";
  const std::string lm = "    - {optimizer: lm, steps: 60}\n";
  const std::string batch = "{interior: 300, boundary: 80}";
  RunSetup first = load_run(write_config(poisson_config(kSmallMlp, batch, adam)), {});
  RunSetup second = load_run(write_config(poisson_config(kSmallMlp, batch, lm)), {});
  fields::Field<Scalar> field(first.field);
  Trainer<Scalar> adam_trainer(*first.problem, field, first.training);
  ASSERT_TRUE(adam_trainer.run({}));
  const double adam_error = relative_l2(field);
  const double adam_loss = adam_trainer.stage_losses().back();

  Trainer<Scalar> lm_trainer(*second.problem, field, second.training);
  long steps = 0;
  double last_loss = INFINITY;
  bool monotone = true;
  typename Trainer<Scalar>::Callbacks callbacks;
  callbacks.progress = [&](const Progress& p) {
    ++steps;
    EXPECT_EQ(p.optimizer, "lm");
    EXPECT_EQ(p.step, steps);
    // LM accepts only steps that lower the loss.
    monotone = monotone && p.loss <= last_loss;
    last_loss = p.loss;
  };
  ASSERT_TRUE(lm_trainer.run(callbacks));
  const double lm_error = relative_l2(field);
  EXPECT_EQ(lm_trainer.step(), 60);
  EXPECT_GT(steps, 10);
  EXPECT_TRUE(monotone);
  ASSERT_EQ(lm_trainer.stage_losses().size(), 1u);
  EXPECT_LT(lm_trainer.stage_losses()[0], adam_loss / (factor * factor));
  EXPECT_LT(lm_error, adam_error / factor) << "adam " << adam_error << ", lm " << lm_error;
  // The per-term losses are those of the final parameters.
  EXPECT_NEAR(lm_trainer.stage_losses()[0], last_loss, 1e-12 * last_loss);
}

TEST(LevenbergMarquardt, RefinesAdamOnPoisson2DDouble) { expect_lm_refines_adam<double>(100); }

// Float Jacobians limit the attainable loss, yet at this size LM still gains as much as in double.
TEST(LevenbergMarquardt, RefinesAdamOnPoisson2DFloat) { expect_lm_refines_adam<float>(30); }

TEST(LevenbergMarquardt, BothLinearSolversAgree) {
  auto run = [](const std::string& solver) {
    const std::string stage =
        "    - {optimizer: lm, steps: 8, backend: ceres, linear_solver: " + solver + "}\n";
    RunSetup setup = load_run(
        write_config(poisson_config(kSmallMlp, "{interior: 100, boundary: 40}", stage)), {});
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training);
    EXPECT_TRUE(trainer.run({}));
    return std::pair(trainer.stage_losses().at(0), Eigen::VectorXd(field.parameters()));
  };
  const auto [qr_loss, qr_theta] = run("dense_qr");
  const auto [chol_loss, chol_theta] = run("dense_normal_cholesky");
  EXPECT_NEAR(qr_loss, chol_loss, 1e-6 * qr_loss);
  EXPECT_LE((qr_theta - chol_theta).cwiseAbs().maxCoeff(), 1e-6 * qr_theta.cwiseAbs().maxCoeff());
}

TEST(LevenbergMarquardt, StopsCheckpointsAndResumesStepCount) {
  const std::string stages =
      "    - {optimizer: lm, steps: 12}\n"
      "    - {optimizer: adam, steps: 3, lr: 1.0e-4}\n";
  RunSetup setup = load_run(
      write_config(poisson_config(kSmallMlp, "{interior: 100, boundary: 40}", stages)), {});
  setup.training.checkpoint_every = 4;
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  std::vector<long> checkpoints;
  typename Trainer<double>::Callbacks callbacks;
  callbacks.checkpoint = [&] { checkpoints.push_back(trainer.step()); };
  callbacks.stop_requested = [&] { return trainer.step() >= 5; };
  ASSERT_FALSE(trainer.run(callbacks));
  EXPECT_EQ(trainer.step(), 5);
  EXPECT_EQ(checkpoints, (std::vector<long>{4}));
  EXPECT_TRUE(trainer.stage_losses().empty());
  callbacks.stop_requested = {};
  ASSERT_TRUE(trainer.run(callbacks));
  EXPECT_EQ(trainer.step(), 15);
  EXPECT_EQ(trainer.stage_losses().size(), 2u);
  EXPECT_EQ(checkpoints, (std::vector<long>{4, 8, 12}));
  EXPECT_TRUE(field.parameters().allFinite());
}

// resample_every: the stage runs in segments of k iterations, each on a new point set, and
// still takes exactly its steps; without it the stage keeps the set it drew at its start.
TEST(LevenbergMarquardt, ResampleEveryDrawsNewPointsAndKeepsTheStepCount) {
  auto run = [](const std::string& optimizer, int resample_every) {
    const std::string stage = "    - {optimizer: " + optimizer + ", steps: 9, resample_every: " +
                              std::to_string(resample_every) + "}\n";
    RunSetup setup = load_run(
        write_config(poisson_config(kSmallMlp, "{interior: 60, boundary: 20}", stage)), {});
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training);
    std::vector<long> steps;
    typename Trainer<double>::Callbacks callbacks;
    callbacks.progress = [&](const Progress& p) { steps.push_back(p.step); };
    EXPECT_TRUE(trainer.run(callbacks));
    EXPECT_EQ(trainer.step(), 9);
    for (size_t i = 0; i < steps.size(); ++i) EXPECT_EQ(steps[i], static_cast<long>(i + 1));
    const std::filesystem::path path = testutil::scratch_dir("lm") / "resample_state.h5";
    {
      io::H5Writer file(path);
      trainer.save_state(file);
      file.commit();
    }
    return io::H5Reader(path).read_matrix<double>("trainer/points/0");
  };
  for (const std::string optimizer : {"lm", "lbfgs"}) {
    SCOPED_TRACE(optimizer);
    const Eigen::MatrixXd kept = run(optimizer, 0), again = run(optimizer, 0);
    const Eigen::MatrixXd resampled = run(optimizer, 3);
    EXPECT_EQ(kept, again);  // deterministic
    ASSERT_EQ(resampled.rows(), kept.rows());
    EXPECT_NE(resampled, kept);  // the last segment's set, not the first
  }
}

// `batch_scale: k` on a stage: its terms draw k times their batch (the earlier stage's do not),
// the resolved config keeps the key, and the load-time size check counts the larger sets.
TEST(LevenbergMarquardt, BatchScaleDrawsMorePointsInItsStage) {
  RunSetup setup = load_run(write_config(poisson_config(kSmallMlp, "{interior: 60, boundary: 20}",
                                                        "    - {optimizer: adam, steps: 2}\n"
                                                        "    - {optimizer: lm, steps: 2, batch_scale: 3}\n")),
                            {});
  EXPECT_EQ(setup.training.to_yaml()["stages"][1]["batch_scale"].as<int>(), 3);
  EXPECT_FALSE(setup.training.to_yaml()["stages"][0]["batch_scale"]);
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  std::vector<Eigen::Index> adam_points;
  typename Trainer<double>::Callbacks callbacks;
  callbacks.progress = [&](const Progress& p) {
    if (p.step <= 2) adam_points.push_back(trainer.points(0).rows() + trainer.points(1).rows());
  };
  ASSERT_TRUE(trainer.run(callbacks));
  EXPECT_EQ(adam_points, (std::vector<Eigen::Index>{80, 80}));
  EXPECT_EQ(trainer.points(0).rows() + trainer.points(1).rows(), 240);

  const std::string field_text = "{type: siren, hidden: [256, 256, 256]}";
  const std::string stages = "    - {optimizer: lm, steps: 1, backend: ceres, batch_scale: 2}\n";
  EXPECT_NO_THROW(load_run(write_config(poisson_config(field_text, "{interior: 9000, boundary: 40}",
                                                       "    - {optimizer: lm, steps: 1, backend: ceres}\n")),
                           {}));
  try {
    load_run(write_config(poisson_config(field_text, "{interior: 9000, boundary: 40}", stages)), {});
    ADD_FAILURE() << "no error at load time";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), "training.stages[0].optimizer") << e.what();
    EXPECT_NE(std::string(e.what()).find("18080 residuals"), std::string::npos) << e.what();
  }
}

// Fewer residuals than parameters: Ceres' LM on its QR solver fits them to rounding, its trust
// region then collapses and Ceres ends the stage early. (On the normal equations, Ceres' and
// the own, the squared condition number stops the fit near 1e-8; the own method's collapse
// is tested in levenberg_marquardt_test.) The stage is over, reported as converged with the
// iterations it took (the run's step count is the steps taken), and the next one runs.
TEST(LevenbergMarquardt, EarlyConvergenceFinishesTheStage) {
  const std::string stages =
      "    - {optimizer: lm, steps: 400, backend: ceres}\n"
      "    - {optimizer: adam, steps: 2, lr: 1.0e-6}\n";
  RunSetup setup = load_run(
      write_config(poisson_config("{type: mlp, activation: tanh, hidden: [12]}",
                                  "{interior: 12, boundary: 8}", stages)),
      {});
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  ASSERT_EQ(trainer.stage_losses().size(), 2u);
  EXPECT_LT(trainer.stage_losses()[0], 1e-20);
  ASSERT_EQ(trainer.stage_ends().size(), 2u);
  const StageEnd& lm = trainer.stage_ends()[0];
  EXPECT_EQ(lm.ended, "converged");
  EXPECT_EQ(lm.termination, "CONVERGENCE");
  EXPECT_FALSE(lm.message.empty());
  // Ceres took fewer iterations than allowed (one duration recorded per iteration).
  EXPECT_GT(lm.iterations, 0);
  EXPECT_LT(lm.iterations, 400);
  EXPECT_EQ(trainer.stage_ends()[1].iterations, 2);
  EXPECT_EQ(trainer.stage_ends()[1].ended, "completed");
  EXPECT_EQ(trainer.step(), lm.iterations + 2);
  EXPECT_EQ(trainer.step_milliseconds().size(), static_cast<size_t>(lm.iterations + 2));
}

// A Jacobian beyond Ceres' int-sized dense matrices is refused with a located message when
// the config is loaded, before any training; the trainer refuses it too, before any of it is
// allocated (RAR points could grow it past the load-time count).
TEST(LevenbergMarquardt, OversizedJacobianIsRefused) {
  const std::string field = "{type: siren, hidden: [256, 256, 256]}";
  const std::string batch = "{interior: 20000, boundary: 40}";
  fields::FieldOptions options;
  options.type = "siren";
  options.hidden = {256, 256, 256};
  const std::string size =
      "20040 residuals x " + std::to_string(fields::Field<double>(options).parameter_count()) +
      " parameters";
  const auto path = write_config(poisson_config(
      field, batch, "    - {optimizer: adam, steps: 1}\n    - {optimizer: lm, steps: 1, backend: ceres}\n"));
  try {
    load_run(path, {});
    ADD_FAILURE() << "no error at load time";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.line(), 16) << e.what();  // the lm stage
    EXPECT_EQ(e.key_path(), "training.stages[1].optimizer") << e.what();
    EXPECT_NE(std::string(e.what()).find(size), std::string::npos) << e.what();
  }
  // The trainer's own check: the same config with a small batch, enlarged afterwards.
  RunSetup setup = load_run(
      write_config(poisson_config(field, "{interior: 20, boundary: 40}",
                                  "    - {optimizer: lm, steps: 1, backend: ceres}\n")),
      {});
  setup.training.batch["interior"] = 20000;
  fields::Field<float> small(setup.field);
  Trainer<float> trainer(*setup.problem, small, setup.training);
  try {
    trainer.run({});
    ADD_FAILURE() << "no error from the trainer";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(size), std::string::npos) << e.what();
  }
}

// The own backend holds JᵀJ, P × P, whatever the points: a field with P² beyond BLAS's int
// is refused at load time, naming P.
TEST(LevenbergMarquardt, OversizedNormalEquationsAreRefused) {
  fields::FieldOptions options;
  options.type = "siren";
  options.hidden = {256, 256, 256};
  const std::string p = std::to_string(fields::Field<double>(options).parameter_count());
  const auto path = write_config(poisson_config("{type: siren, hidden: [256, 256, 256]}",
                                                "{interior: 20, boundary: 4}",
                                                "    - {optimizer: lm, steps: 1}\n"));
  try {
    load_run(path, {});
    ADD_FAILURE() << "no error at load time";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.line(), 15) << e.what();
    EXPECT_NE(std::string(e.what()).find("normal equations of " + p + " x " + p), std::string::npos)
        << e.what();
  }
}

// Both backends from the same start on the same points: the same trust-region rule, so the
// same loss after a few iterations (the normal equations formed in a different order: round-off).
TEST(LevenbergMarquardt, OwnBackendFollowsCeresNormalCholesky) {
  auto run = [](const std::string& backend) {
    const std::string stage = "    - {optimizer: lm, steps: 6, backend: " + backend +
                              ", linear_solver: dense_normal_cholesky}\n";
    RunSetup setup = load_run(
        write_config(poisson_config(kSmallMlp, "{interior: 100, boundary: 40}", stage)), {});
    fields::Field<double> field(setup.field);
    Trainer<double> trainer(*setup.problem, field, setup.training);
    EXPECT_TRUE(trainer.run({}));
    EXPECT_EQ(trainer.step(), 6);
    return std::pair(trainer.stage_losses().at(0), Eigen::VectorXd(field.parameters()));
  };
  const auto [ceres_loss, ceres_theta] = run("ceres");
  const auto [own_loss, own_theta] = run("own");
  EXPECT_NEAR(own_loss, ceres_loss, 1e-6 * ceres_loss);
  EXPECT_LE((own_theta - ceres_theta).cwiseAbs().maxCoeff(), 1e-5 * ceres_theta.cwiseAbs().maxCoeff());
}

using testutil::Located;

void expect_config_error(const std::string& stage, const Located& want) {
  testutil::expect_located_error(
      write_config(poisson_config(kSmallMlp, "{interior: 10, boundary: 4}", stage)), want);
}

TEST(LevenbergMarquardtConfig, UnknownLinearSolverIsAConfigError) {
  // Line 15 is the first stage; column 48 the value of linear_solver.
  expect_config_error("    - {optimizer: lm, steps: 5, linear_solver: svd}\n",
                      {15, 48, "training.stages[0].linear_solver",
                       "expected one of dense_qr, dense_normal_cholesky; got 'svd'"});
}

TEST(LevenbergMarquardtConfig, RadiusOutOfRangeIsAConfigError) {
  expect_config_error("    - {optimizer: lm, steps: 5, initial_radius: 0}\n",
                      {15, 49, "training.stages[0].initial_radius", "expected a number in [1.0e-12, 1.0e+16]"});
  expect_config_error("    - {optimizer: lm, steps: 5, initial_radius: 1e20}\n",
                      {15, 49, "training.stages[0].initial_radius", "expected a number in [1.0e-12, 1.0e+16]"});
}

TEST(LevenbergMarquardtConfig, BackendAndItsSolverAreChecked) {
  expect_config_error("    - {optimizer: lm, steps: 5, backend: gpu}\n",
                      {15, 42, "training.stages[0].backend", "expected one of own, ceres; got 'gpu'"});
  expect_config_error("    - {optimizer: lm, steps: 5, linear_solver: dense_qr}\n",
                      {15, 48, "training.stages[0].linear_solver",
                       "backend: own solves the normal equations by Cholesky"});
}

TEST(LevenbergMarquardtConfig, KeysOfOtherOptimizersAreRejected) {
  expect_config_error("    - {optimizer: lm, steps: 5, lr: 1.0e-3}\n",
                      {15, 33, "training.stages[0].lr", "unknown key 'lr'"});
  expect_config_error("    - {optimizer: lm, steps: 5, memory: 10}\n",
                      {15, 33, "training.stages[0].memory", "unknown key 'memory'"});
  expect_config_error("    - {optimizer: lbfgs, steps: 5, linear_solver: dense_qr}\n",
                      {15, 36, "training.stages[0].linear_solver", "unknown key 'linear_solver'"});
  expect_config_error("    - {optimizer: adam, steps: 5, resample_every: 2}\n",
                      {15, 35, "training.stages[0].resample_every",
                       "unknown key 'resample_every'"});
  expect_config_error("    - {optimizer: lm, steps: 5, resample_every: -1}\n",
                      {15, 49, "training.stages[0].resample_every", "expected an integer in [0, "});
}

TEST(LevenbergMarquardtConfig, ResolvedConfigKeepsTheKeys) {
  const RunSetup setup = load_run(
      write_config(poisson_config(
          kSmallMlp, "{interior: 10, boundary: 4}",
          "    - {optimizer: lm, steps: 7, linear_solver: dense_normal_cholesky, initial_radius: 0.5}\n")),
      {});
  ASSERT_EQ(setup.training.stages.size(), 1u);
  const StageOptions& stage = setup.training.stages[0];
  EXPECT_EQ(stage.optimizer, "lm");
  EXPECT_EQ(stage.steps, 7);
  EXPECT_EQ(stage.options<LmStageOptions>().linear_solver, "dense_normal_cholesky");
  EXPECT_EQ(stage.options<LmStageOptions>().initial_radius, 0.5);
  const YAML::Node written = setup.training.to_yaml()["stages"][0];
  EXPECT_EQ(written["optimizer"].as<std::string>(), "lm");
  EXPECT_EQ(written["linear_solver"].as<std::string>(), "dense_normal_cholesky");
  EXPECT_EQ(written["initial_radius"].as<double>(), 0.5);
  EXPECT_FALSE(written["memory"]);
  EXPECT_FALSE(written["lr"]);

  const RunSetup defaults = load_run(
      write_config(poisson_config(kSmallMlp, "{interior: 10, boundary: 4}",
                                  "    - {optimizer: lm, steps: 7}\n")),
      {});
  EXPECT_EQ(defaults.training.stages[0].options<LmStageOptions>().backend, "own");
  EXPECT_EQ(defaults.training.stages[0].options<LmStageOptions>().linear_solver, "dense_normal_cholesky");
  EXPECT_EQ(defaults.training.stages[0].options<LmStageOptions>().initial_radius, 1e4);
}

}  // namespace
}  // namespace nfield::solvers
