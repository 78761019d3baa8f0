// SPDX-License-Identifier: MIT
#include "solvers/training_options.h"

#include <cmath>
#include <numbers>

#include "solvers/sampler.h"

namespace nfield::solvers {
namespace {
template <typename T>
T in_range_or(const io::ConfigNode& node, std::string_view key, T lowest, T highest, T fallback) {
  return node.has(key) ? node.get_in_range<T>(key, lowest, highest) : fallback;
}
}  // namespace

double StageOptions::learning_rate(int step) const {
  return learning_rate_at(steps > 1 ? static_cast<double>(step) / (steps - 1) : 1.0);
}

double StageOptions::learning_rate_at(double progress) const {
  if (schedule == "cosine")
    return lr_final + 0.5 * (lr - lr_final) * (1 + std::cos(std::numbers::pi * progress));
  if (schedule == "exponential") return lr * std::pow(lr_final / lr, progress);
  return lr;
}

int TrainingOptions::total_steps() const {
  int total = 0;
  for (const auto& s : stages) total += s.steps;
  return total;
}

TrainingOptions TrainingOptions::from_config(const io::ConfigNode& node) {
  TrainingOptions o;
  o.seed = static_cast<std::uint64_t>((node.has("seed") ? node.get_nonnegative<std::int64_t>("seed") : 0));
  o.precision = node.get_choice("precision", {"float", "double"}, "float");
  o.threads = in_range_or(node, "threads", 0, 1024, 0);
  o.block = in_range_or<long>(node, "block", 1, 1 << 20, 128);
  if (node.has("batch")) {
    const io::ConfigNode batch = node.child("batch");
    batch.require(batch.is_map(), "expected a mapping such as {interior: 4096, boundary: 1024}");
    for (const std::string& key : batch.keys()) o.batch[key] = batch.get_in_range<long>(key, 1, 1L << 26);
  }
  o.resample_every = in_range_or(node, "resample_every", 1, 1 << 30, 1);
  o.log_every = in_range_or(node, "log_every", 1, 1 << 30, 100);
  o.checkpoint_every = in_range_or(node, "checkpoint_every", 0, 1 << 30, 0);
  o.sampler = node.get_choice("sampler", sampler_names(), "uniform");
  o.adaptive = adaptive_from_config(node);
  o.balance = balance_from_config(node);
  o.causal = causal_from_config(node);
  if (node.has("stages")) {
    const io::ConfigNode stages = node.child("stages");
    stages.require(stages.is_sequence() && stages.size() > 0, "expected a non-empty list of stages");
    o.stages.clear();
    for (std::size_t i = 0; i < stages.size(); ++i) {
      const io::ConfigNode s = stages.at(i);
      StageOptions stage;
      stage.optimizer = s.get_choice("optimizer", {"adam", "lbfgs", "lm"});
      stage.steps = s.get_in_range("steps", 0, 1 << 30);
      if (stage.optimizer == "adam") {
        stage.lr = s.get_or("lr", stage.lr);
        s.require("lr", stage.lr > 0, "expected a learning rate > 0");
        stage.schedule = s.get_choice("schedule", {"constant", "cosine", "exponential"}, "constant");
        stage.lr_final = s.get_or("lr_final", std::min(stage.lr_final, stage.lr));
        s.require("lr_final", stage.lr_final > 0, "expected a learning rate > 0");
        stage.seconds = s.get_or("seconds", 0.0);
        s.require("seconds", stage.seconds >= 0 && std::isfinite(stage.seconds),
                  "expected a number of seconds >= 0 (0: no time limit)");
      } else if (stage.optimizer == "lbfgs") {
        stage.memory = in_range_or(s, "memory", 1, 1000, 20);
        stage.resample_every = in_range_or(s, "resample_every", 0, 1 << 30, 0);
      } else {
        stage.linear_solver =
            s.get_choice("linear_solver", {"dense_qr", "dense_normal_cholesky"}, "dense_qr");
        stage.initial_radius = in_range_or(s, "initial_radius", 1e-12, 1e16, 1e4);
        stage.resample_every = in_range_or(s, "resample_every", 0, 1 << 30, 0);
      }
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
  for (const auto& s : stages) {
    YAML::Node y;
    y["optimizer"] = s.optimizer;
    y["steps"] = s.steps;
    if (s.optimizer == "adam") {
      y["lr"] = s.lr;
      y["schedule"] = s.schedule;
      y["lr_final"] = s.lr_final;
      if (s.seconds > 0) y["seconds"] = s.seconds;
    } else if (s.optimizer == "lbfgs") {
      y["memory"] = s.memory;
      y["resample_every"] = s.resample_every;
    } else {
      y["linear_solver"] = s.linear_solver;
      y["initial_radius"] = s.initial_radius;
      y["resample_every"] = s.resample_every;
    }
    n["stages"].push_back(y);
  }
  n["sampler"] = sampler;
  write_yaml(n, adaptive, balance, causal);
  return n;
}

}  // namespace nfield::solvers
