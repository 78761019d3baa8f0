// SPDX-License-Identifier: MIT
//
// A run that goes wrong is never reported as one that went right: a diverging run stops at
// the first non-finite step with exit code 3 and keeps the last finite state; a stage that
// ends short of its steps says so; a run killed while it writes a checkpoint leaves the
// previous complete checkpoint or the new complete one, never a broken one.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "cli_test_support.h"
#include "fields/field_io.h"
#include "io/hdf5_file.h"

namespace nfield::apps::testing {
namespace {

// The unit square's Poisson problem, small and on one thread, with the given stages.
std::string unit_square_poisson(const std::string& training) {
  return poisson_config("{lower: [0, 0], upper: [1, 1]}",
                        "  threads: 1\n  batch: {interior: 64, boundary: 32}\n  log_every: 1\n" + training,
                        "{grid: [9, 9], png: false}");
}

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(read_text(path)); }

// The field of a checkpoint evaluated on a few points: all finite.
void expect_finite_field(const std::filesystem::path& checkpoint) {
  const io::H5Reader file(checkpoint);
  const fields::Field<float> field = fields::load_field<float>(file);
  EXPECT_TRUE(field.parameters().allFinite());
  const Eigen::MatrixXf x = Eigen::MatrixXf::Random(16, 2).array().abs();
  EXPECT_TRUE(field.values(x).allFinite());
}

// The example: a learning rate of 1e30 overflows the float Laplacian within a few
// steps. The run stops at that step, names it and the last finite loss, writes metrics with
// finished: false, and keeps (and evaluates) the last finite parameters.
TEST(DivergenceTest, StopsAtTheFirstNonFiniteStepAndKeepsTheLastFiniteState) {
  const auto dir = scratch_dir();
  write_text(dir / "p.yaml", unit_square_poisson("  stages:\n    - {optimizer: adam, steps: 200, lr: 1.0e30}\n"
                                            "    - {optimizer: lbfgs, steps: 10}\n"));
  const Outcome o = run_nfield({"run", (dir / "p.yaml").string(), "--out", (dir / "out").string()}, dir,
                               dir / "capture");
  ASSERT_EQ(o.code, 3) << describe(o);
  const nlohmann::json m = read_json(dir / "out" / "metrics.json");
  EXPECT_FALSE(m["finished"].get<bool>());
  const std::string stopped = m["stopped"];
  EXPECT_EQ(stopped.rfind("diverged: step ", 0), 0u) << stopped;
  const nlohmann::json& d = m["divergence"];
  const long step = d["step"];
  EXPECT_GE(step, 2);
  EXPECT_LT(step, 200);
  EXPECT_EQ(d["stage"], 0);
  EXPECT_EQ(d["optimizer"], "adam");
  EXPECT_EQ(d["last_finite_step"].get<long>(), step - 1);
  EXPECT_TRUE(std::isfinite(d["last_finite_loss"].get<double>()));
  // The losses reported are the kept parameters' (those of the last finite step).
  EXPECT_EQ(m["loss"].get<double>(), d["last_finite_loss"].get<double>());
  // Stopped at that step: the steps before it were taken, and no stage finished.
  EXPECT_EQ(m["steps"].get<long>(), step - 1);
  EXPECT_TRUE(m["stages"].empty());
  // The outputs come from the kept parameters: a finite error, never a NaN reported as 0.
  EXPECT_TRUE(m["rel_l2"].is_number()) << m.dump();
  EXPECT_TRUE(std::isfinite(m["max_abs_err"].get<double>()));
  EXPECT_NE(o.out.find("step " + std::to_string(step) + " (stage 1, adam): "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("is not finite; last finite loss"), std::string::npos) << o.out;
  expect_finite_field(dir / "out" / "checkpoint.h5");
  const Outcome eval = run_nfield({"eval", (dir / "out" / "checkpoint.h5").string(), "--grid", "5", "--out",
                                   (dir / "eval").string()},
                                  dir, dir / "capture");
  EXPECT_EQ(eval.code, 0) << describe(eval);
}

// restore_and_halve_lr goes back to the last finite state at half the rate, a bounded number
// of times: at 1e30 three halvings are not enough, so the run still stops (exit 3) after
// saying so three times; with enough retries the rate falls to where the steps stay finite.
TEST(DivergenceTest, RestoreAndHalveRetriesABoundedNumberOfTimes) {
  const auto dir = scratch_dir();
  const std::string stage = "  stages:\n    - {optimizer: adam, steps: 40, lr: 1.0e30}\n";
  write_text(dir / "three.yaml", unit_square_poisson("  on_divergence: restore_and_halve_lr\n" + stage));
  Outcome o = run_nfield({"run", (dir / "three.yaml").string(), "--out", (dir / "three").string()}, dir,
                         dir / "capture");
  ASSERT_EQ(o.code, 3) << describe(o);
  for (const char* retry : {"(retry 1 of 3)", "(retry 2 of 3)", "(retry 3 of 3)"})
    EXPECT_NE(o.out.find(retry), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("retry 4"), std::string::npos) << o.out;

  write_text(dir / "many.yaml",
             unit_square_poisson("  on_divergence: restore_and_halve_lr\n  divergence_retries: 100\n" + stage));
  o = run_nfield({"run", (dir / "many.yaml").string(), "--out", (dir / "many").string()}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json m = read_json(dir / "many" / "metrics.json");
  EXPECT_TRUE(m["finished"].get<bool>());
  EXPECT_EQ(m["steps"].get<long>(), 40);
  EXPECT_TRUE(std::isfinite(m["loss"].get<double>()));
  expect_finite_field(dir / "many" / "checkpoint.h5");
}

// An L-BFGS or LM stage that would start on a non-finite loss (here a source that is NaN on
// the whole domain) stops the run there, as Adam does, instead of ending as a failed stage.
TEST(DivergenceTest, CeresStagesStopWhereTheyWouldStartOnANonFiniteLoss) {
  const auto dir = scratch_dir();
  for (const std::string optimizer : {"lbfgs", "lm"}) {
    SCOPED_TRACE(optimizer);
    write_text(dir / "nan.yaml", "problem: pde\ndomain: {lower: [0], upper: [1]}\n"
                                 "equation: {residuals: [\"u_xx - sqrt(x - 2)\"]}\n"
                                 "field: {type: siren, hidden: [8]}\n"
                                 "training:\n  threads: 1\n  batch: {interior: 32}\n  stages:\n"
                                 "    - {optimizer: " + optimizer + ", steps: 10}\n    - {optimizer: adam, steps: 5}\n"
                                 "output: {grid: [9], png: false}\n");
    const Outcome o = run_nfield({"run", (dir / "nan.yaml").string(), "--out", (dir / optimizer).string()}, dir,
                                 dir / "capture");
    ASSERT_EQ(o.code, 3) << describe(o);
    const nlohmann::json m = read_json(dir / optimizer / "metrics.json");
    EXPECT_EQ(m["divergence"]["optimizer"], optimizer);
    EXPECT_EQ(m["divergence"]["step"], 1);
    EXPECT_EQ(m["divergence"]["what"], "loss term 'pde'");
    EXPECT_EQ(m["divergence"]["last_finite_step"], 0);
    EXPECT_TRUE(m["stages"].empty());
    EXPECT_NE(o.out.find("no step of this run had a finite loss"), std::string::npos) << o.out;
  }
}

// An L-BFGS stage in float ends when its steps no longer change the parameters (at the
// rounding of float), long before 20,000 iterations (about 600 here): metrics.json records the iterations it took, why it
// ended and Ceres' own words, and the progress output says so; the next stage still runs.
TEST(EarlyStopTest, AStageThatEndsEarlyIsReportedAsItHappened) {
  const auto dir = scratch_dir();
  write_text(dir / "p.yaml",
             "problem: poisson\n"
             "domain: {lower: [0, 0], upper: [1, 1]}\n"
             "equation: {source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\", exact: \"sin(pi*x)*sin(pi*y)\"}\n"
             "conditions:\n  - {on: boundary, type: dirichlet, value: \"0\"}\n"
             "field: {type: siren, hidden: [8], first_omega: 3}\n"
             "training:\n  precision: float\n  threads: 1\n  batch: {interior: 64, boundary: 32}\n"
             "  log_every: 1000\n"
             "  stages:\n    - {optimizer: adam, steps: 20, lr: 1.0e-2}\n"
             "    - {optimizer: lbfgs, steps: 20000}\n    - {optimizer: adam, steps: 5, lr: 1.0e-4}\n"
             "output: {grid: [9, 9], png: false}\n");
  const Outcome o = run_nfield({"run", (dir / "p.yaml").string(), "--out", (dir / "out").string()}, dir,
                               dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json m = read_json(dir / "out" / "metrics.json");
  ASSERT_EQ(m["stages"].size(), 3u);
  const nlohmann::json& adam = m["stages"][0];
  EXPECT_EQ(adam["iterations"], 20);
  EXPECT_EQ(adam["ended"], "completed");
  const nlohmann::json& lbfgs = m["stages"][1];
  EXPECT_EQ(lbfgs["steps"], 20000);
  const int iterations = lbfgs["iterations"];
  EXPECT_GT(iterations, 0);
  EXPECT_LT(iterations, 20000);
  EXPECT_TRUE(lbfgs["ended"] == "converged" || lbfgs["ended"] == "failed") << lbfgs.dump();
  EXPECT_FALSE(lbfgs["termination"].get<std::string>().empty());
  EXPECT_FALSE(lbfgs["message"].get<std::string>().empty());
  EXPECT_EQ(m["stages"][2]["iterations"], 5);
  EXPECT_EQ(m["steps"].get<long>(), 20 + iterations + 5);
  EXPECT_NE(o.out.find("stage 2 (lbfgs) ended after " + std::to_string(iterations) + " of 20000 iterations: " +
                       lbfgs["ended"].get<std::string>()),
            std::string::npos)
      << o.out;
}

// SIGKILL at random moments of a run that writes a checkpoint every step: whatever the
// moment, checkpoint.h5 is absent (killed before the first) or a whole checkpoint with the
// datasets of every other, and a run resumes from it.
TEST(CrashSafetyTest, KilledWhileCheckpointingLeavesAWholeCheckpoint) {
  const auto dir = scratch_dir();
  write_text(dir / "p.yaml", unit_square_poisson("  checkpoint_every: 1\n  stages:\n"
                                            "    - {optimizer: adam, steps: 100000, lr: 1.0e-3}\n"));
  std::mt19937 random(2026);
  std::uniform_int_distribution<int> wait_us(0, 200000);
  std::vector<std::string> names;  // the datasets of the first whole checkpoint seen
  std::filesystem::path kept;
  for (int kill_count = 0; kill_count < 50; ++kill_count) {
    SCOPED_TRACE("kill " + std::to_string(kill_count));
    // Two folders in turn: a run also starts over an older run's checkpoint.
    const auto out = dir / ("out" + std::to_string(kill_count % 2));
    {
      Child child({"run", (dir / "p.yaml").string(), "--out", out.string(), "--progress", "plain"}, dir,
                  dir / "stderr.txt");
      // Once the first step is reported its checkpoint is being written, and one follows
      // every step: a kill a random 0-200 ms later lands in or between writes.
      std::string line;
      while (child.read_line(line) && line.rfind("step ", 0) != 0) {
      }
      ASSERT_EQ(line.rfind("step ", 0), 0u) << "no progress line";
      std::this_thread::sleep_for(std::chrono::microseconds(wait_us(random)));
      kill(child.pid(), SIGKILL);
    }  // reaped
    const auto checkpoint = out / "checkpoint.h5";
    if (kill_count < 2 && !std::filesystem::exists(checkpoint)) continue;  // killed before the first
    ASSERT_TRUE(std::filesystem::exists(checkpoint));
    const io::H5Reader file(checkpoint);
    const std::vector<std::string> these = file.dataset_names();
    if (names.empty()) names = these;
    EXPECT_EQ(these, names);
    EXPECT_TRUE(file.has_attribute("/", "config"));
    EXPECT_GE(file.read_attribute<std::int64_t>("trainer", "global_step"), 1);
    expect_finite_field(checkpoint);
    kept = out;
  }
  ASSERT_FALSE(kept.empty());
  // The last one resumes (to a few more steps than it had).
  const io::H5Reader file(kept / "checkpoint.h5");
  const long reached = file.read_attribute<std::int64_t>("trainer", "global_step");
  const Outcome o = run_nfield({"run", (dir / "p.yaml").string(), "--out", (dir / "resumed").string(), "--resume",
                                (kept / "checkpoint.h5").string(), "--set",
                                "training.stages[0].steps=" + std::to_string(reached + 3), "--set",
                                "training.checkpoint_every=0"},
                               dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_EQ(read_json(dir / "resumed" / "metrics.json")["steps"].get<long>(), reached + 3);
}

}  // namespace
}  // namespace nfield::apps::testing
