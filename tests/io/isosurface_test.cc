// SPDX-License-Identifier: MIT
#include "io/isosurface.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "io/mesh_distance.h"
#include "io/surface_components.h"
#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::data_path;

TEST(Isosurface, SphereOfASignedDistance) {
  const Grid grid = make_grid({-1, -1, -1}, {1, 1, 1}, {48, 48, 48});
  const double h = grid.spacing[0];
  const Eigen::VectorXd sdf = grid.points(3).rowwise().norm().array() - 0.5;
  const TriangleMesh mesh = extract_isosurface(grid, sdf, 0.0, true);
  ASSERT_GT(mesh.triangles.rows(), 1000);
  const Eigen::VectorXd r = mesh.vertices.rowwise().norm();
  EXPECT_LT((r.array() - 0.5).abs().maxCoeff(), h);

  // Triangles face outward and agree with the vertex normals, which point along the gradient.
  ASSERT_EQ(mesh.normals.rows(), mesh.vertices.rows());
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    ASSERT_GT(mesh.normals.row(i).dot(mesh.vertices.row(i)) / r(i), 0.99) << i;
  int outward = 0;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.triangles(t, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.triangles(t, 2));
    outward += (b - a).cross(c - a).dot(a + b + c) > 0;
  }
  EXPECT_EQ(outward, mesh.triangles.rows());

  // Close to the reference icosphere (radius 0.5, 162 vertices: flat faces sit up to
  // about 0.008 inside the sphere).
  const TriangleMesh sphere = read_triangle_mesh(data_path("meshes/sphere.ply"));
  const Eigen::VectorXd d = mesh_distance(mesh.vertices, sphere);
  EXPECT_LT(d.maxCoeff(), 0.02);
  EXPECT_LT(d.mean(), 0.01);
  const ChamferDistance chamfer = chamfer_distance(mesh, sphere);
  EXPECT_LT(chamfer.mean(), 0.01);
  EXPECT_EQ(chamfer.a_to_b, d.mean());
}

// Two balls of radii 0.5 and 0.25, apart: two pieces, the larger with 0.5²/(0.5² + 0.25²) =
// 0.8 of the area (to the marching-cubes error), each triangle labelled with its ball.
TEST(Isosurface, ComponentsOfTwoBalls) {
  const Grid grid = make_grid({-1, -1, -1}, {1, 1, 1}, {64, 64, 64});
  const Eigen::MatrixXd x = grid.points(3);
  const Eigen::Vector3d big(-0.4, 0, 0), small(0.6, 0, 0);
  Eigen::VectorXd sdf(x.rows());
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    const Eigen::Vector3d q = x.row(p).transpose();
    sdf(p) = std::min((q - big).norm() - 0.5, (q - small).norm() - 0.25);
  }
  const TriangleMesh both = extract_isosurface(grid, sdf);
  const SurfaceComponents pieces = surface_components(both);
  EXPECT_EQ(pieces.count, 2);
  EXPECT_NEAR(pieces.largest_area_share, 0.8, 0.01);
  EXPECT_NEAR(pieces.area, 4 * std::numbers::pi * (0.25 + 0.0625), 0.02);
  for (Eigen::Index t = 0; t < both.triangles.rows(); ++t) {
    const bool on_big = both.vertices(both.triangles(t, 0), 0) < 0.1;
    ASSERT_EQ(pieces.piece(t), on_big ? 0 : 1) << t;
  }
  // One ball: one piece holding everything; no triangles: none.
  for (Eigen::Index p = 0; p < x.rows(); ++p) sdf(p) = (x.row(p).transpose() - big).norm() - 0.5;
  const SurfaceComponents one = surface_components(extract_isosurface(grid, sdf));
  EXPECT_EQ(one.count, 1);
  EXPECT_DOUBLE_EQ(one.largest_area_share, 1.0);
  EXPECT_EQ(surface_components(TriangleMesh{}).count, 0);
}

TEST(Isosurface, NoCrossingGivesAnEmptyMesh) {
  const Grid grid = make_grid({0, 0, 0}, {1, 1, 1}, {4, 4, 4});
  const TriangleMesh mesh = extract_isosurface(grid, Eigen::VectorXd::Ones(64), 0.0);
  EXPECT_EQ(mesh.vertices.rows(), 0);
  EXPECT_EQ(mesh.triangles.rows(), 0);
}

TEST(Isosurface, ContourLinesOfACircle) {
  const Grid grid = make_grid({-1, -1}, {1, 1}, {64, 64});
  const Eigen::VectorXd sdf = grid.points(2).rowwise().norm().array() - 0.5;
  const ContourLines lines = extract_contour_lines(grid, sdf);
  ASSERT_EQ(lines.points.cols(), 2);
  ASSERT_GT(lines.segments.rows(), 50);
  EXPECT_LT((lines.points.rowwise().norm().array() - 0.5).abs().maxCoeff(), grid.spacing[0]);
  EXPECT_GE(lines.segments.minCoeff(), 0);
  EXPECT_LT(lines.segments.maxCoeff(), lines.points.rows());
  double length = 0;
  for (Eigen::Index s = 0; s < lines.segments.rows(); ++s)
    length +=
        (lines.points.row(lines.segments(s, 0)) - lines.points.row(lines.segments(s, 1))).norm();
  EXPECT_NEAR(length, std::numbers::pi, 0.01 * std::numbers::pi);
}

TEST(Isosurface, MeshDistanceOfOneTriangle) {
  TriangleMesh tri;
  tri.vertices.resize(3, 3);
  tri.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  tri.triangles.resize(1, 3);
  tri.triangles << 0, 1, 2;
  Eigen::MatrixXd p(3, 3);
  p << 0.25, 0.25, 2, 2, 0, 0, 0.25, 0.25, 0;
  const Eigen::VectorXd d = mesh_distance(p, tri);
  EXPECT_NEAR(d(0), 2, 1e-12);
  EXPECT_NEAR(d(1), 1, 1e-12);
  EXPECT_NEAR(d(2), 0, 1e-12);
}

TEST(Isosurface, Errors) {
  const Grid flat = make_grid({0, 0}, {1, 1}, {4, 4});
  EXPECT_THROW(extract_isosurface(flat, Eigen::VectorXd::Zero(16)), std::invalid_argument);
  const Grid cube = make_grid({0, 0, 0}, {1, 1, 1}, {4, 4, 4});
  EXPECT_THROW(extract_isosurface(cube, Eigen::VectorXd::Zero(63)), std::invalid_argument);
  EXPECT_THROW(extract_contour_lines(cube, Eigen::VectorXd::Zero(64)), std::invalid_argument);
  EXPECT_THROW(mesh_distance(Eigen::MatrixXd::Zero(1, 3), TriangleMesh{}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::io
