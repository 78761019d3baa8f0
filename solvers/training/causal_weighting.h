// SPDX-License-Identifier: MIT
//
// training.causal (Wang, Sankaran, Perdikaris 2022; its options in causal_options.h,
// its registry entry, make_causal_settings, in causal_weighting.cc): the residual term's points are grouped into M equal slices of [t0, t1],
// and point n of slice i is weighted by
//     aₙ = N cᵢ / (M nᵢ),   cᵢ = exp(−ε Σ_{k<i} Lₖ),   Lₖ the mean ‖r‖² over slice k,
// so that the term's loss w/N Σ aₙ ‖rₙ‖² is (w/M) Σᵢ cᵢ Lᵢ: a slice is trained once the ones
// before it fit, and the solution is learned forward in time.
//
// The cᵢ are constants of each gradient (the loss does not differentiate them), recomputed
// at the current parameters before every Adam step and at the start of every L-BFGS segment
// (at most causal.every iterations: a line search needs one objective). LM stages do not
// apply them.
//
// Pitfalls. The weights belong to one point set: when the term's points change before the
// next update (a resumed run, whose checkpoint holds the cᵢ but not the aₙ), point_weights
// gives none rather than weights of other points. Only the cᵢ go into the checkpoint
// (trainer/causal_weights); the aₙ are recomputed from them and the points.
#pragma once

#include "solvers/training/causal_options.h"
#include "solvers/training/loss_balancing.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

template <typename Scalar>
class CausalWeighting final : public TrainingStrategy<Scalar> {
 public:
  // `term`: the residual term; its points' time is column `time_column`, in [t0, t1].
  CausalWeighting(const CausalOptions& options, std::size_t term, int time_column, double t0,
                  double t1);

  int segment_limit(bool reweighted) const override;
  void update_weights(StrategyView<Scalar>& view) override;
  const Eigen::VectorXd* point_weights(std::size_t k, const TermPoints& points) const override;
  void metrics(std::vector<std::pair<std::string, double>>& out) const override;
  void progress(std::vector<std::pair<std::string, double>>& out) const override;
  void save(io::H5Writer& file, const std::string& group) const override;
  void load(const io::H5Reader& file, const std::string& group) override;

  // The weights of the last update (empty before the first).
  const CausalWeights& weights() const { return weights_; }

 private:
  CausalOptions options_;
  std::size_t term_;
  int time_column_;
  double t0_, t1_;
  CausalWeights weights_;
};

}  // namespace nfield::solvers
