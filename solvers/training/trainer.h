// SPDX-License-Identifier: MIT
//
// The training loop: optimizer stages run one after another over a problem's loss terms.
// Each stage's optimizer is an object made from the optimizer registry
// (solvers/training/optimizer.h; adam, lbfgs and lm are described in solvers/training/optimizers.h); the
// trainer runs it through a TrainingStage and knows none by name.
//
// A stage that stops short of its steps (its optimizer converged or failed, or its time budget
// ran out) is over: the next stage starts there, and the stage's report (StageEnd) says how
// many iterations it took and why it ended. A loss, gradient or update that is not finite
// ends the run (Divergence), with the field at the last parameters whose loss was finite,
// unless training.on_divergence retries from there at half the learning rate.
//
// A run is reproducible from its seed and thread count. The whole state (parameters, Adam
// moments and step, stage and step counters, random engine, current points) is saved by
// save_state and restored by load_state, so an interrupted Adam run resumed from its
// checkpoint ends with the same parameters, bit for bit, as one never interrupted.
// (An L-BFGS or LM stage restarts its history, and draws new points, when resumed.)
//
// training.sampler (solvers/sampling/random.h) hooks in here: each term draws through its own
// quasi-random sequence, whose counts are part of save_state. What some runs do to the loss
// or to its points (training.adaptive, balance, causal) are training strategies
// (solvers/training/training_strategy.h), made from the options and called at fixed moments
// of a step; the trainer knows none of them by name, and their state goes into save_state
// too, so resumed runs still match uninterrupted ones.
//
// Data parallelism (solvers/training/communicator.h): with a communicator of R > 1 ranks,
// every rank runs this same trainer on the same points (drawn from the same seeded stream,
// so no per-rank streams are needed); each loss term's passes run over the rank's contiguous
// share of the term's residual rows (points, or groups of points), scaled by the whole
// batch's N, and the term losses and the gradient are summed over the ranks before the
// optimizer sees them: Adam's step, L-BFGS' line search and LM's Jacobian (its rows gathered
// from the ranks) are the same on every rank, and so are the parameters after it. What reads
// the clock or a signal (time budgets, stop requests) is decided on rank 0 or on any rank
// for all. Every rank repeats the drawing of points (and what a problem updates as it
// draws, such as AutoInt's sampling network) and the strategies' hooks on the whole set:
// same inputs, same thread count, same bits. A checkpoint of an R-rank run records R,
// and load_state refuses another R: the order of the sums, and so the bits of the run,
// depend on it. R = 1 (and a build without MPI) runs as before.
#pragma once

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fields/field.h"
#include "io/hdf5_file.h"
#include "solvers/training/communicator.h"
#include "solvers/training/loss_balancing.h"
#include "solvers/training/optimizer.h"
#include "solvers/core/problem.h"
#include "solvers/training/training_options.h"
#include "solvers/training/trained_unknowns.h"
#include "solvers/training/training_strategy.h"

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
  double steps_per_second = 0;  // over the current stage so far
  // The current stage's remaining steps at that rate (or its time budget, if sooner). Later
  // stages are not in it: their optimizers' rates are unknown until they run, and one
  // stage's rate says nothing about another's (an LM step can take 200 L-BFGS steps' time).
  double eta_seconds = 0;
  int later_stages = 0;  // stages after the current one
  std::vector<std::pair<std::string, double>> extras;  // e.g. the minimum causal weight
  // Per loss term, of its last batch: the points, and the groups of them (rays; 0: none).
  std::vector<Eigen::Index> term_points, term_groups;
};

// How a stage ended, for progress lines and metrics.json.
struct StageEnd {
  int iterations = 0;              // steps taken (a resumed stage's include those before it)
  std::string ended = "completed"; // completed | converged | failed | time_budget
  std::string termination;         // Ceres' termination type (CONVERGENCE, FAILURE, …); "" for Adam
  std::string message;             // Ceres' message, or why the stage ended early
};

// The step at which a run went non-finite.
struct Divergence {
  long step = 0;          // counted as progress lines count (the first step of a run is 1)
  int stage = 0;          // 0-based
  std::string optimizer;
  std::string what;       // "loss term 'interior'", "the gradient", "the parameters after the update"
  long last_finite_step = 0;  // the last step whose loss was finite (0: none in this run)
  double last_finite_loss = std::numeric_limits<double>::quiet_NaN();
  // One line: "step 12 (stage 1, adam): loss term 'interior' is not finite; last finite loss
  // 3.1e+05 at step 11".
  std::string describe() const;
};

template <typename Scalar>
class Trainer {
 public:
  struct Callbacks {
    std::function<bool()> stop_requested;           // polled every step
    std::function<void(const Progress&)> progress;  // after every step
    // When a stage starts, with the counters and losses so far (a stage's first step can be
    // long: a Levenberg–Marquardt Jacobian).
    std::function<void(const Progress&)> stage_begins;
    std::function<void()> checkpoint;               // every checkpoint_every steps
    // After each stage: the error against the exact solution then (NaN: none), kept per
    // stage in stage_errors() and in the checkpoint.
    std::function<double()> stage_error;
    // A line to show beside the progress lines: why a stage ended early, a retry after a
    // non-finite step.
    std::function<void(const std::string&)> notice;
    // Before each draw of new points, with the steps done and the trainer's engine: where a
    // problem that samples where the field is updates what its draws read
    // (SamplesWithSolution, solvers/core/problem_capabilities.h). Every rank's run needs it.
    std::function<void(long step, Random& rng)> before_draw;
  };

  // `communicator` (not owned; null: world_communicator()) splits each step over its ranks.
  Trainer(const Problem& problem, fields::Field<Scalar>& field, TrainingOptions options,
          Communicator* communicator = nullptr);
  ~Trainer();

  // The training loss Σ_k w_k/N_k Σ‖r‖² at `params` and its gradient (overwritten), on the
  // current points (drawn first when there are none yet), summed over the ranks: one step's
  // loss and gradient, for checks of the data-parallel split.
  double loss_and_gradient_at(const Scalar* params, Scalar* gradient);
  Communicator& communicator() const { return communicator_; }

  // Runs the remaining stages. Returns false when stopped by stop_requested or by a
  // divergence (divergence() tells which; the field then holds the last parameters whose loss
  // was finite).
  bool run(const Callbacks& callbacks);
  const std::optional<Divergence>& divergence() const { return watch_.divergence; }

  const std::vector<std::string>& term_names() const { return names_; }
  // Loss of each term at the last step (weighted); after a divergence, at the last step
  // whose loss was finite.
  const std::vector<double>& term_losses() const { return losses_; }
  long step() const { return global_step_; }
  // Stages still to run: none after a finished run (resuming it trains nothing more unless
  // the config adds a stage).
  int remaining_stages() const { return std::max(0, static_cast<int>(options_.stages.size()) - stage_); }
  const std::vector<double>& step_milliseconds() const { return step_ms_; }
  // Final loss after each finished stage, in order.
  const std::vector<double>& stage_losses() const { return stage_losses_; }
  const std::vector<double>& stage_errors() const { return stage_errors_; }
  // Wall seconds of each finished stage (NaN for stages finished before a resume).
  const std::vector<double>& stage_seconds() const { return stage_seconds_; }
  // How each finished stage ended (iterations actually taken, why it ended).
  const std::vector<StageEnd>& stage_ends() const { return stage_ends_; }

  // The strategies' figures, for metrics.json, in their order.
  std::vector<std::pair<std::string, double>> extra_metrics() const;
  const Eigen::MatrixXd& points(size_t term) const { return terms_[term].points.x; }
  // The unknown constants' trajectory (inactive without unknowns).
  const TrainedUnknowns<Scalar>& unknowns() const { return unknowns_; }
  // The strategy of type T (such as CausalWeighting<Scalar>), or null when the run has none.
  template <class T>
  const T* strategy() const {
    for (const auto& s : strategies_)
      if (const T* t = dynamic_cast<const T*>(s.get())) return t;
    return nullptr;
  }
  // λ of each term: the product of the strategies' loss scales (1 without training.balance).
  std::vector<double> balance_weights() const;

  void save_state(io::H5Writer& file) const;
  void load_state(const io::H5Reader& file);

 private:
  friend class TrainingStage<Scalar>;
  class View;  // the StrategyView of this trainer

  // One loss term as the trainer holds it: the problem's term and its stream layout, the
  // points of the current step (in double, and in Scalar for the passes), the residual built
  // on them (null before the first draw) and, for a quasi-random sampler, its own sequence.
  struct TermState {
    LossTerm term;
    autodiff::StreamLayout layout;
    TermPoints points{};
    autodiff::Matrix<Scalar> x{};
    autodiff::Matrix<Scalar> tangents{};  // empty: the spec's tangents
    std::unique_ptr<Residual> residual{};
    std::optional<UnitSequence> sequence{};
  };
  // Where the run last had a finite loss, for a divergence's report and its retries.
  struct FiniteWatch {
    std::optional<Divergence> divergence;  // set when a step went non-finite
    long last_finite_step = 0;
    std::vector<double> last_finite_losses;  // per term, at last_finite_step (empty: none yet)
    int retries = 0;                         // taken so far (training.on_divergence)
  };
  bool drawn() const {
    return std::all_of(terms_.begin(), terms_.end(), [](const TermState& t) { return t.residual != nullptr; });
  }

  void resample();
  // n new points of term k, through its sequence.
  TermPoints sample(size_t k, Eigen::Index n);
  void set_points(size_t k);  // the Scalar copies and the residual of term k's points
  double loss_scale(size_t k) const;
  double loss_and_gradient(const Scalar* params, Scalar* gradient);
  // This rank's part of term k's loss (the whole of it with one rank).
  double term_loss(size_t k, const Scalar* params, double weight, Scalar* gradient);
  // Sums the term losses and `gradient` over the ranks.
  void sum_over_ranks(Scalar* gradient);
  bool parallel() const { return communicator_.size() > 1; }
  Eigen::VectorXd squared_residuals(size_t k, const Eigen::MatrixXd& x, const Residual& r) const;
  // Tells the field and the terms that stage_ starts and rebuilds the residuals of the terms
  // that listen.
  void begin_stage();
  // See TrainingStage (solvers/training/optimizer.h).
  void prepare_step();
  void step_gradient(Scalar* gradient);
  int segment_length(int resample_every, bool reweighted) const;
  bool ends_after_segment(int segment, int segment_start, bool early) const;
  void renew_points(int resample_every);
  void finish_step(double learning_rate, double milliseconds);
  void update_weights();
  Progress progress(double lr) const;
  // See TrainingStage: divergence checks and retries, early ends.
  bool check_finite(const Scalar* gradient);
  bool check_finite_parameters();
  bool retry_after_divergence();
  void record_divergence(std::string what);
  void notice(const std::string& line) const;

  const Problem& problem_;
  fields::Field<Scalar>& field_;
  Communicator& communicator_;
  TrainingOptions options_;
  std::vector<TermState> terms_;
  std::vector<std::string> names_;  // the terms' names, for term_names()
  std::vector<double> losses_, stage_losses_, stage_errors_, stage_seconds_, step_ms_;
  std::vector<StageEnd> stage_ends_;
  StageEnd stage_end_;  // of the current stage, filled in as it ends
  FiniteWatch watch_;
  std::unique_ptr<Optimizer> optimizer_;  // of the current stage, while it runs or resumes
  const Callbacks* callbacks_ = nullptr;  // of the current run()
  double time_budget_ = 0;                // of the current stage (TrainingStage::set_time_budget)
  Random rng_;
  int stage_ = 0;
  int stage_step_ = 0;
  long global_step_ = 0;
  double stage_started_ = 0;     // wall clock and global step at the start of the stage
  long stage_started_step_ = 0;  // (or of the resumed part of it)
  TrainingStrategies<Scalar> strategies_;
  TrainedUnknowns<Scalar> unknowns_;  // an inverse problem's unknown constants (θ's tail)
};

}  // namespace nfield::solvers
