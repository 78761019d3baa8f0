// SPDX-License-Identifier: MIT
#include "solvers/training/training_options.h"

#include <algorithm>

#include "solvers/sampling/random.h"

namespace nfield::solvers {
namespace {
template <typename T>
T in_range_or(const io::ConfigNode& node, std::string_view key, T lowest, T highest, T fallback) {
  return node.has(key) ? node.get_in_range<T>(key, lowest, highest) : fallback;
}
}  // namespace

StageOptions::StageOptions() : settings(make_optimizer("adam")) {}

bool TrainingOptions::has_strategies() const {
  for (const auto& s : strategies)
    if (s->enabled()) return true;
  return false;
}

int TrainingOptions::total_steps() const {
  int total = 0;
  for (const auto& s : stages) total += s.steps;
  return total;
}

TrainingOptions TrainingOptions::from_config(const io::ConfigNode& node) {
  TrainingOptions o;
  if (node.has("seed")) o.seed = static_cast<std::uint64_t>(node.get_nonnegative<std::int64_t>("seed"));
  o.precision = node.get_choice("precision", {"float", "double"}, o.precision);
  o.threads = in_range_or(node, "threads", 0, 1024, o.threads);
  o.block = in_range_or<long>(node, "block", 1, 1 << 20, o.block);
  if (node.has("batch")) {
    const io::ConfigNode batch = node.child("batch");
    batch.require(batch.is_map(), "expected a mapping such as {interior: 4096, boundary: 1024}");
    for (const std::string& key : batch.keys()) o.batch[key] = batch.get_in_range<long>(key, 1, 1L << 26);
  }
  o.resample_every = in_range_or(node, "resample_every", 1, 1 << 30, o.resample_every);
  o.log_every = in_range_or(node, "log_every", 1, 1 << 30, o.log_every);
  o.checkpoint_every = in_range_or(node, "checkpoint_every", 0, 1 << 30, o.checkpoint_every);
  o.on_divergence = node.get_choice("on_divergence", {"stop", "restore_and_halve_lr"}, o.on_divergence);
  o.divergence_retries = in_range_or(node, "divergence_retries", 1, 100, o.divergence_retries);
  o.sampler = node.get_choice("sampler", sampler_names(), o.sampler);
  for (const std::string& key : training_strategy_names()) {
    std::unique_ptr<StrategySettings> strategy = make_strategy_settings(key);
    strategy->read(node);
    o.strategies.push_back(std::move(strategy));
  }
  o.meta = meta_from_config(node);
  o.auto_decoder = auto_decoder_from_config(node);
  if (node.has("stages")) {
    const io::ConfigNode stages = node.child("stages");
    stages.require(stages.is_sequence() && stages.size() > 0, "expected a non-empty list of stages");
    o.stages.clear();
    for (std::size_t i = 0; i < stages.size(); ++i) {
      const io::ConfigNode s = stages.at(i);
      StageOptions stage;
      stage.optimizer = s.get_choice("optimizer", optimizer_names());
      stage.steps = s.get_in_range("steps", 0, 1 << 30);
      if (s.has("batch_scale")) stage.batch_scale = s.get_in_range("batch_scale", 1, 1024);
      std::unique_ptr<Optimizer> optimizer = make_optimizer(stage.optimizer);
      optimizer->read(s);
      stage.settings = std::move(optimizer);
      s.reject_unknown_keys();
      o.stages.push_back(stage);
    }
  }
  return o;
}

YAML::Node TrainingOptions::to_yaml() const {
  YAML::Node n;
  n["seed"] = seed;
  n["precision"] = precision;
  n["threads"] = threads;
  n["block"] = block;
  for (const auto& [k, v] : batch) n["batch"][k] = v;
  n["resample_every"] = resample_every;
  n["log_every"] = log_every;
  n["checkpoint_every"] = checkpoint_every;
  n["on_divergence"] = on_divergence;
  if (on_divergence != "stop") n["divergence_retries"] = divergence_retries;
  for (const auto& s : stages) {
    YAML::Node y;
    y["optimizer"] = s.optimizer;
    y["steps"] = s.steps;
    if (s.batch_scale != 1) y["batch_scale"] = s.batch_scale;
    s.settings->write(y);
    n["stages"].push_back(y);
  }
  n["sampler"] = sampler;
  // Sorted by key, as the resolved config always listed them.
  std::vector<std::pair<std::string, const StrategySettings*>> sorted;
  for (const auto& strategy : strategies) sorted.emplace_back(strategy->key, strategy.get());
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [key, strategy] : sorted) strategy->write(n);
  write_yaml(n, meta);
  write_yaml(n, auto_decoder);
  return n;
}

}  // namespace nfield::solvers
