// SPDX-License-Identifier: MIT
//
// ExtraGradient (solvers/core/residual.h): the blocks' gradients with respect to unknown
// constants sum to the same total in whatever order the threads add them, and a block that
// adds twice (each scale of a multiscale field in turn) counts both.
#include <gtest/gtest.h>

#include "solvers/core/residual.h"

namespace nfield::solvers {
namespace {

TEST(ExtraGradient, SumsEveryBlockAndEveryAdditionOfABlock) {
  ExtraGradient forward, backward;
  const Eigen::Vector2d a(1.0, 2.0), b(0.5, -3.0), c(1e-3, 7.0);
  forward.add(0, a);
  forward.add(64, b);
  forward.add(64, c);  // the same block again
  backward.add(64, b);
  backward.add(64, c);
  backward.add(0, a);
  EXPECT_EQ(forward.sum(2), a + (b + c));
  EXPECT_EQ(backward.sum(2), forward.sum(2));  // bit for bit: the order of the blocks, not of the threads
  forward.clear();
  EXPECT_EQ(forward.sum(2), Eigen::Vector2d::Zero());
}

}  // namespace
}  // namespace nfield::solvers
