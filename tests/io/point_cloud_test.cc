// SPDX-License-Identifier: MIT
#include "io/point_cloud.h"

#include <stdexcept>

#include <gtest/gtest.h>

#include "io/triangle_mesh.h"
#include "io/vtk_polydata.h"
#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::data_path;
using testing::expect_error;
using testing::scratch_dir;
using testing::write_text;

// Mean of dot(normal, point - centroid): positive when the normals point outward.
double outwardness(const OrientedPoints& p) {
  const Eigen::RowVector3d c = p.points.colwise().mean();
  return (p.normals.array() * (p.points.rowwise() - c).array()).rowwise().sum().mean();
}

void expect_unit_normals(const OrientedPoints& p) {
  ASSERT_EQ(p.normals.rows(), p.points.rows());
  ASSERT_EQ(p.normals.cols(), 3);
  EXPECT_LT((p.normals.rowwise().norm().array() - 1).abs().maxCoeff(), 1e-6);
}

const char* kCubeOff =
    "OFF\n"
    "# a unit cube of quads\n"
    "8 6 12\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";

TEST(PointCloud, ReadsKittenXyz) {
  const OrientedPoints p = read_oriented_points(data_path("points/kitten.xyz"));
  EXPECT_EQ(p.points.rows(), 5210);
  expect_unit_normals(p);
  EXPECT_EQ(p.points.row(0), Eigen::RowVector3d(-0.0721898, -0.159749, -0.108444));
  EXPECT_GT(outwardness(p), 0);
}

TEST(PointCloud, BunnyPlyGetsOutwardNormalsFromItsFaces) {
  const OrientedPoints p = read_oriented_points(data_path("meshes/bunny00.ply"));
  EXPECT_EQ(p.points.rows(), 37706);
  expect_unit_normals(p);
  EXPECT_GT(outwardness(p), 0);

  const TriangleMesh mesh = read_triangle_mesh(data_path("meshes/bunny00.ply"));
  EXPECT_EQ(mesh.vertices.rows(), 37706);
  EXPECT_EQ(mesh.triangles.rows(), 75408);
  EXPECT_EQ(mesh.normals.size(), 0);
  EXPECT_EQ(mesh.vertices, p.points);
}

TEST(PointCloud, XyzSkipsCommentsAndBlankLines) {
  const auto dir = scratch_dir();
  write_text(dir / "a.pwn", "# header\n\n1 2 3 0 0 2\n  \n4 5 6 0 -1 0 # trailing\n");
  const OrientedPoints p = read_oriented_points(dir / "a.pwn");
  ASSERT_EQ(p.points.rows(), 2);
  EXPECT_EQ(p.points.row(1), Eigen::RowVector3d(4, 5, 6));
  EXPECT_EQ(p.normals.row(0), Eigen::RowVector3d(0, 0, 1));  // normalised
}

TEST(PointCloud, MeshFormatsAndInsideOutMeshes) {
  const auto dir = scratch_dir();
  write_text(dir / "cube.off", kCubeOff);
  const TriangleMesh cube = read_triangle_mesh(dir / "cube.off");
  EXPECT_EQ(cube.vertices.rows(), 8);
  EXPECT_EQ(cube.triangles.rows(), 12);
  const OrientedPoints p = read_oriented_points(dir / "cube.off");
  expect_unit_normals(p);
  EXPECT_GT(outwardness(p), 0);

  // The same cube turned inside out still gets outward normals.
  TriangleMesh flipped = cube;
  flipped.triangles.col(1).swap(flipped.triangles.col(2));
  const Eigen::MatrixXd n = vertex_normals(flipped);
  EXPECT_GT(outwardness({cube.vertices, n}), 0);
  EXPECT_TRUE(n.isApprox(p.normals, 1e-6));

  // .obj, a .vtp mesh, and a .vtp cloud with normals.
  write_text(dir / "t.obj",
             "# tetra\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
             "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const TriangleMesh tet = read_triangle_mesh(dir / "t.obj");
  EXPECT_EQ(tet.vertices.rows(), 4);
  EXPECT_EQ(tet.triangles.rows(), 4);
  EXPECT_GT(outwardness(read_oriented_points(dir / "t.obj")), 0);
  write_vtp_mesh(dir / "cube.vtp", cube);
  EXPECT_EQ(read_triangle_mesh(dir / "cube.vtp").triangles, cube.triangles);
  EXPECT_TRUE(read_oriented_points(dir / "cube.vtp").normals.isApprox(p.normals, 1e-6));
  write_vtp_points(dir / "cloud.vtp", p.points, {{"Normals", 2 * p.normals}});
  EXPECT_TRUE(read_oriented_points(dir / "cloud.vtp").normals.isApprox(p.normals, 1e-6));
}

TEST(PointCloud, PlyPointCloudWithNormals) {
  const auto dir = scratch_dir();
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\n";
  write_text(dir / "n.ply", header +
                                "property float nx\nproperty float ny\nproperty float nz\n"
                                "end_header\n0 0 0 0 0 3\n1 2 3 1 0 0\n");
  const OrientedPoints p = read_oriented_points(dir / "n.ply");
  ASSERT_EQ(p.points.rows(), 2);
  EXPECT_EQ(p.points.row(1), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(p.normals.row(0), Eigen::RowVector3d(0, 0, 1));
  write_text(dir / "bare.ply", header + "end_header\n0 0 0\n1 2 3\n");
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "bare.ply"); },
                                   {"bare.ply", "no normals"});
}

TEST(PointCloud, Errors) {
  const auto dir = scratch_dir();
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "none.xyz"); },
                                   {"none.xyz", "no such file"});
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "none.ply"); },
                                   {"none.ply", "no such file"});
  expect_error<std::runtime_error>([&] { read_triangle_mesh(dir / "none.off"); },
                                   {"none.off", "no such file"});
  write_text(dir / "bad.xyz", "0 0 0 0 0 1\n# ok\n1 2 3 4 5\n");
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "bad.xyz"); },
                                   {"bad.xyz", "line 3", "6 numbers"});
  write_text(dir / "word.xyz", "0 0 0 0 0 x\n");
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "word.xyz"); },
                                   {"word.xyz", "line 1"});
  expect_error<std::runtime_error>([&] { read_oriented_points(dir / "a.stl"); },
                                   {"a.stl", ".stl", ".xyz, .pwn, .ply, .obj, .off, .vtp"});
  expect_error<std::runtime_error>([&] { read_triangle_mesh(dir / "a.xyz"); },
                                   {"a.xyz", ".ply, .obj, .off, .vtp"});
  std::string off = kCubeOff;
  off.replace(off.find("4 0 3 2 1"), 9, "4 0 3 2 9");
  write_text(dir / "bad.off", off);
  expect_error<std::runtime_error>([&] { read_triangle_mesh(dir / "bad.off"); },
                                   {"bad.off", "line 12", "vertex index 9 is not one of 0..7"});
  write_text(dir / "short.off", "OFF\n8 6 0\n0 0 0\n");
  expect_error<std::runtime_error>([&] { read_triangle_mesh(dir / "short.off"); },
                                   {"short.off", "ends before vertex 1"});
  write_text(dir / "text.ply", "hello\n");
  expect_error<std::runtime_error>([&] { read_triangle_mesh(dir / "text.ply"); },
                                   {"text.ply", "not a PLY"});
}

}  // namespace
}  // namespace nfield::io
