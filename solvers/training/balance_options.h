// SPDX-License-Identifier: MIT
//
// `training.balance`, the options of gradient-based loss balancing (grad_norm; the strategy:
// solvers/training/gradient_balancing.h), with their defaults:
//
//   balance: fixed    # fixed (off) | grad_norm | {method: grad_norm, every: 100, alpha: 0.1}
//
// every: Adam steps between updates of λ; alpha: the weight of a new estimate, in (0, 1].
#pragma once

#include <string>

namespace nfield::solvers {

struct BalanceOptions {
  std::string method = "fixed";  // fixed | grad_norm
  int every = 100;
  double alpha = 0.1;
};

}  // namespace nfield::solvers
