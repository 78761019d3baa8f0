// SPDX-License-Identifier: MIT
#include "solvers/geometry/polygon.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nfield::solvers::geometry {
namespace {
using V2 = Eigen::Vector2d;

double cross(const V2& a, const V2& b) { return a(0) * b(1) - a(1) * b(0); }
int sign(double v) { return (v > 0) - (v < 0); }
bool on_segment(const V2& p, const V2& a, const V2& b) {
  return std::min(a(0), b(0)) <= p(0) && p(0) <= std::max(a(0), b(0)) && std::min(a(1), b(1)) <= p(1) &&
         p(1) <= std::max(a(1), b(1));
}
// Whether segments ab and cd share a point (touching counts).
bool segments_meet(const V2& a, const V2& b, const V2& c, const V2& d) {
  const int d1 = sign(cross(b - a, c - a)), d2 = sign(cross(b - a, d - a));
  const int d3 = sign(cross(d - c, a - c)), d4 = sign(cross(d - c, b - c));
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && on_segment(c, a, b)) || (d2 == 0 && on_segment(d, a, b)) ||
         (d3 == 0 && on_segment(a, c, d)) || (d4 == 0 && on_segment(b, c, d));
}
}  // namespace

std::pair<int, int> crossing_edges(const Eigen::MatrixXd& v) {
  const int n = static_cast<int>(v.rows());
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      const V2 a = v.row(i).transpose(), b = v.row((i + 1) % n).transpose();
      const V2 c = v.row(j).transpose(), d = v.row((j + 1) % n).transpose();
      if (adjacent) {
        // Neighbours share one vertex; they cross only when they fold back onto each other.
        const V2 shared = j == i + 1 ? b : a, p = j == i + 1 ? a : b, q = j == i + 1 ? d : c;
        if (sign(cross(p - shared, q - shared)) == 0 && (p - shared).dot(q - shared) > 0) return {i, j};
        continue;
      }
      if (segments_meet(a, b, c, d)) return {i, j};
    }
  return {-1, -1};
}

Polygon::Polygon(const Eigen::MatrixXd& vertices) : v_(vertices) {
  const auto n = v_.rows();
  if (v_.cols() != 2) throw std::invalid_argument("polygon: vertices need 2 coordinates");
  if (n < 3) throw std::invalid_argument("polygon: needs at least 3 vertices, got " + std::to_string(n));
  for (Eigen::Index i = 0; i < n; ++i)
    if ((v_.row((i + 1) % n) - v_.row(i)).norm() == 0)
      throw std::invalid_argument("polygon: vertices " + std::to_string(i) + " and " + std::to_string((i + 1) % n) +
                                  " coincide");
  const auto [i, j] = crossing_edges(v_);
  if (i >= 0)
    throw std::invalid_argument("polygon: edges " + std::to_string(i) + " (vertices " + std::to_string(i) + "–" +
                                std::to_string((i + 1) % n) + ") and " + std::to_string(j) + " (vertices " +
                                std::to_string(j) + "–" + std::to_string((j + 1) % n) + ") cross");
  double twice = 0;
  for (Eigen::Index k = 0; k < n; ++k) twice += cross(v_.row(k).transpose(), v_.row((k + 1) % n).transpose());
  if (twice < 0) v_ = v_.colwise().reverse().eval();
  area_ = 0.5 * std::abs(twice);
  double total = 0;
  for (Eigen::Index k = 0; k < n; ++k) cumulative_.push_back(total += (v_.row((k + 1) % n) - v_.row(k)).norm());
}

bool Polygon::contains(const Vec3& x) const {
  const auto n = v_.rows();
  bool inside = false;
  for (Eigen::Index i = 0, j = n - 1; i < n; j = i++) {
    const double yi = v_(i, 1), yj = v_(j, 1);
    if ((yi > x(1)) != (yj > x(1))) {
      const double xc = v_(j, 0) + (x(1) - yj) * (v_(i, 0) - v_(j, 0)) / (yi - yj);
      if (x(0) < xc) inside = !inside;
      else if (x(0) == xc) return true;  // on the boundary: the closed set
    }
  }
  return inside;
}

Bounds Polygon::bounds() const {
  Bounds b;
  b.lower.head<2>() = v_.colwise().minCoeff().transpose();
  b.upper.head<2>() = v_.colwise().maxCoeff().transpose();
  return b;
}

Scalar2 Polygon::distance(const Coords& x) const {
  const auto n = v_.rows();
  Scalar2 sum_inverse(0.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const V2 p = v_.row(i).transpose(), q = v_.row((i + 1) % n).transpose(), c = 0.5 * (p + q);
    const double length = (q - p).norm();
    const Scalar2 f = ((x[0] - p(0)) * (q(1) - p(1)) - (x[1] - p(1)) * (q(0) - p(0))) / length;
    const Scalar2 t = (0.25 * length * length - square(x[0] - c(0)) - square(x[1] - c(1))) / length;
    const Scalar2 varphi = sqrt(square(t) + square(square(f)));
    const Scalar2 phi = sqrt(square(f) + square((varphi - t) * 0.5));
    sum_inverse = sum_inverse + inverse(phi);
  }
  const Scalar2 phi = inverse(sum_inverse);
  return contains(Vec3(x[0].v, x[1].v, 0)) ? phi : -phi;
}

SurfacePoint Polygon::boundary_point(const double* u) const {
  double u0 = u[0];
  const int e = pick_piece(u0, cumulative_);
  const auto n = v_.rows();
  const V2 p = v_.row(e).transpose(), q = v_.row((e + 1) % n).transpose(), d = (q - p).normalized();
  SurfacePoint s;
  s.point.head<2>() = p + u[1] * (q - p);
  s.normal = Vec3(d(1), -d(0), 0);
  return s;
}

Eigen::MatrixXd read_polygon_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open the polygon file");
  std::vector<double> xy;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    double x = 0, y = 0;
    std::string rest;
    if (!(fields >> x)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": expected two numbers `x y`");
    }
    if (!(fields >> y) || (fields >> rest))
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": expected two numbers `x y`");
    xy.push_back(x);
    xy.push_back(y);
  }
  Eigen::MatrixXd v(static_cast<Eigen::Index>(xy.size() / 2), 2);
  for (Eigen::Index i = 0; i < v.rows(); ++i) v.row(i) << xy[2 * i], xy[2 * i + 1];
  return v;
}

}  // namespace nfield::solvers::geometry
