// SPDX-License-Identifier: MIT
#include "io/vtk_polydata.h"

#include <stdexcept>

#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::expect_error;
using testing::file_names;
using testing::read_text;
using testing::scratch_dir;

TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices.resize(4, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.triangles.resize(4, 3);
  m.triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return m;
}

TEST(VtkPolyData, PointCloudRoundTripsWithVertexCells) {
  const auto dir = scratch_dir();
  const Eigen::MatrixXd points = Eigen::MatrixXd::Random(50, 3);
  const PointArrays arrays{{"u", Eigen::MatrixXd::Random(50, 1)},
                           {"Normals", Eigen::MatrixXd::Random(50, 3)}};
  write_vtp_points(dir / "p.vtp", points, arrays);
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"p.vtp"});
  EXPECT_NE(read_text(dir / "p.vtp").find("vtkZLibDataCompressor"), std::string::npos);

  vtkNew<vtkXMLPolyDataReader> reader;  // what ParaView sees
  reader->SetFileName((dir / "p.vtp").c_str());
  reader->Update();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfVerts(), 50);
  EXPECT_NE(reader->GetOutput()->GetPointData()->GetNormals(), nullptr);

  const PolyData back = read_vtp(dir / "p.vtp");
  EXPECT_EQ(back.points, points);
  EXPECT_EQ(back.triangles.rows(), 0);
  EXPECT_EQ(back.lines.rows(), 0);
  EXPECT_EQ(back.arrays.at("u"), arrays.at("u"));
  EXPECT_EQ(back.arrays.at("Normals"), arrays.at("Normals"));
}

TEST(VtkPolyData, MeshAndLinesRoundTrip) {
  const auto dir = scratch_dir();
  TriangleMesh mesh = tetrahedron();
  mesh.normals = Eigen::MatrixXd::Random(4, 3);
  write_vtp_mesh(dir / "m.vtp", mesh, {{"u", Eigen::MatrixXd::Random(4, 1)}}, Precision::kFloat32);
  const PolyData back = read_vtp(dir / "m.vtp");
  EXPECT_EQ(back.points, mesh.vertices);
  EXPECT_EQ(back.triangles, mesh.triangles);
  EXPECT_EQ(back.arrays.at("Normals"), mesh.normals.cast<float>().cast<double>());
  EXPECT_EQ(back.arrays.size(), 2u);

  PolyData lines;
  lines.points.resize(3, 2);
  lines.points << 0, 0, 1, 0, 1, 1;
  lines.lines.resize(2, 2);
  lines.lines << 0, 1, 1, 2;
  write_vtp(dir / "l.vtp", lines);
  const PolyData l = read_vtp(dir / "l.vtp");
  EXPECT_EQ(l.lines, lines.lines);
  EXPECT_EQ(l.points.leftCols(2), lines.points);
  EXPECT_EQ(l.points.col(2), Eigen::Vector3d::Zero());
}

TEST(VtkPolyData, PlyIsBinaryAndReadsBackWithVtk) {
  const auto dir = scratch_dir();
  const TriangleMesh mesh = tetrahedron();
  write_ply(dir / "m.ply", mesh);
  EXPECT_EQ(read_text(dir / "m.ply").rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  vtkNew<vtkPLYReader> reader;
  reader->SetFileName((dir / "m.ply").c_str());
  reader->Update();
  vtkPolyData* out = reader->GetOutput();
  ASSERT_EQ(out->GetNumberOfPoints(), 4);
  ASSERT_EQ(out->GetNumberOfPolys(), 4);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(out->GetPoint(i)[k], mesh.vertices(i, k));
  vtkNew<vtkIdList> ids;
  for (int t = 0; t < 4; ++t) {
    out->GetCellPoints(t, ids);
    ASSERT_EQ(ids->GetNumberOfIds(), 3);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(ids->GetId(k), mesh.triangles(t, k));
  }
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"m.ply"});
}

TEST(VtkPolyData, Errors) {
  const auto dir = scratch_dir();
  TriangleMesh bad = tetrahedron();
  bad.triangles(0, 0) = 4;
  expect_error<std::invalid_argument>([&] { write_vtp_mesh(dir / "m.vtp", bad); },
                                      {"m.vtp", "outside"});
  expect_error<std::invalid_argument>(
      [&] {
        write_vtp_points(dir / "p.vtp", Eigen::MatrixXd::Zero(3, 3),
                         {{"u", Eigen::MatrixXd::Zero(2, 1)}});
      },
      {"p.vtp", "'u'"});
  expect_error<std::invalid_argument>(
      [&] { write_vtp_points(dir / "p.vtp", Eigen::MatrixXd::Zero(3, 4)); }, {"p.vtp", "columns"});
  EXPECT_TRUE(file_names(dir).empty());
  expect_error<std::runtime_error>([&] { read_vtp(dir / "none.vtp"); },
                                   {"none.vtp", "no such file"});
  write_ply(dir / "m.ply", tetrahedron());
  expect_error<std::runtime_error>([&] { read_vtp(dir / "m.ply"); }, {"m.ply", ".vtp"});
  std::filesystem::copy(dir / "m.ply", dir / "fake.vtp");
  expect_error<std::runtime_error>([&] { read_vtp(dir / "fake.vtp"); },
                                   {"fake.vtp", "not a VTK XML polydata"});
}

}  // namespace
}  // namespace nfield::io
