// SPDX-License-Identifier: MIT
//
// A latitude–longitude triangulation of the ellipsoid (x/a)² + (y/b)² + (z/c)² = 1 with
// (a, b, c) = r · scale (the sphere |x| = r by default), outward winding: reference meshes and
// small families of shapes for the sdf tests.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include "io/triangle_mesh.h"

namespace nfield::testutil {

inline io::TriangleMesh sphere_mesh(double r, int rings = 48, int segments = 96,
                                    const Eigen::Vector3d& scale = Eigen::Vector3d::Ones()) {
  constexpr double kPi = std::numbers::pi;
  io::TriangleMesh mesh;
  const int n = 2 + (rings - 1) * segments;
  mesh.vertices.resize(n, 3);
  mesh.vertices.row(0) << 0, 0, r;
  mesh.vertices.row(n - 1) << 0, 0, -r;
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = kPi * i / rings, phi = 2 * kPi * j / segments;
      mesh.vertices.row(1 + (i - 1) * segments + j) << r * std::sin(theta) * std::cos(phi),
          r * std::sin(theta) * std::sin(phi), r * std::cos(theta);
    }
  mesh.vertices = mesh.vertices * scale.asDiagonal();
  std::vector<Eigen::Vector3i> tris;
  auto at = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    tris.emplace_back(0, at(1, j), at(1, j + 1));
    tris.emplace_back(n - 1, at(rings - 1, j + 1), at(rings - 1, j));
  }
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      tris.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      tris.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  mesh.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t k = 0; k < tris.size(); ++k) mesh.triangles.row(static_cast<Eigen::Index>(k)) = tris[k].transpose();
  return mesh;
}

}  // namespace nfield::testutil
