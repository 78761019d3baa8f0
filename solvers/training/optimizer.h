// SPDX-License-Identifier: MIT
//
// Optimizers: what runs one training stage. Each is an object of its own class, made by
// name from one registry (adam, lbfgs, lm in solvers/training/optimizers.cc; register_optimizer for
// code outside the library), and the trainer knows none of them by name.
//
// An optimizer reads its own keys of the stage's config (`optimizer` and `steps` are the
// trainer's) and writes them back for the resolved config; when its stage runs, the trainer
// hands it a TrainingStage: the loss and its gradient, per-term residuals for least squares,
// the parameters, and the bookkeeping of a step (counters, progress, checkpoints, stop
// requests, new points). Every step must end in TrainingStage::finish_step so that progress
// lines and checkpoints keep coming.
//
// A stage is read once into a template optimizer (StageOptions::settings); each run of the
// stage works on a copy of it (clone), so state such as Adam's moments belongs to one
// trainer, and a checkpoint keeps it through save/load.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "fields/field.h"
#include "io/config.h"
#include "io/hdf5_file.h"
#include "solvers/core/residual.h"
#include "solvers/training/communicator.h"

namespace nfield::solvers {

template <typename Scalar>
class Trainer;
template <typename Scalar>
class TrainedUnknowns;

// The trainer as one stage's optimizer sees it. Valid while the stage runs.
template <typename Scalar>
class TrainingStage {
 public:
  int index() const;          // 0-based, over the run's stages
  int steps() const;          // the stage's steps
  int step() const;           // steps of it done (a resumed stage starts past 0)
  fields::Field<Scalar>& field();
  // An inverse problem's unknown constants at θ's tail (solvers/training/trained_unknowns.h):
  // what an optimizer that forms its own residuals (LM) needs to read and differentiate them.
  TrainedUnknowns<Scalar>& unknowns();

  // The loss terms at their current points.
  std::size_t term_count() const;
  const std::string& term_name(std::size_t k) const;
  const TermPoints& points(std::size_t k) const;
  const autodiff::Matrix<Scalar>& points_in_scalar(std::size_t k) const;
  const Residual& residual(std::size_t k) const;
  const autodiff::StreamLayout& layout(std::size_t k) const;
  // w·λ: the term's weight times its balance weight (training.balance), held in this stage.
  double weight(std::size_t k) const;
  // The loss of term k at the step just taken, for progress lines and metrics.
  void set_term_loss(std::size_t k, double loss);

  // Σ_k w_k λ_k/N_k Σ‖r‖² at `params` and its gradient (overwritten); keeps the term losses.
  double loss_and_gradient(const Scalar* params, Scalar* gradient);

  // Per-step sampling of a first-order method, before each step: new points when they are
  // due (resample_every, or a training strategy such as RAR asks), then the strategies'
  // weights at the current parameters (causal weights).
  void prepare_step();
  // The gradient of that step at the field's parameters: loss_and_gradient, or the one a
  // strategy takes on its steps (training.balance: the terms' gradients one by one).
  void step_gradient(Scalar* gradient);

  // A method that keeps one objective over many iterations (a line search, a least-squares
  // problem) runs in segments between which the objective may change:
  void draw_points();               // new points for every term
  // The strategies' weights at the current parameters and points (training.causal); no-op
  // when none has any.
  void update_weights();
  // Iterations per segment: the whole stage, or fewer where the points change
  // (resample_every of the stage, adaptive.every) or, when the optimizer calls update_weights
  // between segments (`reweighted`), the weights do (causal.every).
  int segment_length(int resample_every, bool reweighted) const;
  // Whether the stage is over after a segment that began at step segment_start: all its steps
  // are taken, or the segment ended `early` (no decrease found) and either the stage has no
  // further segments or the segment made no step at all.
  bool ends_after_segment(int segment, int segment_start, bool early) const;
  // Between segments: the strategies' changes of the points (RAR refines its set), then a
  // new point set (resample_every > 0) or the stage's own points with the new RAR set.
  void renew_points(int resample_every);

  // The ranks the trainer splits each step over (solvers/training/trainer.h); one for a
  // single process.
  Communicator& communicator() const;

  // Wall seconds since the stage (or its resumed part) began (rank 0's, on every rank).
  double seconds() const;
  // A wall-time budget of the stage, for the ETA of progress lines (0: none).
  void set_time_budget(double seconds);
  bool stop_requested() const;
  // After each step: counts it, records its time, reports progress (at the learning rate
  // shown, 0 for none) and writes a checkpoint when one is due.
  void finish_step(double learning_rate, double milliseconds);
  // Divergence. After a loss (and its gradient, if not null) has been evaluated at the field's
  // parameters: whether every term's loss and the gradient are finite. When not, the
  // divergence is recorded (the step, the first non-finite term, the last finite loss).
  bool check_finite(const Scalar* gradient);
  // After an update: whether the field's parameters are finite (recorded as above if not).
  bool check_finite_parameters();
  // After a recorded divergence, once the optimizer has put back its last parameters whose
  // loss was finite: whether to go on from there at half the learning rate
  // (training.on_divergence: restore_and_halve_lr, while retries are left; says so in a
  // line). When false, the optimizer returns false and the run ends, reporting the divergence.
  bool retry_after_divergence();
  // A stage that ends before its steps are taken: `ended` is converged, failed or
  // time_budget; `termination` and `message` Ceres' (or empty). The stage counts the
  // iterations it took, and the next one starts there.
  void end_early(std::string ended, std::string termination, std::string message);
  // How a stage that took all its steps ended in the optimizer's own terms (Ceres'
  // termination type and message), for its report.
  void set_termination(std::string termination, std::string message);

 private:
  friend class Trainer<Scalar>;
  explicit TrainingStage(Trainer<Scalar>& trainer) : trainer_(trainer) {}
  Trainer<Scalar>& trainer_;
};

// The size of the problem a run trains, each part computed when first asked (building the
// field to count its parameters can take a while).
struct ProblemSize {
  // Σ points × residual components over the terms, at the largest point sets the run draws.
  std::function<double()> residual_rows;
  std::function<Eigen::Index()> parameters;
  // The first loss term whose points come in groups or carry per-point tangents (a periodic
  // condition, a pixel's ray); empty when every term is per point.
  std::function<std::string()> grouped_term;
};

class Optimizer {
 public:
  virtual ~Optimizer() = default;

  // Reads this optimizer's keys of one stage (errors are io::ConfigError at the key).
  virtual void read(const io::ConfigNode& /*stage*/) {}
  // Writes them back into the stage's node of the resolved config.
  virtual void write(YAML::Node& /*stage*/) const {}
  // Before training: why the stage cannot run a problem of this size (a message such as "an
  // lm stage here would need a Jacobian of …"), or empty when it can.
  virtual std::string refuse(const ProblemSize& /*size*/) const { return {}; }

  // Runs the rest of the stage. Returns false when stopped by a stop request, or by a
  // divergence that TrainingStage::check_finite recorded (with the field put back at its last
  // parameters whose loss was finite).
  virtual bool run(TrainingStage<float>& stage) = 0;
  virtual bool run(TrainingStage<double>& stage) = 0;

  // State that must outlive an interruption (into the checkpoint group `group`).
  virtual void save(io::H5Writer& /*file*/, const std::string& /*group*/) const {}
  virtual void load(const io::H5Reader& /*file*/, const std::string& /*group*/) {}

  // A fresh copy with the same options, for one run of the stage.
  virtual std::unique_ptr<Optimizer> clone() const = 0;
};

// The options of an optimizer, as a typed struct (StageOptions::options<Options>() reads
// them).
template <class Options>
class OptimizerWithOptions : public Optimizer {
 public:
  Options options;
};

struct NoOptions {};

// Implements run and clone from Derived's member template
// `template <typename Scalar> bool run_stage(TrainingStage<Scalar>&)` and its copy.
template <class Derived, class Options = NoOptions>
class OptimizerOf : public OptimizerWithOptions<Options> {
 public:
  bool run(TrainingStage<float>& stage) final {
    return static_cast<Derived&>(*this).run_stage(stage);
  }
  bool run(TrainingStage<double>& stage) final {
    return static_cast<Derived&>(*this).run_stage(stage);
  }
  std::unique_ptr<Optimizer> clone() const final {
    return std::make_unique<Derived>(static_cast<const Derived&>(*this));
  }
};

using OptimizerFactory = std::function<std::unique_ptr<Optimizer>()>;

// Adds an optimizer to the registry (`training.stages[i].optimizer: NAME`). Throws
// std::logic_error if the name is taken.
void register_optimizer(std::string_view name, OptimizerFactory factory);
// A new optimizer of that name with default options; UnknownNameError listing the valid
// names otherwise.
std::unique_ptr<Optimizer> make_optimizer(std::string_view name);
// Sorted, lower-case.
std::vector<std::string> optimizer_names();

}  // namespace nfield::solvers
