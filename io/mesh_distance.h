// SPDX-License-Identifier: MIT
#pragma once
#include <Eigen/Core>

#include "io/triangle_mesh.h"

namespace nfield::io {

// The unsigned distance from each row of `points` (n×3) to the nearest point of the
// triangles of `mesh` (vtkStaticCellLocator). Throws std::invalid_argument if the mesh has no
// triangles or `points` has not 3 columns.
Eigen::VectorXd mesh_distance(const Eigen::MatrixXd& points, const TriangleMesh& mesh);

// Chamfer distance between two surfaces, measured from their vertices: the mean distance of
// a's vertices to b and of b's vertices to a.
struct ChamferDistance {
  double a_to_b = 0;
  double b_to_a = 0;
  double mean() const { return 0.5 * (a_to_b + b_to_a); }
};
ChamferDistance chamfer_distance(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace nfield::io
