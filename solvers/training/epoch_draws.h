// SPDX-License-Identifier: MIT
//
// Instances of a family drawn in epochs: a shuffled order of all of them, drawn in turn and
// shuffled again when used up, so that every instance weighs the same over an epoch (and a
// step that draws all of them takes each once). Reptile's outer loop and the auto-decoder
// draw their instances this way.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

#include "solvers/sampling/random.h"

namespace nfield::solvers {

class EpochDraws {
 public:
  EpochDraws(std::size_t instances, Random::result_type seed) : order_(instances), rng_(seed) {
    std::iota(order_.begin(), order_.end(), std::size_t{0});
  }
  std::size_t next() {
    if (next_ == order_.size()) {
      std::shuffle(order_.begin(), order_.end(), rng_);
      next_ = 0;
    }
    return order_[next_++];
  }

 private:
  std::vector<std::size_t> order_;
  Random rng_;
  std::size_t next_ = order_.size();
};

}  // namespace nfield::solvers
