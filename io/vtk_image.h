// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>
#include <map>
#include <string>

#include "io/grid.h"
#include "io/point_arrays.h"

namespace nfield::io {

// Writes `grid` and its point arrays (each with grid.point_count() rows, in grid order) as a
// VTK XML image file (.vti: appended raw binary, zlib compressed), atomically (see
// io/atomic_write.h). An array named "Normals" with 3 columns is marked as the normals.
// `field_data`: numbers about the whole dataset (a frame's error), as one-value arrays of
// its field data, which ParaView lists beside the point arrays and plots over time.
// Throws std::invalid_argument for an array of the wrong size and std::runtime_error naming
// `path` when writing fails.
using FieldData = std::map<std::string, double, std::less<>>;
void write_vti(const std::filesystem::path& path, const Grid& grid, const PointArrays& arrays,
               Precision precision = Precision::kFloat64, const FieldData& field_data = {});

// The grid and the numeric point arrays of a .vti file (any numeric type, read as double; a
// direction matrix, if any, is ignored).
// Throws std::runtime_error naming `path` when it is missing or not VTK image data.
struct ImageData {
  Grid grid;
  PointArrays arrays;
  FieldData field_data;  // one-value numeric field-data arrays
};
ImageData read_vti(const std::filesystem::path& path);

}  // namespace nfield::io
