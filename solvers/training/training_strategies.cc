// SPDX-License-Identifier: MIT
// The registry of training strategies (strategy_settings.h) and make_training_strategies
// (training_strategy.h). A new strategy is its own files and one registration line here, in
// hook order.
#include <stdexcept>

#include "io/registry.h"
#include "io/text.h"
#include "solvers/core/problem.h"
#include "solvers/training/strategy_settings.h"
#include "solvers/training/training_options.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {
namespace {

struct Entry {
  std::string key;
  StrategyFactory factory;
};

// In registration order, which is hook order.
std::vector<Entry>& entries() {
  static std::vector<Entry> list{{"causal", make_causal_settings},
                                 {"balance", make_balance_settings},
                                 {"adaptive", make_adaptive_settings}};
  return list;
}

}  // namespace

void register_training_strategy(std::string_view key, StrategyFactory factory) {
  const std::string name = io::to_lower(key);
  for (const Entry& e : entries())
    if (e.key == name) throw std::logic_error("training strategy '" + name + "' registered twice");
  entries().push_back({name, std::move(factory)});
}

std::vector<std::string> training_strategy_names() {
  std::vector<std::string> names;
  for (const Entry& e : entries()) names.push_back(e.key);
  return names;
}

std::unique_ptr<StrategySettings> make_strategy_settings(std::string_view key) {
  const std::string name = io::to_lower(key);
  std::string valid;
  for (const Entry& e : entries()) {
    if (e.key == name) {
      std::unique_ptr<StrategySettings> settings = e.factory();
      settings->key = name;
      return settings;
    }
    valid += (valid.empty() ? "" : ", ") + e.key;
  }
  throw UnknownNameError("unknown training strategy '" + std::string(key) + "' (valid: " + valid + ")");
}

void require_residual_term(const io::ConfigNode& training, std::string_view key,
                           const Problem& problem) {
  if (problem.residual_term() < 0)
    throw training.error(key, "this problem has no PDE residual term to act on");
}

std::size_t residual_term_for(std::string_view key, const Problem& problem,
                              const std::vector<std::string>& term_names) {
  const int term = problem.residual_term();
  if (term < 0 || term >= static_cast<int>(term_names.size()))
    throw std::invalid_argument("training." + std::string(key) + " needs a PDE residual term");
  return static_cast<std::size_t>(term);
}

template <typename Scalar>
TrainingStrategies<Scalar> make_training_strategies(const TrainingOptions& options,
                                                    const Problem& problem,
                                                    const std::vector<std::string>& term_names) {
  TrainingStrategies<Scalar> strategies;
  for (const auto& settings : options.strategies) {
    if (!settings->enabled()) continue;
    if constexpr (std::is_same_v<Scalar, float>)
      strategies.push_back(settings->make_float(problem, term_names));
    else
      strategies.push_back(settings->make_double(problem, term_names));
  }
  return strategies;
}

template TrainingStrategies<float> make_training_strategies<float>(
    const TrainingOptions&, const Problem&, const std::vector<std::string>&);
template TrainingStrategies<double> make_training_strategies<double>(
    const TrainingOptions&, const Problem&, const std::vector<std::string>&);

}  // namespace nfield::solvers
