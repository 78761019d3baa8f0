// SPDX-License-Identifier: MIT
//
// Points with line and triangle cells and named point arrays: what io/vtk_polydata.h writes
// and reads, and io/vtk_convert.h converts to and from VTK.
#pragma once

#include <Eigen/Core>

#include "io/point_arrays.h"

namespace nfield::io {

// What a .vtp file holds here: points, line segments, triangles and named point arrays.
struct PolyData {
  Eigen::MatrixXd points;                           // n×3 (n×2 is accepted for writing: z = 0)
  Eigen::Matrix<int, Eigen::Dynamic, 2> lines;      // point indices of each segment
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  // point indices of each triangle
  PointArrays arrays;                               // each with one row per point
};

}  // namespace nfield::io
