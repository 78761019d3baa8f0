// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>

#include <Eigen/Core>

#include "io/point_arrays.h"
#include "io/poly_data.h"
#include "io/triangle_mesh.h"

namespace nfield::io {

// Writes a VTK XML polydata file (.vtp: appended raw binary, zlib compressed) atomically (see
// io/atomic_write.h). With neither lines nor triangles, every point is also written as a
// vertex cell so that ParaView draws the cloud. An array named "Normals" with 3 columns is
// marked as the normals. Throws std::invalid_argument for arrays of the wrong size or indices
// out of range, std::runtime_error naming `path` when writing fails.
void write_vtp(const std::filesystem::path& path, const PolyData& data,
               Precision precision = Precision::kFloat64);
// A point cloud: write_vtp with points and arrays only.
void write_vtp_points(const std::filesystem::path& path, const Eigen::MatrixXd& points,
                      const PointArrays& arrays = {}, Precision precision = Precision::kFloat64);
// A triangle mesh; non-empty mesh.normals are written as the array "Normals".
void write_vtp_mesh(const std::filesystem::path& path, const TriangleMesh& mesh,
                    const PointArrays& arrays = {}, Precision precision = Precision::kFloat64);

// Reads a .vtp file: polygons and strips come back as triangles, polylines as segments, vertex
// cells are dropped (their points stay). Throws std::runtime_error naming `path` when it is
// missing or not VTK polydata.
PolyData read_vtp(const std::filesystem::path& path);

// Writes a binary little-endian Stanford .ply of the vertices (float32) and triangles,
// atomically. VTK's PLY writer has no normals, so mesh.normals are not written.
void write_ply(const std::filesystem::path& path, const TriangleMesh& mesh);

}  // namespace nfield::io
