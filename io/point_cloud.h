// SPDX-License-Identifier: MIT
#pragma once
#include <filesystem>

#include <Eigen/Core>

namespace nfield::io {

// Surface samples with their normals (unit length, or zero where none could be found).
struct OrientedPoints {
  Eigen::MatrixXd points;   // n×3
  Eigen::MatrixXd normals;  // n×3
};

// Reads oriented points, chosen by extension (case-insensitive):
//  .xyz, .pwn   text, "x y z nx ny nz" per line; blank lines and '#' comments skipped;
//  .ply, .obj, .vtp   through VTK: the points and their normals; a mesh without normals gets
//               normals computed from its faces (see vertex_normals in io/triangle_mesh.h);
//  .off         a mesh, its normals computed likewise unless it is an NOFF.
// Normals are scaled to unit length. Throws std::runtime_error naming `path` when it is
// missing, malformed (a text error names the line), without normals or faces to compute them
// from, or its extension is none of the above (the message lists them).
OrientedPoints read_oriented_points(const std::filesystem::path& path);

}  // namespace nfield::io
