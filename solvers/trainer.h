// SPDX-License-Identifier: MIT
//
// The training loop: optimizer stages run one after another over a problem's loss terms.
//
//   adam   each step draws new points for every term (every `resample_every` steps),
//          sums the terms' parameter gradients (one chunked forward/reverse pass per term)
//          and takes one Adam step at the stage's scheduled learning rate.
//   lbfgs  draws one point set per term and minimizes the summed loss on it with Ceres'
//          L-BFGS (ceres::GradientProblemSolver), one step per Ceres iteration.
//   lm     draws one point set per term and minimizes the same loss as a least-squares
//          problem with Ceres' Levenberg–Marquardt (ceres::Problem, one parameter block θ
//          in double, one cost function per loss term whose N·C residuals are √(w/N)·r at
//          the term's points, so Ceres' ½Σf² is half the loss). Jacobians come from the
//          reverse pass per point (Sequential::residuals_and_jacobian), in the training
//          scalar, converted to double. A dense linear solver (the stage's linear_solver)
//          factors the (Σ N·C) × P Jacobian: memory and time grow as N·P and N·P², which
//          suits small fields (P up to a few thousand) and a few thousand points. One step
//          per Ceres iteration, a rejected step included.
//
// A stage that stops early because its optimizer cannot decrease the loss further
// (converged) counts as finished, with all its steps.
//
// A run is reproducible from its seed and thread count. The whole state (parameters, Adam
// moments and step, stage and step counters, random engine, current points) is saved by
// save_state and restored by load_state, so an interrupted Adam run resumed from its
// checkpoint ends with the same parameters, bit for bit, as one never interrupted.
// (An L-BFGS or LM stage restarts its history, and draws new points, when resumed.)
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fields/field.h"
#include "io/hdf5_file.h"
#include "solvers/adam.h"
#include "solvers/problem.h"
#include "solvers/training_options.h"

namespace nfield::solvers {

struct Progress {
  int stage = 0;
  std::string optimizer;
  long step = 0;         // steps done, over all stages
  long total_steps = 0;
  double learning_rate = 0;
  double loss = 0;
  std::vector<std::string> term_names;
  std::vector<double> term_losses;
  double steps_per_second = 0;
  double eta_seconds = 0;
};

template <typename Scalar>
class Trainer {
 public:
  struct Callbacks {
    std::function<bool()> stop_requested;           // polled every step
    std::function<void(const Progress&)> progress;  // after every step
    std::function<void()> checkpoint;               // every checkpoint_every steps
  };

  Trainer(const Problem& problem, fields::Field<Scalar>& field, TrainingOptions options);
  ~Trainer();

  // Runs the remaining stages. Returns false when stopped by stop_requested.
  bool run(const Callbacks& callbacks);

  const std::vector<std::string>& term_names() const { return names_; }
  // Loss of each term at the last step (weighted).
  const std::vector<double>& term_losses() const { return losses_; }
  long step() const { return global_step_; }
  const std::vector<double>& step_milliseconds() const { return step_ms_; }
  // Final loss after each finished stage, in order.
  const std::vector<double>& stage_losses() const { return stage_losses_; }

  void save_state(io::H5Writer& file) const;
  void load_state(const io::H5Reader& file);

 private:
  void resample();
  double loss_and_gradient(const Scalar* params, Scalar* gradient);
  bool run_adam(const StageOptions& stage, const Callbacks& callbacks);
  bool run_lbfgs(const StageOptions& stage, const Callbacks& callbacks);
  bool run_lm(const StageOptions& stage, const Callbacks& callbacks);
  // After a Ceres iteration has been accepted or rejected: parameters, step counters,
  // progress and checkpoints. Returns false when a stop is requested.
  bool finish_ceres_step(const StageOptions& stage, const Callbacks& callbacks, double& last);
  void report(const Callbacks& callbacks, const StageOptions& stage, double lr);

  const Problem& problem_;
  fields::Field<Scalar>& field_;
  TrainingOptions options_;
  std::vector<LossTerm> terms_;
  std::vector<std::string> names_;
  std::vector<autodiff::StreamLayout> layouts_;
  std::vector<Eigen::MatrixXd> points_;
  std::vector<autodiff::Matrix<Scalar>> points_scalar_;
  std::vector<std::unique_ptr<Residual>> residuals_;
  std::vector<double> losses_, stage_losses_, step_ms_;
  std::unique_ptr<Adam<Scalar>> adam_;
  Random rng_;
  int stage_ = 0;
  int stage_step_ = 0;
  long global_step_ = 0;
  double started_ = 0;
  long started_step_ = 0;
};

}  // namespace nfield::solvers
