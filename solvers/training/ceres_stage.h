// SPDX-License-Identifier: MIT
//
// What the stages that run Ceres (lbfgs, lm with backend: ceres) share: the callback that
// turns each Ceres iteration into a trainer step, and the report of how the stage ended.
#pragma once

#include <ceres/iteration_callback.h>
#include <ceres/types.h>

#include <chrono>
#include <functional>
#include <string>

#include "solvers/training/optimizer.h"

namespace nfield::solvers {

inline double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

class StepCallback final : public ceres::IterationCallback {
 public:
  using OnStep = std::function<bool(const ceres::IterationSummary&)>;
  explicit StepCallback(OnStep on_step) : on_step_(std::move(on_step)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) return ceres::SOLVER_CONTINUE;
    return on_step_(summary) ? ceres::SOLVER_CONTINUE : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  OnStep on_step_;
};

// After an iteration has been accepted or rejected: its time since the last, the step
// counters, progress and checkpoints. Returns false when a stop is requested.
template <typename Scalar>
bool finish_iteration(TrainingStage<Scalar>& stage, double& last) {
  const double t = now_seconds();
  stage.finish_step(0.0, 1e3 * (t - last));
  last = t;
  return !stage.stop_requested();
}

// The report of a stage: why it ended, when short of its steps (CONVERGENCE: no decrease
// found; FAILURE: the line search or the linear solver gave up). `termination` is Ceres' name
// (ceres::TerminationTypeToString) or the own LM's, which uses the same names.
template <typename Scalar>
void end_stage(TrainingStage<Scalar>& stage, const std::string& termination, const std::string& message) {
  if (stage.step() >= stage.steps()) stage.set_termination(termination, message);
  else stage.end_early(termination == "FAILURE" ? "failed" : "converged", termination, message);
}

}  // namespace nfield::solvers
