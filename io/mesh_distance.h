// SPDX-License-Identifier: MIT
//
// Distances between points and triangle surfaces, and the comparison of two surfaces (a
// level set against a reference mesh): Chamfer distances both ways and normal consistency.
//
// The nearest point of a mesh comes from VTK's vtkStaticCellLocator, built once and then
// queried from all OpenMP threads (each with its own vtkGenericCell, which makes the query
// thread-safe). The surface of a 256³ level set (about 3·10⁵ vertices) against a mesh of
// 10⁵ triangles takes about a second on 2 cores: bench/chamfer_bench.cc.
#pragma once
#include <algorithm>

#include <Eigen/Core>

#include "io/grid.h"
#include "io/triangle_mesh.h"

namespace nfield::io {

// For each row of `points` (n×3): the distance to the nearest point of `mesh`'s triangles
// and the index of the triangle it lies on. Throws std::invalid_argument if the mesh has no
// triangles or `points` has not 3 columns.
struct ClosestTriangles {
  Eigen::VectorXd distance;
  Eigen::VectorXi triangle;
};
ClosestTriangles closest_triangles(const Eigen::MatrixXd& points, const TriangleMesh& mesh);

// For each row of `points`: the distance to the nearest row of `cloud` (both n×3), through
// vtkStaticPointLocator, or that row's index. Throw std::invalid_argument for an empty cloud.
Eigen::VectorXd point_cloud_distance(const Eigen::MatrixXd& points, const Eigen::MatrixXd& cloud);
Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> nearest_cloud_points(const Eigen::MatrixXd& points,
                                                                     const Eigen::MatrixXd& cloud);

// Unit normals of the triangles (right-handed in their vertex order; zero for degenerate ones).
Eigen::MatrixXd triangle_normals(const TriangleMesh& mesh);

// Whether each row of `points` lies within `radius` of `mesh` (vtkStaticCellLocator's search
// within a radius, which is quick for points far from the mesh).
Eigen::Array<bool, Eigen::Dynamic, 1> near_mesh(const Eigen::MatrixXd& points, const TriangleMesh& mesh,
                                                double radius);

// near_mesh for the points of a 3D grid, in grid order, found by blocks: a block of points
// whose centre is farther from the mesh than `radius` plus the block's half-diagonal is far
// as a whole, one nearer than `radius` minus it is near as a whole, and any other is split
// into eight until single points are queried. Only the blocks along the radius's level set
// are split, so a 256³ grid takes seconds where a query per point takes minutes.
Eigen::Array<bool, Eigen::Dynamic, 1> grid_near_mesh(const Grid& grid, const TriangleMesh& mesh, double radius);

// closest_triangles(points, mesh).distance.
Eigen::VectorXd mesh_distance(const Eigen::MatrixXd& points, const TriangleMesh& mesh);

// Two surfaces measured from their vertices.
//   a_to_b, b_to_a        the distance of each vertex of one surface to the other surface;
//   normal_consistency    the mean over both directions of |n(v) · n_T|, n(v) a vertex's
//                         normal (the area-weighted mean of its triangles' normals) and n_T
//                         the normal of the triangle of the other surface nearest to v
//                         (Mescheder et al. 2019, without orientation: 1 when the surfaces
//                         are parallel everywhere, about 0.5 for unrelated ones).
// Vertices that no triangle uses count in neither. Throws std::invalid_argument if a surface
// has no triangles.
struct SurfaceComparison {
  Eigen::VectorXd a_to_b, b_to_a;
  double normal_consistency = 0;
  double chamfer_mean() const { return 0.5 * (a_to_b.mean() + b_to_a.mean()); }
  double chamfer_max() const { return std::max(a_to_b.maxCoeff(), b_to_a.maxCoeff()); }
};
SurfaceComparison compare_surfaces(const TriangleMesh& a, const TriangleMesh& b);

// Chamfer distance between two surfaces, measured from their vertices: the mean distance of
// a's vertices to b and of b's vertices to a.
struct ChamferDistance {
  double a_to_b = 0;
  double b_to_a = 0;
  double mean() const { return 0.5 * (a_to_b + b_to_a); }
};
ChamferDistance chamfer_distance(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace nfield::io
