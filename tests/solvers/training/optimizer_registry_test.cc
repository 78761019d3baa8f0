// SPDX-License-Identifier: MIT
//
// The optimizer registry from outside the library: a plain gradient-descent optimizer
// registered here trains a small Poisson problem through a config (its own key read
// strictly, written back, located errors); taken names are refused; an unknown name lists
// the valid ones; the typed options of the library's optimizers validate themselves.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "io/registry.h"
#include "solvers/training/optimizer.h"
#include "solvers/training/optimizers.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

struct DescentOptions {
  double rate = 0.01;
};

// θ ← θ − rate·∇L, new points every step as Adam draws them.
class GradientDescent final : public OptimizerOf<GradientDescent, DescentOptions> {
 public:
  void read(const io::ConfigNode& stage) override {
    options.rate = stage.get_or("rate", options.rate);
    stage.require("rate", options.rate > 0, "expected a step size > 0");
  }
  void write(YAML::Node& stage) const override { stage["rate"] = options.rate; }

  template <typename Scalar>
  bool run_stage(TrainingStage<Scalar>& stage) {
    auto& theta = stage.field().parameters();
    autodiff::Vector<Scalar> gradient(theta.size());
    while (stage.step() < stage.steps()) {
      if (stage.stop_requested()) return false;
      const auto start = std::chrono::steady_clock::now();
      stage.prepare_step();
      stage.step_gradient(gradient.data());
      theta -= static_cast<Scalar>(options.rate) * gradient;
      stage.finish_step(options.rate, std::chrono::duration<double, std::milli>(
                                          std::chrono::steady_clock::now() - start)
                                          .count());
    }
    return true;
  }
};

// Registered once per test program, before the first config is read.
void register_descent() {
  static const bool registered = [] {
    register_optimizer("gradient_descent", [] { return std::make_unique<GradientDescent>(); });
    return true;
  }();
  (void)registered;
}

std::string poisson_config(const std::string& stages) {
  return "problem: poisson\n"                                               // 1
         "domain: {lower: [0, 0], upper: [1, 1]}\n"                         // 2
         "equation:\n"                                                      // 3
         "  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n"                      // 4
         "  exact: \"sin(pi*x)*sin(pi*y)\"\n"                               // 5
         "conditions:\n"                                                    // 6
         "  - {on: boundary, type: dirichlet, value: \"0\", weight: 10}\n"  // 7
         "field: {type: mlp, activation: tanh, hidden: [16, 16]}\n"         // 8
         "training:\n"                                                      // 9
         "  seed: 5\n"                                                      // 10
         "  precision: double\n"                                            // 11
         "  threads: 1\n"                                                   // 12
         "  batch: {interior: 200, boundary: 60}\n"                         // 13
         "  stages:\n"                                                      // 14
         + stages +                                                         // 15…
         "output: {grid: [5, 5]}\n";
}

std::filesystem::path write_config(const std::string& text) {
  return testutil::write_config("optimizer_registry", text);
}

TEST(OptimizerRegistry, OptimizerFromOutsideTrainsThroughAConfig) {
  register_descent();
  const RunSetup setup =
      load_run(write_config(poisson_config("    - {optimizer: gradient_descent, steps: 200, rate: 0.001}\n")), {});
  ASSERT_EQ(setup.training.stages.size(), 1u);
  EXPECT_EQ(setup.training.stages[0].options<DescentOptions>().rate, 0.001);
  const YAML::Node written = setup.resolved["training"]["stages"][0];
  EXPECT_EQ(written["optimizer"].as<std::string>(), "gradient_descent");
  EXPECT_EQ(written["rate"].as<double>(), 0.001);

  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  double first_loss = NAN, last_loss = NAN;
  long reported = 0;
  Trainer<double>::Callbacks callbacks;
  callbacks.progress = [&](const Progress& p) {
    EXPECT_EQ(p.optimizer, "gradient_descent");
    EXPECT_EQ(p.step, ++reported);
    if (reported == 1) first_loss = p.loss;
    last_loss = p.loss;
  };
  ASSERT_TRUE(trainer.run(callbacks));
  EXPECT_EQ(trainer.step(), 200);
  EXPECT_EQ(reported, 200);
  ASSERT_TRUE(std::isfinite(first_loss));
  // Plain descent at this rate takes the loss down by well over half in 200 steps.
  EXPECT_LT(last_loss, 0.5 * first_loss) << "first " << first_loss << ", last " << last_loss;
  ASSERT_EQ(trainer.stage_losses().size(), 1u);
  EXPECT_EQ(trainer.stage_losses()[0], last_loss);
}

// The ETA of a progress line is the current stage's: its steps left at its rate. Later
// stages run other optimizers at other rates (an LM step can cost hundreds of L-BFGS steps),
// so they are counted, not timed.
TEST(TrainerProgress, EtaCoversTheCurrentStageAndCountsTheLaterOnes) {
  const RunSetup setup = load_run(write_config(poisson_config("    - {optimizer: adam, steps: 30, lr: 1.0e-3}\n"
                                                              "    - {optimizer: lbfgs, steps: 10}\n")),
                                  {});
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  long checked = 0;
  Trainer<double>::Callbacks callbacks;
  callbacks.progress = [&](const Progress& p) {
    const long stage_end = p.stage == 0 ? 30 : 40;
    EXPECT_EQ(p.later_stages, p.stage == 0 ? 1 : 0) << "step " << p.step;
    if (p.steps_per_second <= 0) return;
    EXPECT_NEAR(p.eta_seconds * p.steps_per_second, static_cast<double>(stage_end - p.step), 1e-9 * stage_end)
        << "step " << p.step;
    ++checked;
  };
  ASSERT_TRUE(trainer.run(callbacks));
  EXPECT_GT(checked, 20);
}

TEST(OptimizerRegistry, OutsideOptimizerKeysAreReadStrictly) {
  register_descent();
  // Line 15 is the stage; column 53 the value of rate, column 47 the unknown key.
  testutil::expect_located_error(
      write_config(poisson_config("    - {optimizer: gradient_descent, steps: 5, rate: -1}\n")),
      {15, 53, "training.stages[0].rate", "expected a step size > 0"});
  testutil::expect_located_error(
      write_config(poisson_config("    - {optimizer: gradient_descent, steps: 5, lr: 0.1}\n")),
      {15, 47, "training.stages[0].lr", "unknown key 'lr'"});
}

TEST(OptimizerRegistry, TakenNamesAreRefused) {
  register_descent();
  const auto factory = [] { return std::make_unique<GradientDescent>(); };
  EXPECT_THROW(register_optimizer("adam", factory), std::logic_error);
  EXPECT_THROW(register_optimizer("Gradient_Descent", factory), std::logic_error);
}

TEST(OptimizerRegistry, UnknownNameListsTheValidOnes) {
  register_descent();
  try {
    make_optimizer("sgd");
    ADD_FAILURE() << "no error";
  } catch (const UnknownNameError& e) {
    EXPECT_EQ(std::string(e.what()),
              "unknown optimizer 'sgd' (valid: adam, gradient_descent, lbfgs, lm)");
  }
  testutil::expect_located_error(
      write_config(poisson_config("    - {optimizer: sgd, steps: 5}\n")),
      {15, 19, "training.stages[0].optimizer",
       "expected one of adam, gradient_descent, lbfgs, lm; got 'sgd'"});
  EXPECT_NE(make_optimizer("LM"), nullptr);  // names are matched case-insensitively
}

TEST(OptimizerRegistry, TypedOptionsValidateThemselves) {
  const auto message = [](const auto& options) -> std::string {
    try {
      options.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message(AdamStageOptions{}), "");
  EXPECT_EQ(message(LbfgsStageOptions{}), "");
  EXPECT_EQ(message(LmStageOptions{}), "");
  EXPECT_EQ(message(AdamStageOptions{.lr = 0}), "adam.lr = 0: must be > 0");
  EXPECT_EQ(message(AdamStageOptions{.schedule = "linear"}),
            "adam.schedule = linear: must be constant, cosine or exponential");
  EXPECT_EQ(message(LbfgsStageOptions{.memory = 0}), "lbfgs.memory = 0: must be in [1, 1000]");
  EXPECT_EQ(message(LmStageOptions{.linear_solver = "svd"}),
            "lm.linear_solver = svd: must be dense_qr or dense_normal_cholesky");
  EXPECT_EQ(message(LmStageOptions{.initial_radius = 0}),
            "lm.initial_radius = 0: must be in [1e-12, 1e16]");
}

}  // namespace
}  // namespace nfield::solvers
