// SPDX-License-Identifier: MIT
//
// `training.causal`, the options of causal weighting in time (the strategy:
// solvers/training/causal_weighting.h), with their defaults; absent: off. It needs a problem
// with a time axis (domain.time: [t0, t1]).
//
//   causal: {epsilon: 1.0, slices: 32, every: 100}
//
// epsilon: ε of cᵢ = exp(−ε Σ_{k<i} Lₖ), ≥ 0; slices: M, the number of equal slices of
// [t0, t1]; every: L-BFGS iterations between weight updates.
#pragma once

namespace nfield::solvers {

struct CausalOptions {
  bool enabled = false;
  double epsilon = 1.0;
  int slices = 32;
  int every = 100;  // L-BFGS: iterations between weight updates
};

}  // namespace nfield::solvers
