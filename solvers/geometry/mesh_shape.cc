// SPDX-License-Identifier: MIT
#include "solvers/geometry/mesh_shape.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/Geometry>

#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>

#include "io/mesh_distance.h"
#include "io/vtk_convert.h"

namespace nfield::solvers::geometry {
namespace {
using Tri = Eigen::Matrix<int, Eigen::Dynamic, 3>;

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
}
std::string vertex_text(const Eigen::MatrixXd& v, int i) {
  std::ostringstream s;
  s << i << " (" << v(i, 0) << ", " << v(i, 1) << ", " << v(i, 2) << ")";
  return s.str();
}

// Triangles of each undirected edge; throws for holes and seams.
std::unordered_map<std::uint64_t, std::vector<int>> edge_triangles(const io::TriangleMesh& mesh) {
  std::unordered_map<std::uint64_t, std::vector<int>> edges;
  const Tri& t = mesh.triangles;
  for (int f = 0; f < t.rows(); ++f)
    for (int k = 0; k < 3; ++k) edges[edge_key(t(f, k), t(f, (k + 1) % 3))].push_back(f);
  int open = 0, seams = 0;
  std::uint64_t first_open = 0, first_seam = 0;
  for (const auto& [key, faces] : edges) {
    if (faces.size() == 1 && (open++ == 0 || key < first_open)) first_open = key;
    if (faces.size() > 2 && (seams++ == 0 || key < first_seam)) first_seam = key;
  }
  const auto ends = [&](std::uint64_t key) {
    return vertex_text(mesh.vertices, static_cast<int>(key >> 32)) + " and " +
           vertex_text(mesh.vertices, static_cast<int>(key & 0xffffffffu));
  };
  if (open > 0)
    throw std::invalid_argument("the surface is not closed: " + std::to_string(open) +
                                " boundary edge(s) (used by one triangle only), the first between vertices " +
                                ends(first_open));
  if (seams > 0)
    throw std::invalid_argument("the surface is not a manifold: " + std::to_string(seams) +
                                " edge(s) shared by more than two triangles, the first between vertices " +
                                ends(first_seam));
  return edges;
}

bool has_directed(const Tri& t, int f, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (t(f, k) == a && t(f, (k + 1) % 3) == b) return true;
  return false;
}

// Flips triangles so that neighbours traverse shared edges in opposite directions.
void orient(io::TriangleMesh& mesh, const std::unordered_map<std::uint64_t, std::vector<int>>& edges) {
  Tri& t = mesh.triangles;
  std::vector<char> seen(static_cast<size_t>(t.rows()), 0);
  for (int start = 0; start < t.rows(); ++start) {
    if (seen[static_cast<size_t>(start)]) continue;
    seen[static_cast<size_t>(start)] = 1;
    std::queue<int> todo;
    todo.push(start);
    while (!todo.empty()) {
      const int f = todo.front();
      todo.pop();
      for (int k = 0; k < 3; ++k) {
        const int a = t(f, k), b = t(f, (k + 1) % 3);
        for (int g : edges.at(edge_key(a, b))) {
          if (g == f) continue;
          const bool same = has_directed(t, g, a, b);
          if (seen[static_cast<size_t>(g)]) {
            if (same)
              throw std::invalid_argument("the surface cannot be oriented (a Möbius-like strip), at the edge between vertices " +
                                          vertex_text(mesh.vertices, a) + " and " + vertex_text(mesh.vertices, b));
            continue;
          }
          if (same) std::swap(t(g, 1), t(g, 2));
          seen[static_cast<size_t>(g)] = 1;
          todo.push(g);
        }
      }
    }
  }
}

Vec3 corner(const io::TriangleMesh& m, int f, int k) { return m.vertices.row(m.triangles(f, k)).transpose(); }

double orient2(double ay, double az, double by, double bz, double py, double pz) {
  return (by - ay) * (pz - az) - (bz - az) * (py - ay);
}

// Whether segment pq crosses triangle abc (Möller–Trumbore, endpoints included).
bool segment_hits(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a, h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;
  const Vec3 s = p - a;
  const double u = s.dot(h) / det;
  if (u < 0 || u > 1) return false;
  const Vec3 qv = s.cross(e1);
  const double v = d.dot(qv) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) / det;
  return t >= 0 && t <= 1;
}
}  // namespace

struct MeshShape::Locator {
  vtkSmartPointer<vtkPolyData> poly;
  vtkNew<vtkStaticCellLocator> cells;
};

MeshShape::MeshShape(io::TriangleMesh mesh) : mesh_(std::move(mesh)), locator_(std::make_unique<Locator>()) {
  const Tri& t = mesh_.triangles;
  if (t.rows() < 4) throw std::invalid_argument("a closed surface needs at least 4 triangles");
  if (t.minCoeff() < 0 || t.maxCoeff() >= mesh_.vertices.rows())
    throw std::invalid_argument("a triangle refers to a vertex that does not exist");
  orient(mesh_, edge_triangles(mesh_));
  double six_volume = 0;
  for (int f = 0; f < t.rows(); ++f) six_volume += corner(mesh_, f, 0).dot(corner(mesh_, f, 1).cross(corner(mesh_, f, 2)));
  if (six_volume < 0) {
    mesh_.triangles.col(1).swap(mesh_.triangles.col(2));
    six_volume = -six_volume;
  }
  volume_ = six_volume / 6;
  const auto [f, g] = find_self_intersection(mesh_);
  if (f >= 0)
    throw std::invalid_argument("the surface intersects itself: triangles " + std::to_string(f) + " and " +
                                std::to_string(g) + ", the first with vertices " +
                                vertex_text(mesh_.vertices, t(f, 0)) + ", " + vertex_text(mesh_.vertices, t(f, 1)) +
                                ", " + vertex_text(mesh_.vertices, t(f, 2)));
  normals_.resize(t.rows(), 3);
  double area = 0;
  for (int k = 0; k < t.rows(); ++k) {
    const Vec3 n = (corner(mesh_, k, 1) - corner(mesh_, k, 0)).cross(corner(mesh_, k, 2) - corner(mesh_, k, 0));
    normals_.row(k) = n.norm() > 0 ? Eigen::RowVector3d(n.normalized().transpose()) : Eigen::RowVector3d::Zero();
    cumulative_.push_back(area += 0.5 * n.norm());
  }
  bounds_.lower = mesh_.vertices.colwise().minCoeff().transpose();
  bounds_.upper = mesh_.vertices.colwise().maxCoeff().transpose();

  // The (y, z) buckets.
  grid_ = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(t.rows()))));
  y0_ = bounds_.lower(1);
  z0_ = bounds_.lower(2);
  cell_y_ = std::max((bounds_.upper(1) - y0_) / grid_, 1e-300);
  cell_z_ = std::max((bounds_.upper(2) - z0_) / grid_, 1e-300);
  const auto cell = [&](double v, double v0, double h) { return std::clamp(static_cast<int>((v - v0) / h), 0, grid_ - 1); };
  std::vector<int> count(static_cast<size_t>(grid_ * grid_ + 1), 0);
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 0; k < t.rows(); ++k) {
      double ylo = 1e300, yhi = -1e300, zlo = 1e300, zhi = -1e300;
      for (int c = 0; c < 3; ++c) {
        const Vec3 p = corner(mesh_, k, c);
        ylo = std::min(ylo, p(1)), yhi = std::max(yhi, p(1)), zlo = std::min(zlo, p(2)), zhi = std::max(zhi, p(2));
      }
      for (int i = cell(ylo, y0_, cell_y_); i <= cell(yhi, y0_, cell_y_); ++i)
        for (int j = cell(zlo, z0_, cell_z_); j <= cell(zhi, z0_, cell_z_); ++j) {
          const size_t b = static_cast<size_t>(i * grid_ + j);
          if (pass == 0) ++count[b + 1];
          else bucket_items_[static_cast<size_t>(count[b]++)] = k;
        }
    }
    if (pass == 0) {
      for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
      bucket_start_ = count;
      bucket_items_.resize(static_cast<size_t>(count.back()));
    }
  }

  locator_->poly = io::to_vtk_polydata(io::PolyData{mesh_.vertices, {}, mesh_.triangles, {}}, io::Precision::kFloat64);
  locator_->cells->SetDataSet(locator_->poly);
  locator_->cells->BuildLocator();
}

MeshShape::~MeshShape() = default;

bool MeshShape::contains(const Vec3& x) const {
  for (int a = 0; a < 3; ++a)
    if (x(a) < bounds_.lower(a) || x(a) > bounds_.upper(a)) return false;
  const int i = std::clamp(static_cast<int>((x(1) - y0_) / cell_y_), 0, grid_ - 1);
  const int j = std::clamp(static_cast<int>((x(2) - z0_) / cell_z_), 0, grid_ - 1);
  const size_t b = static_cast<size_t>(i * grid_ + j);
  const Eigen::MatrixXd& v = mesh_.vertices;
  bool inside = false;
  for (int s = bucket_start_[b]; s < bucket_start_[b + 1]; ++s) {
    const int f = bucket_items_[static_cast<size_t>(s)];
    int id[3];
    for (int c = 0; c < 3; ++c) id[c] = mesh_.triangles(f, c);
    const double o = orient2(v(id[0], 1), v(id[0], 2), v(id[1], 1), v(id[1], 2), v(id[2], 1), v(id[2], 2));
    if (o == 0) continue;
    double lambda[3];
    bool hit = true;
    for (int c = 0; c < 3 && hit; ++c) {
      const int p = id[(c + 1) % 3], q = id[(c + 2) % 3], lo = std::min(p, q), hi = std::max(p, q);
      const double e = orient2(v(lo, 1), v(lo, 2), v(hi, 1), v(hi, 2), x(1), x(2));
      const bool left_canonical = e >= 0;
      const bool left = p < q ? left_canonical : !left_canonical;  // of the directed edge p → q
      hit = left == (o > 0);
      lambda[c] = p < q ? e : -e;  // the directed determinant, ∝ the barycentric weight of id[c]
    }
    if (!hit) continue;
    const double xc = (lambda[0] * v(id[0], 0) + lambda[1] * v(id[1], 0) + lambda[2] * v(id[2], 0)) /
                      (lambda[0] + lambda[1] + lambda[2]);
    if (xc > x(0)) inside = !inside;
  }
  return inside;
}

namespace {
// ψ(x(ξ)) from ψ's value, gradient g and Hessian H in x and the derivatives x carries in ξ.
Scalar2 compose(double value, const Vec3& g, const Eigen::Matrix3d& hess, const Coords& x) {
  Scalar2 r(value);
  for (int i = 0; i < 3; ++i) {
    r.g += g(i) * x[static_cast<size_t>(i)].g;
    r.h += g(i) * x[static_cast<size_t>(i)].h;
    for (int j = 0; j < 3; ++j)
      r.h += hess(i, j) * x[static_cast<size_t>(i)].g * x[static_cast<size_t>(j)].g.transpose();
  }
  return r;
}
}  // namespace

void MeshShape::use_spline_distance(int cells) {
  spline_ = std::make_unique<SplineDistance>(bounds_, cells, [this](const Eigen::MatrixXd& points) {
    Eigen::VectorXd d = io::mesh_distance(points, mesh_);
    for (Eigen::Index r = 0; r < d.size(); ++r)
      if (!contains(points.row(r).transpose())) d(r) = -d(r);
    return d;
  });
}

Scalar2 MeshShape::distance(const Coords& x) const {
  if (spline_) {
    const Scalar2 s = (*spline_)(Vec3(x[0].v, x[1].v, x[2].v));
    return compose(s.v, s.g, s.h, x);
  }
  double point[3] = {x[0].v, x[1].v, x[2].v}, closest[3];
  vtkIdType cell = 0;
  int sub = 0;
  double d2 = 0;
  locator_->cells->FindClosestPoint(point, closest, cell, sub, d2);
  const Vec3 p(point[0], point[1], point[2]), c(closest[0], closest[1], closest[2]);
  // On the surface (up to rounding: a sampled boundary point's closest point differs from it
  // by ~1e-16, whose direction is noise, and the parity test may say either) the gradient is
  // the face's −n.
  const double on_surface = 1e-12 * (bounds_.upper - bounds_.lower).norm();
  const double d = std::sqrt(d2), sign = d <= on_surface || contains(p) ? 1.0 : -1.0;
  const Vec3 g = d > on_surface ? Vec3((p - c) / d) : Vec3(-normals_.row(cell).transpose());
  // Which feature c lies on: the barycentric weights that vanish.
  const int f = static_cast<int>(cell);
  const Vec3 a = corner(mesh_, f, 0), b = corner(mesh_, f, 1), cc = corner(mesh_, f, 2);
  const Vec3 n = (b - a).cross(cc - a);
  const double n2 = n.squaredNorm(), tol = 1e-9;
  double w[3] = {(cc - b).cross(c - b).dot(n) / n2, (a - cc).cross(c - cc).dot(n) / n2, 0};
  w[2] = 1 - w[0] - w[1];
  int zeros = 0, nonzero[3], nz = 0;
  for (int k = 0; k < 3; ++k) {
    if (w[k] < tol) ++zeros;
    else nonzero[nz++] = k;
  }
  Eigen::Matrix3d hess = Eigen::Matrix3d::Zero();
  if (d > on_surface && zeros == 1) {
    const Vec3 e = (corner(mesh_, f, nonzero[1]) - corner(mesh_, f, nonzero[0])).normalized();
    hess = (Eigen::Matrix3d::Identity() - e * e.transpose() - g * g.transpose()) / d;
  } else if (d > on_surface && zeros >= 2) {
    hess = (Eigen::Matrix3d::Identity() - g * g.transpose()) / d;
  }
  // Compose with the derivatives the coordinates carry (a rotated or scaled mesh).
  return compose(sign * d, sign * g, sign * hess, x);
}

SurfacePoint MeshShape::boundary_point(const double* u) const {
  double u0 = u[0];
  const int f = pick_piece(u0, cumulative_);
  const double r = std::sqrt(u[1]);
  SurfacePoint s;
  s.point = (1 - r) * corner(mesh_, f, 0) + r * (1 - u[2]) * corner(mesh_, f, 1) + r * u[2] * corner(mesh_, f, 2);
  s.normal = normals_.row(f).transpose();
  return s;
}

std::unique_ptr<MeshShape> read_mesh_shape(const std::filesystem::path& path) {
  io::TriangleMesh mesh = io::read_triangle_mesh(path);
  try {
    return std::make_unique<MeshShape>(std::move(mesh));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path.string() + ": " + e.what());
  }
}

std::pair<int, int> find_self_intersection(const io::TriangleMesh& mesh) {
  const Tri& t = mesh.triangles;
  const Vec3 lo = mesh.vertices.colwise().minCoeff().transpose(), hi = mesh.vertices.colwise().maxCoeff().transpose();
  const int g = std::max(1, static_cast<int>(std::cbrt(static_cast<double>(t.rows()))));
  const Vec3 h = ((hi - lo) / g).cwiseMax(1e-300);
  const auto cell = [&](double v, int a) { return std::clamp(static_cast<int>((v - lo(a)) / h(a)), 0, g - 1); };
  std::unordered_map<std::int64_t, std::vector<int>> buckets;
  for (int f = 0; f < t.rows(); ++f) {
    Vec3 a = corner(mesh, f, 0), b = a;
    for (int k = 1; k < 3; ++k) a = a.cwiseMin(corner(mesh, f, k)), b = b.cwiseMax(corner(mesh, f, k));
    for (int i = cell(a(0), 0); i <= cell(b(0), 0); ++i)
      for (int j = cell(a(1), 1); j <= cell(b(1), 1); ++j)
        for (int k = cell(a(2), 2); k <= cell(b(2), 2); ++k)
          buckets[(static_cast<std::int64_t>(i) * g + j) * g + k].push_back(f);
  }
  std::pair<int, int> first{-1, -1};
  for (const auto& [key, faces] : buckets)
    for (size_t p = 0; p < faces.size(); ++p)
      for (size_t q = p + 1; q < faces.size(); ++q) {
        const int f1 = std::min(faces[p], faces[q]), f2 = std::max(faces[p], faces[q]);
        bool shared = false;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) shared = shared || t(f1, a) == t(f2, b);
        if (shared || (first.first >= 0 && std::pair{f1, f2} >= first)) continue;
        bool hit = false;
        for (int e = 0; e < 3 && !hit; ++e) {
          hit = segment_hits(corner(mesh, f1, e), corner(mesh, f1, (e + 1) % 3), corner(mesh, f2, 0), corner(mesh, f2, 1),
                             corner(mesh, f2, 2)) ||
                segment_hits(corner(mesh, f2, e), corner(mesh, f2, (e + 1) % 3), corner(mesh, f1, 0), corner(mesh, f1, 1),
                             corner(mesh, f1, 2));
        }
        if (hit) first = {f1, f2};
      }
  return first;
}

}  // namespace nfield::solvers::geometry
