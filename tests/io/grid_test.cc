// SPDX-License-Identifier: MIT
#include "io/grid.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace nfield::io {
namespace {

TEST(Grid, PointsAreNumberedXFastest) {
  const Grid g{{3, 2, 2}, {1, 2, 3}, {0.5, 0.25, 2}};
  EXPECT_EQ(g.point_count(), 12);
  EXPECT_EQ(g.dimension(), 3);
  EXPECT_EQ(g.point(0), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(g.point(1), Eigen::Vector3d(1.5, 2, 3));
  EXPECT_EQ(g.point(3), Eigen::Vector3d(1, 2.25, 3));
  EXPECT_EQ(g.point(6), Eigen::Vector3d(1, 2, 5));
  EXPECT_EQ(g.point(11), Eigen::Vector3d(2, 2.25, 5));
  const Eigen::MatrixXd p = g.points(3);
  ASSERT_EQ(p.rows(), 12);
  for (int i = 0; i < 12; ++i) EXPECT_EQ(p.row(i), g.point(i).transpose());
}

TEST(Grid, PointsDropsUnusedAxesOnly) {
  const Grid g{{4, 3, 1}, {0, 0, 7}, {1, 1, 1}};
  EXPECT_EQ(g.dimension(), 2);
  const Eigen::MatrixXd p = g.points(2);
  EXPECT_EQ(p.cols(), 2);
  EXPECT_EQ(p.row(5), Eigen::RowVector2d(1, 1));
  EXPECT_EQ(g.points(3)(0, 2), 7);
  EXPECT_THROW(g.points(1), std::invalid_argument);
  EXPECT_THROW(g.points(4), std::invalid_argument);
}

TEST(Grid, MakeGridSpansTheCorners) {
  const Grid g = make_grid({-1, 0}, {1, 2}, {5, 3});
  EXPECT_EQ(g.dims, (std::array<int, 3>{5, 3, 1}));
  EXPECT_EQ(g.origin, (std::array<double, 3>{-1, 0, 0}));
  EXPECT_EQ(g.spacing, (std::array<double, 3>{0.5, 1, 1}));
  EXPECT_EQ(g.point(g.point_count() - 1), Eigen::Vector3d(1, 2, 0));
  EXPECT_EQ(make_grid({2}, {3}, {1}).origin[0], 2);
  EXPECT_THROW(make_grid({0, 0}, {1}, {2, 2}), std::invalid_argument);
  EXPECT_THROW(make_grid({0}, {1}, {0}), std::invalid_argument);
  EXPECT_THROW(make_grid({0, 0, 0, 0}, {1, 1, 1, 1}, {2, 2, 2, 2}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::io
