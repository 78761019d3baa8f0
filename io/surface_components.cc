// SPDX-License-Identifier: MIT
#include "io/surface_components.h"

#include <algorithm>
#include <numeric>
#include <vector>

#include <Eigen/Geometry>

namespace nfield::io {
namespace {

// Union–find over vertex indices (path halving, union by size). Not VTK's connectivity filter:
// it renumbers the points it keeps and colours them, not the input triangles, in VTK 9.1.
class DisjointSets {
 public:
  explicit DisjointSets(Eigen::Index n) : parent_(static_cast<size_t>(n)), size_(static_cast<size_t>(n), 1) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int v) {
    while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];
    return v;
  }
  void join(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<int> parent_, size_;
};

}  // namespace

SurfaceComponents surface_components(const TriangleMesh& mesh) {
  SurfaceComponents result;
  const Eigen::Index triangles = mesh.triangles.rows();
  if (triangles == 0) return result;
  DisjointSets sets(mesh.vertices.rows());
  for (Eigen::Index t = 0; t < triangles; ++t) {
    sets.join(mesh.triangles(t, 0), mesh.triangles(t, 1));
    sets.join(mesh.triangles(t, 0), mesh.triangles(t, 2));
  }
  std::vector<int> region(static_cast<size_t>(mesh.vertices.rows()), -1);
  std::vector<double> area;
  Eigen::VectorXi id(triangles);
  for (Eigen::Index t = 0; t < triangles; ++t) {
    int& r = region[static_cast<size_t>(sets.find(mesh.triangles(t, 0)))];
    if (r < 0) {
      r = static_cast<int>(area.size());
      area.push_back(0);
    }
    id(t) = r;
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.triangles(t, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.triangles(t, 2));
    area[static_cast<size_t>(r)] += 0.5 * (b - a).cross(c - a).norm();
  }
  const int count = static_cast<int>(area.size());
  std::vector<int> order(static_cast<size_t>(count));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&area](int i, int j) { return area[i] > area[j]; });
  std::vector<int> rank(static_cast<size_t>(count));
  for (int r = 0; r < count; ++r) rank[static_cast<size_t>(order[r])] = r;
  result.piece.resize(triangles);
  for (Eigen::Index t = 0; t < triangles; ++t) result.piece(t) = rank[static_cast<size_t>(id(t))];
  result.count = count;
  result.area = std::accumulate(area.begin(), area.end(), 0.0);
  result.largest_area_share = result.area > 0 ? area[static_cast<size_t>(order[0])] / result.area : 0;
  return result;
}

}  // namespace nfield::io
