// SPDX-License-Identifier: MIT
//
// training.auto_decoder: the options of a run that trains a latent code per instance of a
// family with the field (the algorithm: solvers/training/auto_decoder.h). Its own header so
// that TrainingOptions can hold them without knowing the loop.
#pragma once

#include <string>

#include "io/config.h"

namespace nfield::solvers {

struct AutoDecoderOptions {
  bool given = false;           // training.auto_decoder present (the keys below read from it)
  int instances_per_step = 8;   // B: instances drawn per step, in epochs
  double prior = 1e-4;          // λ: each drawn instance's loss gets λ‖z‖² (DeepSDF's value)
  double init_std = 0.01;       // codes start from N(0, init_std² I)
  int fit_steps = 300;          // a new instance's code: this many Adam steps …
  double fit_lr = 1e-2;         // … at this rate (constant)
  int interpolation_steps = 5;  // outputs along the line between two training codes (0: none)

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

// training.auto_decoder (absent: the defaults, given = false). Throws io::ConfigError located
// at the key at fault.
AutoDecoderOptions auto_decoder_from_config(const io::ConfigNode& training);
// Adds `options` to the resolved `training` section when given.
void write_yaml(YAML::Node& training, const AutoDecoderOptions& options);

}  // namespace nfield::solvers
