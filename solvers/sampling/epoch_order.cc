// SPDX-License-Identifier: MIT
#include "solvers/sampling/epoch_order.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "solvers/sampling/random.h"

namespace nfield::solvers {

EpochOrder::EpochOrder(Eigen::Index samples, std::uint64_t seed) : samples_(samples), seed_(seed) {
  if (samples <= 0) throw std::invalid_argument("EpochOrder: expected at least one sample");
}

Eigen::VectorXi EpochOrder::at(std::int64_t first, Eigen::Index count) const {
  if (first < 0) throw std::invalid_argument("EpochOrder: expected a position >= 0");
  const std::lock_guard lock(mutex_);
  Eigen::VectorXi index(count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const std::int64_t p = first + i, epoch = p / samples_;
    if (epoch != epoch_) {
      order_.resize(static_cast<size_t>(samples_));
      std::iota(order_.begin(), order_.end(), 0);
      // Neighbouring epochs get unrelated engines.
      Random rng(mix(seed_ + 0x9E3779B97F4A7C15ull * static_cast<std::uint64_t>(epoch)));
      std::shuffle(order_.begin(), order_.end(), rng);
      epoch_ = epoch;
    }
    index(i) = order_[static_cast<size_t>(p % samples_)];
  }
  return index;
}

}  // namespace nfield::solvers
