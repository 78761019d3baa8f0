// SPDX-License-Identifier: MIT
#include "io/inside_mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace nfield::io {

Eigen::Array<bool, Eigen::Dynamic, 1> inside_closed_mesh(const Grid& grid, const TriangleMesh& mesh) {
  if (grid.dimension() != 3) throw std::invalid_argument("inside_closed_mesh: the grid must be 3D");
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  // Line (j, k) runs along x at y_j, z_k, nudged off the mesh's edges and vertices.
  const double dy = grid.spacing[1] * 1e-6 * 0.7071067811865476, dz = grid.spacing[2] * 1e-6 * 0.5772156649015329;
  const auto line_y = [&](int j) { return grid.origin[1] + j * grid.spacing[1] + dy; };
  const auto line_z = [&](int k) { return grid.origin[2] + k * grid.spacing[2] + dz; };
  std::vector<std::vector<double>> crossings(static_cast<size_t>(ny) * nz);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t) {
    const Eigen::RowVector3d a = mesh.vertices.row(mesh.triangles(t, 0));
    const Eigen::RowVector3d b = mesh.vertices.row(mesh.triangles(t, 1));
    const Eigen::RowVector3d c = mesh.vertices.row(mesh.triangles(t, 2));
    // Twice the signed area of the projection onto (y, z); edge-on triangles cross no line.
    const double area = (b(1) - a(1)) * (c(2) - a(2)) - (b(2) - a(2)) * (c(1) - a(1));
    if (area == 0) continue;
    const double y0 = std::min({a(1), b(1), c(1)}), y1 = std::max({a(1), b(1), c(1)});
    const double z0 = std::min({a(2), b(2), c(2)}), z1 = std::max({a(2), b(2), c(2)});
    const int j0 = std::max(0, static_cast<int>(std::ceil((y0 - dy - grid.origin[1]) / grid.spacing[1])));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((y1 - dy - grid.origin[1]) / grid.spacing[1])));
    const int k0 = std::max(0, static_cast<int>(std::ceil((z0 - dz - grid.origin[2]) / grid.spacing[2])));
    const int k1 = std::min(nz - 1, static_cast<int>(std::floor((z1 - dz - grid.origin[2]) / grid.spacing[2])));
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j) {
        const double y = line_y(j), z = line_z(k);
        // Barycentric weights of (y, z) in the projection.
        const double wa = ((b(1) - y) * (c(2) - z) - (b(2) - z) * (c(1) - y)) / area;
        const double wb = ((c(1) - y) * (a(2) - z) - (c(2) - z) * (a(1) - y)) / area;
        const double wc = 1.0 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        crossings[static_cast<size_t>(k) * ny + j].push_back(wa * a(0) + wb * b(0) + wc * c(0));
      }
  }
  Eigen::Array<bool, Eigen::Dynamic, 1> inside = Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(grid.point_count(), false);
#pragma omp parallel for schedule(dynamic, 64)
  for (long line = 0; line < static_cast<long>(crossings.size()); ++line) {
    std::vector<double>& xs = crossings[line];
    if (xs.empty()) continue;
    std::sort(xs.begin(), xs.end());
    size_t below = 0;
    const Eigen::Index first = static_cast<Eigen::Index>(line) * nx;
    for (int i = 0; i < nx; ++i) {
      const double x = grid.origin[0] + i * grid.spacing[0];
      while (below < xs.size() && xs[below] < x) ++below;
      inside(first + i) = below % 2 == 1;
    }
  }
  return inside;
}

}  // namespace nfield::io
