// SPDX-License-Identifier: MIT
//
// The registry of training strategies (solvers/training/training_strategy.h). Each is one
// key of `training:` (causal, balance, adaptive; register_training_strategy for code outside
// the library) with a settings object that owns its typed options struct (CausalOptions in
// causal_options.h, …): it reads the key, writes it back for the resolved config, checks it
// against the problem, tells what the run must know of it (the points it adds) and makes the
// strategy. The trainer and the run driver know none of them by name.
//
// Order: the strategies run, and report their metrics, in the order of registration (the
// library's: causal, balance, adaptive); TrainingOptions::strategies holds every registered
// one in that order, on or off.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "io/config.h"
#include "solvers/training/training_strategy.h"

namespace nfield::solvers {

class Problem;

class StrategySettings {
 public:
  virtual ~StrategySettings() = default;

  std::string key;  // of `training:`, as registered (make_strategy_settings sets it)

  // Reads the strategy's key of `training:` (absent: its default, off); errors are
  // io::ConfigError at the key.
  virtual void read(const io::ConfigNode& training) = 0;
  // Writes it back into `training` of the resolved config (nothing, or its "off" form).
  virtual void write(YAML::Node& training) const = 0;
  // Whether the run uses the strategy.
  virtual bool enabled() const = 0;
  // Before training, for an enabled strategy: what the problem must have (a PDE residual
  // term, a time axis); errors are io::ConfigError at the strategy's key of `training`.
  virtual void check(const io::ConfigNode& /*training*/, const Problem& /*problem*/) const {}
  // The most points the strategy adds behind the problem's residual term (RAR's set), for
  // the optimizers' size checks.
  virtual long extra_points() const { return 0; }

  // The strategy for a trainer whose terms are `term_names`; std::invalid_argument when the
  // problem lacks what it needs.
  virtual std::unique_ptr<TrainingStrategy<float>> make_float(
      const Problem& problem, const std::vector<std::string>& term_names) const = 0;
  virtual std::unique_ptr<TrainingStrategy<double>> make_double(
      const Problem& problem, const std::vector<std::string>& term_names) const = 0;
};

// The options of a strategy, as a typed struct (TrainingOptions::strategy_options reads them).
template <class Options>
class StrategyWithOptions : public StrategySettings {
 public:
  Options options;
};

// Implements make_float/make_double from Derived's static member template
// `template <typename Scalar> static std::unique_ptr<TrainingStrategy<Scalar>> make(
//      const Options&, const Problem&, const std::vector<std::string>& term_names)`.
template <class Derived, class Options>
class StrategySettingsOf : public StrategyWithOptions<Options> {
 public:
  std::unique_ptr<TrainingStrategy<float>> make_float(
      const Problem& problem, const std::vector<std::string>& names) const final {
    return Derived::template make<float>(this->options, problem, names);
  }
  std::unique_ptr<TrainingStrategy<double>> make_double(
      const Problem& problem, const std::vector<std::string>& names) const final {
    return Derived::template make<double>(this->options, problem, names);
  }
};

using StrategyFactory = std::function<std::unique_ptr<StrategySettings>()>;

// Adds a strategy read from `training.KEY`; it runs after those registered before it.
// Throws std::logic_error if the key is taken.
void register_training_strategy(std::string_view key, StrategyFactory factory);
// The registered keys, in hook order.
std::vector<std::string> training_strategy_names();
// New settings of that key with default options (off); UnknownNameError listing the valid
// keys otherwise.
std::unique_ptr<StrategySettings> make_strategy_settings(std::string_view key);

// For the settings of strategies that act on the problem's residual term: check() fails at
// training.KEY when the problem has none; residual_term_for gives its index among the
// trainer's `term_names` (std::invalid_argument naming training.KEY when it is not there).
void require_residual_term(const io::ConfigNode& training, std::string_view key,
                           const Problem& problem);
std::size_t residual_term_for(std::string_view key, const Problem& problem,
                              const std::vector<std::string>& term_names);

// The library's strategies' settings (in their own .cc files).
std::unique_ptr<StrategySettings> make_causal_settings();
std::unique_ptr<StrategySettings> make_balance_settings();
std::unique_ptr<StrategySettings> make_adaptive_settings();

}  // namespace nfield::solvers
