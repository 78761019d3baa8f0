// SPDX-License-Identifier: MIT
//
// training.balance: grad_norm (learning-rate annealing, Wang, Teng, Perdikaris 2021,
// Algorithm 1; its options in balance_options.h, its registry
// entry, make_balance_settings, in gradient_balancing.cc). With gₖ the parameter gradient of term k's
// loss wₖLₖ (wₖ its fixed weight), on every `every`-th Adam step
//     λ̂ₖ = wₖ · max_θ |g_r| / mean_θ |gₖ|,     λₖ ← (1 − α) λₖ + α λ̂ₖ,
// g_r the residual term's gradient, λ_r = 1, every λ starting at 1; the training loss is
// Σₖ λₖ wₖ Lₖ. λ brings each term's gradient to the scale of the residual term's; wₖ stays a
// relative preference on top.
//
// Pitfalls. An update step needs each term's gradient apart, one pass per term instead of
// one pass over all, so it costs about as much as a step of its own; the other steps take
// the ordinary gradient at the held λ. The gradients and losses are summed over the ranks
// before λ is computed, so every rank moves λ alike. L-BFGS and LM stages hold λ (a line
// search needs one objective). λ goes into the checkpoint (trainer/balance_weights) only with
// grad_norm on; a checkpoint's λ of another term count is ignored.
#pragma once

#include "solvers/training/balance_options.h"
#include "solvers/training/loss_balancing.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

template <typename Scalar>
class GradientBalancing final : public TrainingStrategy<Scalar> {
 public:
  // `term`: the residual term whose gradient sets the scale; the trainer's terms by name.
  GradientBalancing(const BalanceOptions& options, std::size_t term,
                    std::vector<std::string> term_names);

  double loss_scale(std::size_t k) const override { return lambda_[k]; }
  bool step_gradient(StrategyView<Scalar>& view, Scalar* gradient) override;
  void metrics(std::vector<std::pair<std::string, double>>& out) const override;
  void save(io::H5Writer& file, const std::string& group) const override;
  void load(const io::H5Reader& file, const std::string& group) override;

  // λ per term.
  const std::vector<double>& weights() const { return lambda_; }

 private:
  BalanceOptions options_;
  std::size_t term_;
  std::vector<std::string> names_;
  std::vector<double> lambda_;
};

}  // namespace nfield::solvers
