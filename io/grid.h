// SPDX-License-Identifier: MIT
#pragma once
#include <array>
#include <vector>

#include <Eigen/Core>

namespace nfield::io {

// A regular grid of 1 to 3 dimensions: dims[d] points along axis d, the first at origin[d],
// spaced by spacing[d]. Unused axes have dims 1. Points are numbered as VTK numbers them,
// x fastest: index = i + dims[0] * (j + dims[1] * k). This is the layout of a .vti file.
struct Grid {
  std::array<int, 3> dims{1, 1, 1};
  std::array<double, 3> origin{};
  std::array<double, 3> spacing{1, 1, 1};

  // dims[0] * dims[1] * dims[2].
  Eigen::Index point_count() const;
  // The number of axes with more than one point (0 for a single point).
  int dimension() const;
  // The coordinates of point `index` (0 <= index < point_count()).
  Eigen::Vector3d point(Eigen::Index index) const;
  // The coordinates of all points, one row per point in VTK order, the first `dim` axes as
  // columns (1 <= dim <= 3). Throws std::invalid_argument if a dropped axis has more than one
  // point.
  Eigen::MatrixXd points(int dim) const;
};

// The grid with counts[d] points from lower[d] to upper[d] inclusive along each of the
// 1 to 3 given axes; the remaining axes get one point at 0. An axis with one point sits at
// lower[d]. Throws std::invalid_argument on mismatched sizes or a count below 1.
Grid make_grid(const std::vector<double>& lower, const std::vector<double>& upper,
               const std::vector<int>& counts);

}  // namespace nfield::io
