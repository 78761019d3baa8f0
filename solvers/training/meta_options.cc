// SPDX-License-Identifier: MIT
#include "solvers/training/meta_options.h"

#include <stdexcept>

namespace nfield::solvers {

void MetaOptions::validate() const {
  const auto fail = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw std::invalid_argument("meta." + field + " = " + value + ": " + rule);
  };
  if (steps < 1) fail("steps", std::to_string(steps), "expected at least 1");
  if (tasks_per_step < 1) fail("tasks_per_step", std::to_string(tasks_per_step), "expected at least 1");
  if (inner_steps < 1) fail("inner_steps", std::to_string(inner_steps), "expected at least 1");
  if (curve_steps < 1) fail("curve_steps", std::to_string(curve_steps), "expected at least 1");
  if (!(inner_lr > 0)) fail("inner_lr", std::to_string(inner_lr), "expected a number > 0");
  if (!(outer_lr > 0 && outer_lr <= 1)) fail("outer_lr", std::to_string(outer_lr), "expected a number in (0, 1]");
  if (inner_optimizer != "sgd" && inner_optimizer != "adam")
    fail("inner_optimizer", inner_optimizer, "expected sgd or adam");
  if (algorithm != "reptile" && inner_optimizer != "sgd")
    fail("inner_optimizer", inner_optimizer,
         "expected sgd with algorithm " + algorithm + " (its meta-gradient differentiates plain gradient steps)");
}

const std::vector<std::string>& meta_algorithm_names() {
  static const std::vector<std::string> names{"reptile", "maml", "fomaml"};
  return names;
}

MetaOptions meta_from_config(const io::ConfigNode& training) {
  MetaOptions o;
  if (!training.has("meta")) return o;
  const io::ConfigNode meta = training.child("meta");
  meta.require(meta.is_map(), "expected a mapping such as {algorithm: reptile, inner_steps: 2, steps: 1000}");
  o.enabled = true;
  o.algorithm = meta.get_choice("algorithm", meta_algorithm_names(), o.algorithm);
  if (meta.has("steps")) o.steps = meta.get_in_range("steps", 1, 1 << 30);
  if (meta.has("tasks_per_step")) o.tasks_per_step = meta.get_in_range("tasks_per_step", 1, 1 << 16);
  if (meta.has("inner_steps")) o.inner_steps = meta.get_in_range("inner_steps", 1, 1 << 16);
  if (meta.has("curve_steps")) o.curve_steps = meta.get_in_range("curve_steps", 1, 1 << 20);
  o.inner_optimizer = meta.get_choice("inner_optimizer", {"sgd", "adam"}, o.inner_optimizer);
  if (o.algorithm != "reptile")
    meta.require("inner_optimizer", o.inner_optimizer == "sgd",
                 "expected sgd with algorithm " + o.algorithm +
                     " (its meta-gradient differentiates plain gradient steps: solvers/training/maml.h)");
  if (o.algorithm != "reptile" && !meta.has("outer_lr")) o.outer_lr = 1e-4;
  if (meta.has("learn_inner_lr")) {
    o.learn_inner_lr = meta.get<bool>("learn_inner_lr");
    meta.require("learn_inner_lr", !o.learn_inner_lr || o.algorithm != "reptile",
                 "expected false with algorithm reptile (rates per parameter are learned through MAML's "
                 "meta-gradient: algorithm maml or fomaml)");
  }
  if (meta.has("inner_lr")) {
    o.inner_lr = meta.get_positive<double>("inner_lr");
    meta.require("inner_lr", o.inner_lr <= 1e6, "expected a number in (0, 1e6]");
  }
  if (meta.has("outer_lr")) {
    o.outer_lr = meta.get_positive<double>("outer_lr");
    meta.require("outer_lr", o.outer_lr <= 1,
                 o.algorithm == "reptile" ? "expected a number in (0, 1]: the fraction of the way to the adapted weights"
                                          : "expected a number in (0, 1]: the outer Adam's rate");
  }
  meta.reject_unknown_keys();
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw meta.error(e.what());
  }
  return o;
}

void write_yaml(YAML::Node& training, const MetaOptions& meta) {
  if (!meta.enabled) return;
  YAML::Node n;
  n["algorithm"] = meta.algorithm;
  n["steps"] = meta.steps;
  n["tasks_per_step"] = meta.tasks_per_step;
  n["inner_steps"] = meta.inner_steps;
  n["inner_optimizer"] = meta.inner_optimizer;
  n["inner_lr"] = meta.inner_lr;
  n["outer_lr"] = meta.outer_lr;
  n["curve_steps"] = meta.curve_steps;
  if (meta.learn_inner_lr) n["learn_inner_lr"] = true;
  training["meta"] = n;
}

}  // namespace nfield::solvers
