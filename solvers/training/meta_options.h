// SPDX-License-Identifier: MIT
//
// training.meta: the options of a meta-learning run (the keys and the algorithm:
// solvers/training/reptile.h). Its own header so that TrainingOptions can hold them without
// knowing the outer loop.
#pragma once

#include <string>

#include "io/config.h"

namespace nfield::solvers {

struct MetaOptions {
  bool enabled = false;  // training.meta present
  std::string algorithm = "reptile";  // reptile | maml | fomaml (solvers/training/maml.h)
  int steps = 1000;          // outer steps
  int tasks_per_step = 4;    // instances per outer step
  int inner_steps = 2;       // K
  std::string inner_optimizer = "sgd";  // sgd | adam
  double inner_lr = 1e-2;    // α
  double outer_lr = 1.0;     // reptile: ε at the first outer step, annealed linearly to 0;
                             // maml, fomaml: the outer Adam's rate (default 1e-4 there)
  int curve_steps = 10;      // held-out curves from the learned θ: this many inner steps
  bool learn_inner_lr = false;  // maml, fomaml: a rate per parameter, learned (Meta-SGD)

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

// The algorithms of training.meta.algorithm.
const std::vector<std::string>& meta_algorithm_names();

// training.meta (absent: disabled). Throws io::ConfigError located at the key at fault.
MetaOptions meta_from_config(const io::ConfigNode& training);
// Adds `meta` to the resolved `training` section when enabled.
void write_yaml(YAML::Node& training, const MetaOptions& meta);

}  // namespace nfield::solvers
