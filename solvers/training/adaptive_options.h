// SPDX-License-Identifier: MIT
//
// `training.adaptive`, the options of residual-based adaptive refinement (RAR; the strategy:
// solvers/training/adaptive_refinement.h), with their defaults; absent: off.
//
//   adaptive:
//     every: 500          # steps between refinements (Adam and L-BFGS)
//     candidates: 10000   # points drawn (like the interior batch) and scored by ‖r‖
//     add: 100            # the highest-scoring ones join a persistent extra set
//     max_points: 2000    # size cap of the set (at least add); the oldest points leave first
//
// The set rides behind the residual term's batch, so a run draws up to max_points more
// points for that term (StrategySettings::extra_points): the optimizers' size checks count
// them.
#pragma once

namespace nfield::solvers {

struct AdaptiveOptions {
  bool enabled = false;
  int every = 500;
  long candidates = 10000;
  long add = 100;
  long max_points = 2000;
};

}  // namespace nfield::solvers
