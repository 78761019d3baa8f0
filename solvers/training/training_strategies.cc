// SPDX-License-Identifier: MIT
// The library's training strategies, made from `training:` (training_strategy.h). A new one
// is one more `if` here, in hook order.
#include <stdexcept>

#include "solvers/core/problem.h"
#include "solvers/training/adaptive_refinement.h"
#include "solvers/training/causal_weighting.h"
#include "solvers/training/gradient_balancing.h"
#include "solvers/training/training_options.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

template <typename Scalar>
TrainingStrategies<Scalar> make_training_strategies(const TrainingOptions& options,
                                                    const Problem& problem,
                                                    const std::vector<std::string>& term_names) {
  const bool causal = options.causal.enabled, balance = options.balance.method != "fixed",
             adaptive = options.adaptive.enabled;
  const int term = problem.residual_term();
  if ((adaptive || causal || balance) && (term < 0 || term >= static_cast<int>(term_names.size())))
    throw std::invalid_argument("training.adaptive, balance and causal need a PDE residual term");
  const Domain& domain = problem.domain();
  if (causal && !domain.has_time())
    throw std::invalid_argument("training.causal needs a time axis (domain.time)");
  TrainingStrategies<Scalar> strategies;
  // This order is the order of the hooks and of the figures in metrics.json.
  if (causal) {
    const auto [t0, t1] = domain.time();
    strategies.push_back(std::make_unique<CausalWeighting<Scalar>>(
        options.causal, term, domain.time_column(), t0, t1));
  }
  if (balance)
    strategies.push_back(std::make_unique<GradientBalancing<Scalar>>(options.balance, term, term_names));
  if (adaptive)
    strategies.push_back(
        std::make_unique<AdaptiveRefinement<Scalar>>(options.adaptive, term, term_names[term]));
  return strategies;
}

template TrainingStrategies<float> make_training_strategies<float>(
    const TrainingOptions&, const Problem&, const std::vector<std::string>&);
template TrainingStrategies<double> make_training_strategies<double>(
    const TrainingOptions&, const Problem&, const std::vector<std::string>&);

}  // namespace nfield::solvers
