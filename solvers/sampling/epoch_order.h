// SPDX-License-Identifier: MIT
//
// A finite set of samples drawn in epochs, as a function of the position in the stream of
// draws: position p is sample σ_e(p mod n) of the n, e = ⌊p / n⌋, with σ_e a shuffle seeded
// by (seed, e). A batch of b samples at step t takes positions tb … tb + b − 1, so every
// sample is drawn once per epoch (random reshuffling) instead of about Poisson(1) times, as
// independent draws with replacement give; SGD over a finite sum then converges faster (the
// gradient noise of an epoch sums to zero). Resume needs no saved state: the draws at step t
// follow from the seed and t alone.
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include <Eigen/Core>

namespace nfield::solvers {

class EpochOrder {
 public:
  EpochOrder(Eigen::Index samples, std::uint64_t seed);
  // The samples at positions first … first + count − 1. Thread-safe.
  Eigen::VectorXi at(std::int64_t first, Eigen::Index count) const;

 private:
  Eigen::Index samples_;
  std::uint64_t seed_;
  mutable std::mutex mutex_;
  mutable std::int64_t epoch_ = -1;  // whose shuffle order_ holds
  mutable std::vector<int> order_;
};

}  // namespace nfield::solvers
