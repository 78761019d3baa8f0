// SPDX-License-Identifier: MIT
//
// Triangles as a VTK XML unstructured grid (.vtu): the 2-D domain outputs of
// solvers/output/domain_output.h. A .vtu rather than a .vtp with polygons because ParaView
// treats an unstructured grid as a volume (area) dataset: its filters for cells (Integrate
// Variables gives the area, Cell Size, Mesh Quality) apply, and it is what the issue asked for.
#pragma once
#include <filesystem>

#include <Eigen/Core>

#include "io/point_arrays.h"

namespace nfield::io {

struct TriangleGrid {
  Eigen::MatrixXd points;                           // n×3 (n×2 accepted for writing: z = 0)
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  // point indices of each triangle
  PointArrays arrays;                               // each with one row per point
};

// Writes a .vtu (appended raw binary, zlib) atomically (io/atomic_write.h). Throws
// std::invalid_argument for arrays of the wrong size or indices out of range,
// std::runtime_error naming `path` when writing fails.
void write_vtu(const std::filesystem::path& path, const TriangleGrid& data,
               Precision precision = Precision::kFloat64);

// Reads a .vtu whose cells are triangles (others are skipped). Throws std::runtime_error
// naming `path` when it is missing or not an unstructured grid.
TriangleGrid read_vtu(const std::filesystem::path& path);

}  // namespace nfield::io
