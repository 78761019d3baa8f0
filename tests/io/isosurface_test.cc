// SPDX-License-Identifier: MIT
#include "io/isosurface.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <vtkImplicitPolyDataDistance.h>
#include <vtkNew.h>
#include <vtkPolyData.h>

#include "io/inside_mesh.h"
#include "io/mesh_distance.h"
#include "io/vtk_convert.h"
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

// Two level sets of distances to concentric spheres, radii 0.5 and 0.6: every vertex of one
// is 0.1 from the other (to the marching-cubes error), and their normals agree.
TEST(Isosurface, CompareConcentricSpheres) {
  const Grid grid = make_grid({-1, -1, -1}, {1, 1, 1}, {40, 40, 40});
  const Eigen::VectorXd r = grid.points(3).rowwise().norm();
  const TriangleMesh inner = extract_isosurface(grid, r.array() - 0.5, 0.0, true);
  const TriangleMesh outer = extract_isosurface(grid, r.array() - 0.6, 0.0, true);
  const SurfaceComparison c = compare_surfaces(inner, outer);
  ASSERT_EQ(c.a_to_b.size(), inner.vertices.rows());
  ASSERT_EQ(c.b_to_a.size(), outer.vertices.rows());
  EXPECT_NEAR(c.a_to_b.mean(), 0.1, 0.005);
  EXPECT_NEAR(c.b_to_a.mean(), 0.1, 0.005);
  EXPECT_NEAR(c.chamfer_mean(), 0.1, 0.005);
  EXPECT_LT(c.chamfer_max(), 0.11);
  EXPECT_GT(c.normal_consistency, 0.99);
  // Threads give the same numbers as one.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const SurfaceComparison serial = compare_surfaces(inner, outer);
  omp_set_num_threads(std::max(2, threads));
  const SurfaceComparison parallel = compare_surfaces(inner, outer);
  omp_set_num_threads(threads);
  EXPECT_EQ(serial.a_to_b, parallel.a_to_b);
  EXPECT_EQ(serial.b_to_a, parallel.b_to_a);
  EXPECT_EQ(serial.normal_consistency, parallel.normal_consistency);
}

// Normal consistency tells crossing surfaces from parallel ones: the squares z = 0 and x = 0
// (through each other) have perpendicular normals everywhere, so 0; z = 0 against z = 0.1, 1.
TEST(Isosurface, NormalConsistencyOfPlanes) {
  const auto square = [](int normal_axis, double offset) {
    TriangleMesh m;
    const int n = 8;
    m.vertices.resize((n + 1) * (n + 1), 3);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        Eigen::RowVector3d p;
        p(normal_axis) = offset;
        p((normal_axis + 1) % 3) = -1 + 2.0 * i / n;
        p((normal_axis + 2) % 3) = -1 + 2.0 * j / n;
        m.vertices.row(j * (n + 1) + i) = p;
      }
    m.triangles.resize(2 * n * n, 3);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int v = j * (n + 1) + i;
        m.triangles.row(2 * (j * n + i)) << v, v + 1, v + n + 2;
        m.triangles.row(2 * (j * n + i) + 1) << v, v + n + 2, v + n + 1;
      }
    return m;
  };
  EXPECT_NEAR(compare_surfaces(square(2, 0), square(0, 0)).normal_consistency, 0.0, 1e-12);
  const SurfaceComparison parallel = compare_surfaces(square(2, 0), square(2, 0.1));
  EXPECT_NEAR(parallel.normal_consistency, 1.0, 1e-12);
  EXPECT_NEAR(parallel.chamfer_mean(), 0.1, 1e-12);
  // Unit normals of each triangle, right-handed: +z for these.
  const Eigen::MatrixXd normals = triangle_normals(square(2, 0));
  EXPECT_NEAR((normals.col(2).array() - 1).abs().maxCoeff(), 0.0, 1e-12);
  EXPECT_THROW(compare_surfaces(square(2, 0), TriangleMesh{}), std::invalid_argument);
}

TEST(Isosurface, PointCloudDistanceIsTheNearestPoint) {
  std::srand(7);
  const Eigen::MatrixXd cloud = Eigen::MatrixXd::Random(500, 3), points = Eigen::MatrixXd::Random(200, 3);
  const Eigen::VectorXd d = point_cloud_distance(points, cloud);
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    EXPECT_DOUBLE_EQ(d(i), std::sqrt((cloud.rowwise() - points.row(i)).rowwise().squaredNorm().minCoeff())) << i;
  EXPECT_THROW(point_cloud_distance(points, Eigen::MatrixXd(0, 3)), std::invalid_argument);
}

// Inside a closed mesh by crossing parity: the icosphere of radius 0.5 (flat faces up to
// 0.008 inside the sphere) holds the grid points with r < 0.49 and none with r > 0.5; the
// bunny agrees with VTK's implicit signed distance wherever that is not within 1e-3 of 0.
TEST(Isosurface, InsideClosedMesh) {
  const TriangleMesh sphere = read_triangle_mesh(data_path("meshes/sphere.ply"));
  const Grid grid = make_grid({-0.7, -0.6, -0.65}, {0.7, 0.6, 0.65}, {41, 37, 29});
  const auto inside = inside_closed_mesh(grid, sphere);
  const Eigen::VectorXd r = grid.points(3).rowwise().norm();
  Eigen::Index count = 0;
  for (Eigen::Index p = 0; p < r.size(); ++p) {
    if (r(p) < 0.49) EXPECT_TRUE(inside(p)) << p;
    if (r(p) > 0.5) EXPECT_FALSE(inside(p)) << p;
    count += inside(p);
  }
  EXPECT_GT(count, 0);

  const TriangleMesh bunny = read_triangle_mesh(data_path("meshes/bunny00.ply"));
  const Eigen::RowVector3d lo = bunny.vertices.colwise().minCoeff(), hi = bunny.vertices.colwise().maxCoeff();
  const Grid box = make_grid({lo(0) - 0.01, lo(1) - 0.01, lo(2) - 0.01}, {hi(0) + 0.01, hi(1) + 0.01, hi(2) + 0.01},
                             {23, 21, 19});
  const auto in_bunny = inside_closed_mesh(box, bunny);
  vtkNew<vtkImplicitPolyDataDistance> distance;
  distance->SetInput(to_vtk_polydata(PolyData{bunny.vertices, {}, bunny.triangles, {}}, Precision::kFloat64));
  double outside_probe[3] = {hi(0) + 10, hi(1), hi(2)};
  const double orientation = distance->EvaluateFunction(outside_probe) < 0 ? -1.0 : 1.0;
  const Eigen::MatrixXd x = box.points(3);
  Eigen::Index compared = 0, inside_count = 0;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    double q[3] = {x(p, 0), x(p, 1), x(p, 2)};
    const double d = orientation * distance->EvaluateFunction(q);
    if (std::abs(d) < 1e-3) continue;
    ++compared;
    inside_count += d < 0;
    EXPECT_EQ(in_bunny(p), d < 0) << "point " << p << ", signed distance " << d;
  }
  EXPECT_GT(compared, 8000);
  EXPECT_GT(inside_count, 1000);
}

TEST(Isosurface, NearMesh) {
  const TriangleMesh sphere = read_triangle_mesh(data_path("meshes/sphere.ply"));
  Eigen::MatrixXd p(4, 3);
  p << 0, 0, 0, 0.55, 0, 0, 0.62, 0, 0, 0, 0, 0.45;
  const auto near = near_mesh(p, sphere, 0.1);
  const Eigen::VectorXd d = mesh_distance(p, sphere);
  for (Eigen::Index i = 0; i < 4; ++i) EXPECT_EQ(near(i), d(i) < 0.1) << i << ": " << d(i);
  // By blocks on a grid: the same answer as a query per point, for every point.
  const Grid grid = make_grid({-0.8, -0.7, -0.75}, {0.8, 0.7, 0.75}, {45, 37, 40});
  const Eigen::MatrixXd x = grid.points(3);
  const auto by_blocks = grid_near_mesh(grid, sphere, 0.12);
  const auto per_point = near_mesh(x, sphere, 0.12);
  EXPECT_EQ((by_blocks != per_point).count(), 0);
  EXPECT_GT(by_blocks.count(), 1000);
  EXPECT_LT(by_blocks.count(), x.rows() / 2);
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
