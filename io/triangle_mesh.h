// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>

#include <Eigen/Core>

namespace nfield::io {

// A surface of triangles over shared vertices.
struct TriangleMesh {
  Eigen::MatrixXd vertices;                         // n×3
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  // m×3 vertex indices
  Eigen::MatrixXd normals;                          // n×3 per-vertex normals, or 0×0 if none
};

// Reads .ply, .obj, .stl and .vtp (through VTK) and .off (including COFF, NOFF, CNOFF), chosen by
// extension (case-insensitive). Polygons are split into triangles; lines and vertex cells are
// ignored. `normals` are the file's per-vertex normals if it has them, else empty. Throws
// std::runtime_error naming `path` when it is missing or malformed (an .off error also names
// the line), or when the extension is not one of those above.
TriangleMesh read_triangle_mesh(const std::filesystem::path& path);

// Per-vertex unit normals computed from the triangles (vtkPolyDataNormals, without splitting
// vertices): triangle orientations are made consistent across each connected surface, then the
// normals are flipped if needed so that the enclosed signed volume is positive, i.e. they
// point outward on a closed surface. Vertices on no triangle get a zero normal.
Eigen::MatrixXd vertex_normals(const TriangleMesh& mesh);

}  // namespace nfield::io
