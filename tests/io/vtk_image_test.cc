// SPDX-License-Identifier: MIT
#include "io/vtk_image.h"

#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::expect_error;
using testing::file_names;
using testing::read_text;
using testing::scratch_dir;
using testing::write_text;

TEST(VtkImage, RoundTripsGridAndArraysExactly) {
  const auto dir = scratch_dir();
  const Grid grid{{5, 4, 3}, {-1, 0.5, 2}, {0.25, 0.5, 0.125}};
  const Eigen::Index n = grid.point_count();
  PointArrays arrays{{"u", Eigen::MatrixXd::Random(n, 1)},
                     {"v2", Eigen::MatrixXd::Random(n, 2)},
                     {"gradient", Eigen::MatrixXd::Random(n, 3)},
                     {"Normals", Eigen::MatrixXd::Random(n, 3)}};
  write_vti(dir / "f.vti", grid, arrays);
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"f.vti"});
  const std::string text = read_text(dir / "f.vti");
  EXPECT_NE(text.find("format=\"appended\""), std::string::npos);
  EXPECT_NE(text.find("vtkZLibDataCompressor"), std::string::npos);
  EXPECT_NE(text.find("type=\"Float64\""), std::string::npos);

  const ImageData back = read_vti(dir / "f.vti");
  EXPECT_EQ(back.grid.dims, grid.dims);
  EXPECT_EQ(back.grid.origin, grid.origin);
  EXPECT_EQ(back.grid.spacing, grid.spacing);
  ASSERT_EQ(back.arrays.size(), arrays.size());
  for (const auto& [name, m] : arrays) EXPECT_EQ(require_array(back.arrays, name, ""), m) << name;
}

TEST(VtkImage, Float32StoresRoundedValues) {
  const auto dir = scratch_dir();
  const Grid grid{{7, 6, 1}, {}, {0.1, 0.2, 1}};
  const Eigen::MatrixXd u = Eigen::MatrixXd::Random(42, 1);
  write_vti(dir / "f.vti", grid, {{"u", u}}, Precision::kFloat32);
  EXPECT_NE(read_text(dir / "f.vti").find("type=\"Float32\""), std::string::npos);
  const ImageData back = read_vti(dir / "f.vti");
  EXPECT_EQ(back.grid.dims, grid.dims);
  EXPECT_EQ(back.arrays.at("u"), u.cast<float>().cast<double>());
}

TEST(VtkImage, OverwritesAnOldFile) {
  const auto dir = scratch_dir();
  const Grid grid{{2, 2, 2}, {}, {1, 1, 1}};
  write_vti(dir / "f.vti", grid, {{"u", Eigen::MatrixXd::Zero(8, 1)}});
  write_vti(dir / "f.vti", grid, {{"u", Eigen::MatrixXd::Ones(8, 1)}});
  EXPECT_EQ(read_vti(dir / "f.vti").arrays.at("u"), Eigen::MatrixXd::Ones(8, 1));
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"f.vti"});
}

TEST(VtkImage, Errors) {
  const auto dir = scratch_dir();
  const Grid grid{{2, 2, 1}, {}, {1, 1, 1}};
  expect_error<std::invalid_argument>(
      [&] {
        write_vti(dir / "f.vti", grid, {{"u", Eigen::MatrixXd::Zero(3, 1)}});
      },
      {"f.vti", "'u'"});
  EXPECT_TRUE(file_names(dir).empty());
  expect_error<std::runtime_error>([&] { write_vti(dir / "none" / "f.vti", grid, {}); },
                                   {"f.vti", "does not exist"});
  expect_error<std::runtime_error>([&] { read_vti(dir / "missing.vti"); },
                                   {"missing.vti", "no such file"});
  write_text(dir / "text.vti", "hello\n");
  expect_error<std::runtime_error>([&] { read_vti(dir / "text.vti"); },
                                   {"text.vti", "not a VTK XML image data"});
  write_vti(dir / "f.vti", grid, {{"u", Eigen::MatrixXd::Zero(4, 1)}});
  const std::string whole = read_text(dir / "f.vti");
  write_text(dir / "cut.vti", whole.substr(0, whole.size() - 40));
  expect_error<std::runtime_error>([&] { read_vti(dir / "cut.vti"); }, {"cut.vti"});
  const ImageData back = read_vti(dir / "f.vti");
  expect_error<std::runtime_error>([&] { require_array(back.arrays, "w", dir / "f.vti"); },
                                   {"f.vti", "'w'", "present: u"});
}

}  // namespace
}  // namespace nfield::io
