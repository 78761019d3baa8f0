// SPDX-License-Identifier: MIT
//
// The `training:` section of a config, with its defaults:
//
//   training:
//     seed: 0                      # weights, encodings and sample points
//     precision: float             # float | double
//     threads: 0                   # 0: all cores
//     block: 128                   # points per block of the chunked passes
//     batch: {interior: 4096, boundary: 1024, initial: 1024}   # points per loss term kind
//     resample_every: 1            # new points every k Adam steps (L-BFGS keeps its points)
//     log_every: 100               # progress lines when the output is not a terminal
//     checkpoint_every: 0          # steps between checkpoints (0: at the end and on Ctrl-C)
//     on_divergence: stop          # stop | restore_and_halve_lr: what a non-finite step does
//     divergence_retries: 3        # restore_and_halve_lr: at most this many times a run
//     sampler: uniform             # uniform | sobol | halton: interior, face and initial points
//     adaptive: {every: 500, candidates: 10000, add: 100, max_points: 2000}  # RAR; absent: off
//     balance: fixed               # fixed | grad_norm | {method: grad_norm, every: 100, alpha: 0.1}
//     causal: {epsilon: 1.0, slices: 32, every: 100}   # causal weights in time; absent: off
//                                  # (the training strategies: each reads its own key,
//                                  #  solvers/training/strategy_settings.h)
//     meta: {algorithm: reptile, steps: 1000, inner_steps: 2, …}  # solvers/training/reptile.h
//     auto_decoder: {instances_per_step: 8, prior: 1.0e-4, …}      # solvers/training/auto_decoder.h
//     stages:
//       - {optimizer: adam, steps: 2000, lr: 1.0e-3, schedule: cosine, lr_final: 1.0e-5}
//       - {optimizer: lbfgs, steps: 500, memory: 20, resample_every: 0}
//       - {optimizer: lm, steps: 200, linear_solver: dense_qr, initial_radius: 1.0e4}
//
// Stage keys by optimizer: adam reads lr, schedule, lr_final and seconds (a wall-time budget:
// the stage ends after `steps` steps or `seconds` seconds, whichever comes first, and its
// schedule then follows the fraction of the seconds spent; such a stage is not repeatable
// bit for bit, and a resumed one starts its budget anew); lbfgs reads memory; lm
// (Levenberg–Marquardt) reads linear_solver (dense_qr | dense_normal_cholesky, default
// dense_qr) and initial_radius (Ceres' initial trust-region radius, default 1e4, in
// [1e-12, 1e16]; the first damping is about its inverse); lbfgs and lm read resample_every
// (0, the default: one point set for the stage; k: a new set every k iterations, each a new
// Ceres problem). Keys of another optimizer are rejected as unknown. Each optimizer reads its
// own keys (solvers/training/optimizers.cc; their typed options and defaults in solvers/training/optimizers.h).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "io/config.h"
#include "solvers/training/auto_decoder_options.h"
#include "solvers/training/meta_options.h"
#include "solvers/training/optimizer.h"
#include "solvers/training/strategy_settings.h"

namespace nfield::solvers {

struct StageOptions {
  StageOptions();  // adam with its defaults

  std::string optimizer = "adam";  // a name of the optimizer registry (solvers/training/optimizer.h)
  int steps = 1000;
  // Every loss term draws this many times its training.batch in this stage (a last
  // Levenberg–Marquardt polish on more points than the earlier stages could afford).
  int batch_scale = 1;
  // The optimizer with this stage's own keys read; each run of the stage works on a clone.
  std::shared_ptr<const Optimizer> settings;

  // The optimizer's typed options (AdamStageOptions, … in solvers/training/optimizers.h);
  // std::bad_cast when the stage's optimizer has others.
  template <class Options>
  const Options& options() const {
    return dynamic_cast<const OptimizerWithOptions<Options>&>(*settings).options;
  }
};

struct TrainingOptions {
  std::uint64_t seed = 0;
  std::string precision = "float";
  int threads = 0;
  long block = 128;
  std::map<std::string, long> batch{{"interior", 4096}, {"boundary", 1024}, {"initial", 1024}};
  int resample_every = 1;
  int log_every = 100;
  int checkpoint_every = 0;
  // A loss, gradient or update that is not finite ends the run with the field at the last
  // parameters whose loss was finite (`stop`), or sends an Adam stage back there at half its
  // learning rate, up to divergence_retries times a run (`restore_and_halve_lr`; L-BFGS and
  // LM never step onto a non-finite loss, and stop where they start on one).
  std::string on_divergence = "stop";
  int divergence_retries = 3;
  std::vector<StageOptions> stages{StageOptions{}};
  std::string sampler = "uniform";  // solvers/sampling/random.h
  // The training strategies (solvers/training/strategy_settings.h): from a config, every
  // registered one in hook order, each on or off as `training:` says; empty: none.
  std::vector<std::shared_ptr<const StrategySettings>> strategies;
  // Meta-learning over a family of instances (solvers/training/reptile.h); off by default.
  MetaOptions meta;
  AutoDecoderOptions auto_decoder;

  int total_steps() const;
  // Whether any strategy is on.
  bool has_strategies() const;
  // The options of the strategy whose options are `Options` (AdaptiveOptions, …), or null
  // when it is off.
  template <class Options>
  const Options* strategy_options() const {
    for (const auto& s : strategies)
      if (const auto* own = dynamic_cast<const StrategyWithOptions<Options>*>(s.get()))
        return s->enabled() ? &own->options : nullptr;
    return nullptr;
  }
  static TrainingOptions from_config(const io::ConfigNode& node);
  YAML::Node to_yaml() const;
};

}  // namespace nfield::solvers
