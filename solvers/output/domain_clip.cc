// SPDX-License-Identifier: MIT
#include "solvers/output/domain_clip.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

namespace nfield::solvers {
namespace {

// The points of the clipped mesh as they are made: grid points once each, crossings once per
// grid edge.
class PointTable {
 public:
  PointTable(const io::Grid& grid, const std::function<bool(const Eigen::Vector2d&)>& contains, double tolerance)
      : grid_(grid), contains_(contains), tolerance_(tolerance),
        id_(static_cast<size_t>(grid.point_count()), -1) {}

  int grid_point(Eigen::Index g) {
    int& i = id_[static_cast<size_t>(g)];
    if (i < 0) i = add(xy(g), g);
    return i;
  }
  // The crossing on the edge from grid point a (inside) to b (outside); a itself when a lies
  // on ∂Ω (no point of the edge beyond a is inside).
  int crossing(Eigen::Index a, Eigen::Index b) {
    const auto key = static_cast<std::uint64_t>(std::min(a, b)) << 32 | static_cast<std::uint64_t>(std::max(a, b));
    const auto [at, is_new] = crossing_id_.try_emplace(key, -1);
    if (is_new) {
      const Eigen::Vector2d p = bisect(xy(a), xy(b));
      at->second = p == xy(a) ? grid_point(a) : add(p, -1);
    }
    return at->second;
  }

  std::vector<Eigen::Vector2d> points;
  std::vector<Eigen::Index> grid_index;

 private:
  Eigen::Vector2d xy(Eigen::Index g) const { return grid_.point(g).head<2>(); }
  int add(const Eigen::Vector2d& p, Eigen::Index g) {
    points.push_back(p);
    grid_index.push_back(g);
    return static_cast<int>(points.size()) - 1;
  }
  // The inside end of a bracket [in, out] halved to below the tolerance.
  Eigen::Vector2d bisect(Eigen::Vector2d in, Eigen::Vector2d out) const {
    while ((out - in).norm() > tolerance_) {
      const Eigen::Vector2d mid = 0.5 * (in + out);
      (contains_(mid) ? in : out) = mid;
    }
    return in;
  }

  const io::Grid& grid_;
  const std::function<bool(const Eigen::Vector2d&)>& contains_;
  double tolerance_;
  std::vector<int> id_;
  std::unordered_map<std::uint64_t, int> crossing_id_;
};

// Appends (p, q, r) unless it is degenerate: a repeated point (a corner on ∂Ω) or an area
// that rounds to zero or below (a crossing within rounding of a corner).
void append(const PointTable& table, int p, int q, int r, std::vector<std::array<int, 3>>& out) {
  if (p == q || q == r || r == p) return;
  const Eigen::Vector2d a = table.points[static_cast<size_t>(p)], b = table.points[static_cast<size_t>(q)],
                        c = table.points[static_cast<size_t>(r)];
  if ((b(0) - a(0)) * (c(1) - a(1)) - (b(1) - a(1)) * (c(0) - a(0)) <= 0) return;
  out.push_back({p, q, r});
}

// Appends triangle (a, b, c) of grid points (counter-clockwise), clipped.
void clip_one(const std::array<Eigen::Index, 3>& t, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
              PointTable& table, std::vector<std::array<int, 3>>& out) {
  int in_count = 0;
  for (const Eigen::Index g : t) in_count += inside(g) ? 1 : 0;
  if (in_count == 0) return;
  if (in_count == 3) {
    out.push_back({table.grid_point(t[0]), table.grid_point(t[1]), table.grid_point(t[2])});
    return;
  }
  // Rotate (keeping the orientation) so that t[0] is the lone inside corner (one inside) or
  // the lone outside corner is t[2] (two inside).
  int r = 0;
  for (int k = 0; k < 3; ++k) {
    const bool in = inside(t[static_cast<size_t>(k)]);
    if ((in_count == 1 && in) || (in_count == 2 && !in)) r = in_count == 1 ? k : (k + 1) % 3;
  }
  const Eigen::Index a = t[static_cast<size_t>(r)], b = t[static_cast<size_t>((r + 1) % 3)],
                     c = t[static_cast<size_t>((r + 2) % 3)];
  if (in_count == 1) {
    const int pa = table.grid_point(a), pab = table.crossing(a, b), pac = table.crossing(a, c);
    append(table, pa, pab, pac, out);
  } else {  // a, b inside, c outside
    const int pa = table.grid_point(a), pb = table.grid_point(b), pbc = table.crossing(b, c),
              pca = table.crossing(a, c);
    append(table, pa, pb, pbc, out);
    append(table, pa, pbc, pca, out);
  }
}

}  // namespace

std::vector<Eigen::Index> ClippedTriangles::crossings() const {
  std::vector<Eigen::Index> rows;
  for (size_t p = 0; p < grid_index.size(); ++p)
    if (grid_index[p] < 0) rows.push_back(static_cast<Eigen::Index>(p));
  return rows;
}

ClippedTriangles clip_triangles(const io::Grid& grid, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside,
                                const std::function<bool(const Eigen::Vector2d&)>& contains, double tolerance) {
  if (grid.dims[2] != 1 || inside.size() != grid.point_count() || !(tolerance > 0))
    throw std::invalid_argument("clip_triangles: a 2-D grid, one mask entry per point and a tolerance > 0");
  const int nx = grid.dims[0], ny = grid.dims[1];
  PointTable table(grid, contains, tolerance);
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const Eigen::Index a = i + static_cast<Eigen::Index>(nx) * j, b = a + 1, c = a + nx + 1, d = a + nx;
      clip_one({a, b, c}, inside, table, tris);
      clip_one({a, c, d}, inside, table, tris);
    }
  ClippedTriangles out;
  out.points.resize(static_cast<Eigen::Index>(table.points.size()), 2);
  for (size_t p = 0; p < table.points.size(); ++p) out.points.row(static_cast<Eigen::Index>(p)) = table.points[p];
  out.grid_index = std::move(table.grid_index);
  out.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t k = 0; k < tris.size(); ++k)
    for (int c = 0; c < 3; ++c) out.triangles(static_cast<Eigen::Index>(k), c) = tris[k][static_cast<size_t>(c)];
  return out;
}

double clip_tolerance(const io::Grid& grid) { return 1e-6 * std::min(grid.spacing[0], grid.spacing[1]); }

}  // namespace nfield::solvers
