// SPDX-License-Identifier: MIT
#pragma once
#include <Eigen/Core>

#include "io/grid.h"
#include "io/triangle_mesh.h"

namespace nfield::io {

// The surface where a field sampled on a 3-D grid equals `iso` (flying edges, VTK's fast
// marching cubes). `values` holds one value per grid point in grid order
// (grid.point_count() of them). Triangles wind counter-clockwise seen from the side of larger
// values, so for a signed distance (negative inside) they face outward; with `normals`, the
// per-vertex unit normals point the same way (along the field's gradient). Vertices are
// shared between triangles. An empty mesh if the level is not crossed. Throws
// std::invalid_argument unless every grid axis has at least 2 points and the size matches.
TriangleMesh extract_isosurface(const Grid& grid, const Eigen::VectorXd& values, double iso = 0.0,
                                bool normals = false);

// The level-`iso` curves of a field on a 2-D grid (axes x and y, dims[2] == 1), as segments.
struct ContourLines {
  Eigen::MatrixXd points;                          // n×2, (x, y)
  Eigen::Matrix<int, Eigen::Dynamic, 2> segments;  // point indices of each segment
};
// Throws std::invalid_argument unless the x and y axes have at least 2 points, the z axis one,
// and the size matches.
ContourLines extract_contour_lines(const Grid& grid, const Eigen::VectorXd& values,
                                   double iso = 0.0);

}  // namespace nfield::io
