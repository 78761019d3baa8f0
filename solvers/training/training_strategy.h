// SPDX-License-Identifier: MIT
//
// Training strategies: what some runs do to the loss or to where its points lie, and others
// not. The trainer (solvers/training/trainer.h) knows optimizers, stages, sampling and
// checkpoints; each strategy is an object it holds and calls at fixed moments, and it knows
// none of them by name. The library's three, each read from its own key of `training:` by its
// registry entry (strategy_settings.h) and made by make_training_strategies
// (training_strategies.cc), act on the problem's residual term, given at construction:
//
//   causal     CausalWeighting     (causal_weighting.h): per-point weights of the residual
//                                  term, exp(−ε · loss of the earlier time slices)
//   balance    GradientBalancing   (gradient_balancing.h): a factor λₖ on each term's loss,
//                                  from the gradient scales (grad_norm)
//   adaptive   AdaptiveRefinement  (adaptive_refinement.h): an extra point set where ‖r‖ is
//                                  largest, behind the residual term's drawn points (RAR)
//
// and one made from the field rather than `training:`, added last by the trainer for an acorn
// field (make_block_allocation): BlockAllocation (block_allocation.h), ACORN's reallocation
// of its blocks and per-block sampling.
//
// The loss a first-order step sees is then
//     L = Σₖ wₖ λₖ / Nₖ Σₙ aₖₙ ‖rₖ(xₙ)‖²,
// wₖ the term's fixed weight, λₖ the product of the strategies' loss_scale (1 by default), aₖₙ
// the point weights of the first strategy that gives some (none: 1).
//
// Pitfalls. A strategy's state must be in its save/load, or a resumed run is not bit for bit
// the uninterrupted one. Anything it draws must go through StrategyView::sample (the
// trainer's engine and the term's quasi-random sequence, in a fixed order). With several
// ranks every rank runs every hook on the same whole point set, so the hooks must be
// deterministic; only term_loss splits work, and its caller sums over the ranks. The hooks
// run in the order of the strategies in the trainer (causal, balance, adaptive), which is
// also the order of their metrics.
#pragma once

#include <climits>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "autodiff/streams.h"
#include "fields/field.h"
#include "io/hdf5_file.h"
#include "solvers/core/residual.h"

namespace nfield::solvers {

class Communicator;
class Problem;
struct TrainingOptions;

// The trainer as a strategy sees it, valid during a hook. An interface, so that a test can
// run a strategy on terms of its own (tests/solvers/training/training_strategy_test.cc).
template <typename Scalar>
class StrategyView {
 public:
  virtual ~StrategyView() = default;

  virtual long step() const = 0;  // steps done, over all stages
  virtual double term_weight(std::size_t k) const = 0;  // the fixed wₖ
  virtual const TermPoints& points(std::size_t k) const = 0;
  virtual Eigen::Index parameter_count() const = 0;
  virtual Communicator& communicator() const = 0;

  // n new points for term k, drawn as the trainer draws (its engine, the term's sequence).
  virtual TermPoints sample(std::size_t k, Eigen::Index n) = 0;
  // ‖r‖² of each residual row of term k at the current parameters, at its current points or
  // at `points`: a forward pass only, on this rank, over all the points.
  virtual Eigen::VectorXd squared_residuals(std::size_t k) const = 0;
  virtual Eigen::VectorXd squared_residuals(std::size_t k, const TermPoints& points) const = 0;
  // Replaces term k's point coordinates (groups and tangents stay) and rebuilds its residual.
  virtual void replace_points(std::size_t k, Eigen::MatrixXd x) = 0;
  // This rank's share of term k's loss at the current parameters with the fixed `weight`
  // (and the point weights), its gradient written into `gradient` (zeroed by the caller).
  virtual double term_loss(std::size_t k, double weight, Scalar* gradient) = 0;
  // The loss of term k at the step just taken, for progress lines and metrics.
  virtual void set_term_loss(std::size_t k, double loss) = 0;
  // The field being trained, at its current parameters (null: a view without one, as the
  // tests' views of bare terms).
  virtual const fields::Field<Scalar>* field() const { return nullptr; }
};

template <typename Scalar>
class TrainingStrategy {
 public:
  virtual ~TrainingStrategy() = default;

  // -- points
  // Before a first-order step draws (or keeps) its points: true when the step must draw new
  // ones, as after RAR grew its set.
  virtual bool before_step(StrategyView<Scalar>& /*view*/) { return false; }
  // Term k's points were just drawn; they may be added to.
  virtual void points_drawn(std::size_t /*k*/, TermPoints& /*points*/) {}
  // Between two segments of a stage that keeps its points over many iterations (L-BFGS,
  // LM), before the trainer draws new points (`redraw`) or keeps those it has.
  virtual void between_segments(StrategyView<Scalar>& /*view*/, bool /*redraw*/) {}
  // The most iterations such a segment may run; `reweighted`: the optimizer calls
  // update_weights between segments (L-BFGS does, LM does not).
  virtual int segment_limit(bool /*reweighted*/) const { return INT_MAX; }

  // -- the loss
  // Recomputes what depends on the parameters at the current points (causal weights): before
  // each first-order step, once its points are in place, and at each L-BFGS segment start.
  virtual void update_weights(StrategyView<Scalar>& /*view*/) {}
  // λₖ, the factor on term k's weighted loss.
  virtual double loss_scale(std::size_t /*k*/) const { return 1; }
  // aₙ for the points of term k (one per point), or null for none.
  virtual const Eigen::VectorXd* point_weights(std::size_t /*k*/,
                                               const TermPoints& /*points*/) const {
    return nullptr;
  }
  // Takes the gradient of a first-order step at the field's parameters (true), or leaves it
  // to the trainer (false). The term losses must be set, summed over the ranks.
  virtual bool step_gradient(StrategyView<Scalar>& /*view*/, Scalar* /*gradient*/) { return false; }

  // -- reporting and checkpoints
  // Figures for metrics.json, and the shorter ones shown in progress lines.
  virtual void metrics(std::vector<std::pair<std::string, double>>& /*out*/) const {}
  virtual void progress(std::vector<std::pair<std::string, double>>& /*out*/) const {}
  // State a resumed run needs, as datasets under `group` (the trainer's).
  virtual void save(io::H5Writer& /*file*/, const std::string& /*group*/) const {}
  virtual void load(const io::H5Reader& /*file*/, const std::string& /*group*/) {}
};

template <typename Scalar>
using TrainingStrategies = std::vector<std::unique_ptr<TrainingStrategy<Scalar>>>;

// The strategies `options` asks for, in hook order, acting on the problem's residual term
// (term_names: the trainer's terms). std::invalid_argument when the problem lacks what one
// needs (a residual term; a time axis for causal).
template <typename Scalar>
TrainingStrategies<Scalar> make_training_strategies(const TrainingOptions& options,
                                                    const Problem& problem,
                                                    const std::vector<std::string>& term_names);

}  // namespace nfield::solvers
