// SPDX-License-Identifier: MIT
// Geometry's sampling and measures (the method is described in geometry.h).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solvers/geometry/geometry.h"

namespace nfield::solvers::geometry {
namespace {
constexpr Eigen::Index kGiveUp = 1'000'000;  // candidates in a row without a hit: empty

}  // namespace

Eigen::MatrixXd Geometry::sample_interior(Random& rng, Eigen::Index n) const {
  const Bounds box = bounds();
  Eigen::MatrixXd out(n, dim_);
  Eigen::Index have = 0, drawn = 0, missed = 0;
  double rate = 1;
  while (have < n) {
    if (box.empty(dim_) || missed >= kGiveUp)
      throw std::runtime_error("the domain is empty: none of " + std::to_string(missed) +
                               " points drawn in its bounding box lies inside it");
    const Eigen::Index m = std::max<Eigen::Index>(64, static_cast<Eigen::Index>(1.2 * (n - have) / rate) + 16);
    const Eigen::MatrixXd u = unit_points(rng, m, dim_);
    Eigen::Index hits = 0;
    for (Eigen::Index r = 0; r < m && have < n; ++r) {
      Vec3 x = Vec3::Zero();
      for (int a = 0; a < dim_; ++a) x(a) = box.lower(a) + (box.upper(a) - box.lower(a)) * u(r, a);
      if (!contains(root_, x)) continue;
      out.row(have++) = x.head(dim_).transpose();
      ++hits;
    }
    drawn += m;
    missed = hits > 0 ? 0 : missed + m;
    rate = std::max(static_cast<double>(have) / static_cast<double>(drawn), 1e-3);
  }
  return out;
}

BoundarySample Geometry::sample_boundary(Random& rng, Eigen::Index n, const Selection& selection) const {
  std::vector<int> leaves = selection.parts;
  if (leaves.empty())
    for (int i = 0; i < part_count(); ++i) leaves.push_back(i);
  std::vector<double> cumulative;
  double total = 0;
  for (int l : leaves) {
    const Leaf& leaf = leaves_[static_cast<size_t>(l)];
    cumulative.push_back(total += leaf.shape->proposal_measure() * std::pow(leaf.map.scale, dim_ - 1));
  }
  BoundarySample s{Eigen::MatrixXd(n, dim_), Eigen::MatrixXd(n, dim_), Eigen::VectorXi(n)};
  Eigen::Index have = 0, drawn = 0, missed = 0;
  double rate = 1;
  while (have < n) {
    if (missed >= kGiveUp)
      throw std::runtime_error("the selected boundary is empty: none of " + std::to_string(missed) +
                               " candidate points lies on it");
    const Eigen::Index m = std::max<Eigen::Index>(64, static_cast<Eigen::Index>(1.2 * (n - have) / rate) + 16);
    const Eigen::MatrixXd u = unit_points(rng, m, dim_ + 1);
    Eigen::Index hits = 0;
    for (Eigen::Index r = 0; r < m && have < n; ++r) {
      double v[4] = {u(r, 0), u(r, 1), dim_ == 3 ? u(r, 2) : 0.0, 0.0};
      const int leaf = leaves[static_cast<size_t>(pick_piece(v[0], cumulative))];
      const Leaf& l = leaves_[static_cast<size_t>(leaf)];
      const SurfacePoint p = l.shape->boundary_point(v);
      if (u(r, dim_) >= p.accept) continue;
      const Vec3 x = l.map.apply(p.point);
      const int sign = keep(root_, leaf, x);
      if (sign == 0 || !selected(selection, leaf, x)) continue;
      s.points.row(have) = x.head(dim_).transpose();
      s.normals.row(have) = (sign * (l.map.rotation * p.normal)).head(dim_).transpose();
      s.parts(have++) = leaf;
      ++hits;
    }
    drawn += m;
    missed = hits > 0 ? 0 : missed + m;
    rate = std::max(static_cast<double>(have) / static_cast<double>(drawn), 1e-3);
  }
  return s;
}

BoundaryQuadrature Geometry::boundary_quadrature(const Selection& selection, Eigen::Index n) const {
  std::vector<int> leaves = selection.parts;
  if (leaves.empty())
    for (int i = 0; i < part_count(); ++i) leaves.push_back(i);
  double total = 0;
  for (int l : leaves) {
    const Leaf& leaf = leaves_[static_cast<size_t>(l)];
    total += leaf.shape->proposal_measure() * std::pow(leaf.map.scale, dim_ - 1);
  }
  std::vector<Vec3> points, normals;
  std::vector<double> weights;
  std::vector<int> parts;
  for (int leaf : leaves) {
    const Leaf& l = leaves_[static_cast<size_t>(leaf)];
    const double stretch = std::pow(l.map.scale, dim_ - 1);
    const std::vector<double> pieces = l.shape->pieces();
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      const double start = k == 0 ? 0.0 : pieces[k - 1], share = pieces[k] - start;
      if (!(share > 0)) continue;
      const auto wanted = std::max<Eigen::Index>(
          1, static_cast<Eigen::Index>(std::llround(static_cast<double>(n) * share * stretch / total)));
      const Eigen::Index side =
          dim_ == 2 ? wanted : std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::ceil(std::sqrt(wanted))));
      const Eigen::Index count = dim_ == 2 ? side : side * side;
      for (Eigen::Index c = 0; c < count; ++c) {
        double v[4] = {(start + share / 2) / pieces.back(), (static_cast<double>(c % side) + 0.5) / side,
                       (static_cast<double>(c / side) + 0.5) / side, 0};
        const SurfacePoint p = l.shape->boundary_point(v);
        const Vec3 x = l.map.apply(p.point);
        const int sign = keep(root_, leaf, x);
        if (sign == 0 || !selected(selection, leaf, x)) continue;
        points.push_back(x);
        normals.push_back(sign * (l.map.rotation * p.normal));
        weights.push_back(share * stretch * p.accept / static_cast<double>(count));
        parts.push_back(leaf);
      }
    }
  }
  const auto m = static_cast<Eigen::Index>(points.size());
  BoundaryQuadrature q{Eigen::MatrixXd(m, dim_), Eigen::MatrixXd(m, dim_), Eigen::VectorXd(m), Eigen::VectorXi(m)};
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto j = static_cast<std::size_t>(i);
    q.points.row(i) = points[j].head(dim_).transpose();
    q.normals.row(i) = normals[j].head(dim_).transpose();
    q.weights(i) = weights[j];
    q.parts(i) = parts[j];
  }
  return q;
}

Measure Geometry::volume(Eigen::Index samples, std::uint64_t seed) const {
  if (root_.op == Combine::kLeaf) {
    const Leaf& l = leaves_.front();
    return {l.shape->volume() * std::pow(l.map.scale, dim_), 0, true};
  }
  const Bounds box = bounds();
  if (box.empty(dim_)) return {0, 0, false};
  double box_volume = 1;
  for (int a = 0; a < dim_; ++a) box_volume *= box.upper(a) - box.lower(a);
  Random rng(seed);
  Eigen::Index hits = 0;
  for (Eigen::Index r = 0; r < samples; ++r) {
    Vec3 x = Vec3::Zero();
    for (int a = 0; a < dim_; ++a) x(a) = box.lower(a) + (box.upper(a) - box.lower(a)) * uniform01(rng);
    hits += contains(root_, x) ? 1 : 0;
  }
  const double p = static_cast<double>(hits) / static_cast<double>(samples);
  return {box_volume * p, box_volume * std::sqrt(p * (1 - p) / static_cast<double>(samples)), false};
}

Measure Geometry::boundary_measure(const Selection& selection, Eigen::Index samples, std::uint64_t seed) const {
  std::vector<int> leaves = selection.parts;
  if (leaves.empty())
    for (int i = 0; i < part_count(); ++i) leaves.push_back(i);
  if (root_.op == Combine::kLeaf && !selection.where) {
    const Leaf& l = leaves_.front();
    const double m = l.shape->boundary_measure();
    if (std::isfinite(m)) return {m * std::pow(l.map.scale, dim_ - 1), 0, true};
  }
  std::vector<double> cumulative;
  double total = 0;
  for (int l : leaves) {
    const Leaf& leaf = leaves_[static_cast<size_t>(l)];
    cumulative.push_back(total += leaf.shape->proposal_measure() * std::pow(leaf.map.scale, dim_ - 1));
  }
  Random rng(seed);
  Eigen::Index hits = 0;
  for (Eigen::Index r = 0; r < samples; ++r) {
    double v[4] = {uniform01(rng), uniform01(rng), uniform01(rng), 0};
    const int leaf = leaves[static_cast<size_t>(pick_piece(v[0], cumulative))];
    const Leaf& l = leaves_[static_cast<size_t>(leaf)];
    const SurfacePoint p = l.shape->boundary_point(v);
    if (uniform01(rng) >= p.accept) continue;
    const Vec3 x = l.map.apply(p.point);
    if (keep(root_, leaf, x) != 0 && selected(selection, leaf, x)) ++hits;
  }
  const double p = static_cast<double>(hits) / static_cast<double>(samples);
  return {total * p, total * std::sqrt(p * (1 - p) / static_cast<double>(samples)), false};
}

}  // namespace nfield::solvers::geometry
