// SPDX-License-Identifier: MIT
//
// Which points of a regular grid lie inside a closed triangle mesh, by the parity of
// crossings along the grid's x lines: each triangle is projected onto the (y, z) plane, every
// x line through its projection gets the x of the crossing, and a point is inside when an odd
// number of crossings lie below it. Cost: the triangles times the lines each one covers, plus
// a sort per line, so a 256³ grid against 10⁵ triangles takes well under a second, where a
// signed distance per point (vtkImplicitPolyDataDistance) takes minutes.
//
// The mesh must be closed (watertight); its winding does not matter. A line through an edge or
// a vertex would count the crossing twice or not at all, so the lines are moved by 10⁻⁶ of a
// cell in y and z (an irrational share), which makes such ties as good as impossible.
#pragma once
#include <Eigen/Core>

#include "io/grid.h"
#include "io/triangle_mesh.h"

namespace nfield::io {

// One flag per grid point, in grid order (x fastest). The grid must be 3D.
Eigen::Array<bool, Eigen::Dynamic, 1> inside_closed_mesh(const Grid& grid, const TriangleMesh& mesh);

}  // namespace nfield::io
