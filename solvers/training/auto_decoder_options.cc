// SPDX-License-Identifier: MIT
#include "solvers/training/auto_decoder_options.h"

#include <stdexcept>

namespace nfield::solvers {

void AutoDecoderOptions::validate() const {
  const auto fail = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw std::invalid_argument("auto_decoder." + field + " = " + value + ": " + rule);
  };
  if (instances_per_step < 1) fail("instances_per_step", std::to_string(instances_per_step), "expected at least 1");
  if (!(prior >= 0 && prior <= 1e6)) fail("prior", std::to_string(prior), "expected a number in [0, 1e6]");
  if (!(init_std >= 0 && init_std <= 1e3)) fail("init_std", std::to_string(init_std), "expected a number in [0, 1e3]");
  if (fit_steps < 0) fail("fit_steps", std::to_string(fit_steps), "expected a number >= 0");
  if (!(fit_lr > 0 && fit_lr <= 1e3)) fail("fit_lr", std::to_string(fit_lr), "expected a number in (0, 1e3]");
  if (interpolation_steps < 0 || interpolation_steps == 1)
    fail("interpolation_steps", std::to_string(interpolation_steps), "expected 0 (none) or at least 2");
}

AutoDecoderOptions auto_decoder_from_config(const io::ConfigNode& training) {
  AutoDecoderOptions o;
  if (!training.has("auto_decoder")) return o;
  const io::ConfigNode node = training.child("auto_decoder");
  node.require(node.is_map(), "expected a mapping such as {instances_per_step: 8, prior: 1.0e-4, fit_steps: 300}");
  o.given = true;
  if (node.has("instances_per_step")) o.instances_per_step = node.get_in_range("instances_per_step", 1, 1 << 16);
  if (node.has("prior")) {
    o.prior = node.get<double>("prior");
    node.require("prior", o.prior >= 0 && o.prior <= 1e6, "expected a number in [0, 1e6]");
  }
  if (node.has("init_std")) {
    o.init_std = node.get<double>("init_std");
    node.require("init_std", o.init_std >= 0 && o.init_std <= 1e3, "expected a number in [0, 1e3]");
  }
  if (node.has("fit_steps")) o.fit_steps = node.get_in_range("fit_steps", 0, 1 << 24);
  if (node.has("fit_lr")) {
    o.fit_lr = node.get_positive<double>("fit_lr");
    node.require("fit_lr", o.fit_lr <= 1e3, "expected a number in (0, 1e3]");
  }
  if (node.has("interpolation_steps")) {
    o.interpolation_steps = node.get_in_range("interpolation_steps", 0, 1000);
    node.require("interpolation_steps", o.interpolation_steps != 1, "expected 0 (none) or at least 2: the two ends");
  }
  node.reject_unknown_keys();
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw node.error(e.what());
  }
  return o;
}

void write_yaml(YAML::Node& training, const AutoDecoderOptions& options) {
  if (!options.given) return;
  YAML::Node n;
  n["instances_per_step"] = options.instances_per_step;
  n["prior"] = options.prior;
  n["init_std"] = options.init_std;
  n["fit_steps"] = options.fit_steps;
  n["fit_lr"] = options.fit_lr;
  n["interpolation_steps"] = options.interpolation_steps;
  training["auto_decoder"] = n;
}

}  // namespace nfield::solvers
