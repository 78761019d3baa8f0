// SPDX-License-Identifier: MIT
#include "solvers/geometry/geometry.h"

#include <cmath>
#include <algorithm>
#include <numbers>
#include <span>
#include <stdexcept>

#include <Eigen/Geometry>

#include "io/text.h"

namespace nfield::solvers::geometry {

Similarity Similarity::after(const Similarity& inner) const {
  Similarity m;
  m.scale = scale * inner.scale;
  m.rotation = rotation * inner.rotation;
  m.translation = apply(inner.translation);
  return m;
}

Eigen::Matrix3d Similarity::rotation_2d(double degrees) {
  return Eigen::AngleAxisd(degrees * std::numbers::pi / 180, Vec3::UnitZ()).toRotationMatrix();
}

Eigen::Matrix3d Similarity::rotation_3d(const Vec3& degrees) {
  const Vec3 r = degrees * std::numbers::pi / 180;
  return (Eigen::AngleAxisd(r(2), Vec3::UnitZ()) * Eigen::AngleAxisd(r(1), Vec3::UnitY()) *
          Eigen::AngleAxisd(r(0), Vec3::UnitX()))
      .toRotationMatrix();
}

ShapeTree ShapeTree::primitive(std::string name, std::unique_ptr<Primitive> shape) {
  if (!shape) throw std::invalid_argument("ShapeTree::primitive: no shape");
  ShapeTree t;
  t.leaf_ = std::make_unique<Leaf>(Leaf{std::move(name), std::move(shape), {}});
  return t;
}

ShapeTree ShapeTree::combine(Combine op, std::vector<ShapeTree> operands) {
  if (op == Combine::kLeaf || operands.empty())
    throw std::invalid_argument("ShapeTree::combine: a union, intersection or difference of at least one shape");
  ShapeTree t;
  t.op_ = op;
  t.operands_ = std::move(operands);
  return t;
}

ShapeTree&& ShapeTree::place(const Similarity& map) && {
  if (leaf_) leaf_->map = map.after(leaf_->map);
  for (ShapeTree& o : operands_) std::move(o).place(map);
  return std::move(*this);
}

Geometry::Geometry(ShapeTree tree) {
  root_ = build(std::move(tree), Similarity{});
  dim_ = leaves_.front().shape->dim();
  for (size_t i = 0; i < leaves_.size(); ++i) {
    if (leaves_[i].shape->dim() != dim_)
      throw std::invalid_argument("part '" + leaves_[i].name + "' is " + std::to_string(leaves_[i].shape->dim()) +
                                  "-D, part '" + leaves_.front().name + "' " + std::to_string(dim_) + "-D");
    if (leaves_[i].name.empty()) leaves_[i].name = leaves_[i].shape->type() + std::to_string(i + 1);
  }
  for (size_t i = 0; i < leaves_.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (io::to_lower(leaves_[i].name) == io::to_lower(leaves_[j].name))
        throw std::invalid_argument("two parts are named '" + leaves_[i].name + "'");
}

Geometry::Geometry(Geometry&&) noexcept = default;
Geometry& Geometry::operator=(Geometry&&) noexcept = default;
Geometry::~Geometry() = default;

Geometry::Node Geometry::build(ShapeTree&& tree, const Similarity& outer) {
  Node n;
  n.op = tree.op_;
  n.first = static_cast<int>(leaves_.size());
  if (tree.leaf_) {
    n.leaf = n.first;
    leaves_.push_back(Leaf{std::move(tree.leaf_->name), std::move(tree.leaf_->shape), outer.after(tree.leaf_->map)});
  }
  for (ShapeTree& o : tree.operands_) n.children.push_back(build(std::move(o), outer));
  n.end = static_cast<int>(leaves_.size());
  return n;
}

const std::string& Geometry::part_name(int part) const { return leaves_.at(static_cast<size_t>(part)).name; }
const Primitive& Geometry::part_shape(int part) const { return *leaves_.at(static_cast<size_t>(part)).shape; }

int Geometry::part(const std::string& name) const {
  std::vector<std::string> names;
  for (size_t i = 0; i < leaves_.size(); ++i) {
    if (io::to_lower(leaves_[i].name) == io::to_lower(name)) return static_cast<int>(i);
    names.push_back(leaves_[i].name);
  }
  throw std::invalid_argument("unknown part '" + name + "' (parts: " + io::join(names, ", ") + "; or boundary)");
}

Selection Geometry::select(const std::vector<std::string>& names, const std::string& where) const {
  Selection s;
  bool all = names.empty();
  for (const std::string& n : names) {
    if (io::to_lower(n) == "boundary") all = true;
    else s.parts.push_back(part(n));
  }
  if (all) s.parts.clear();
  if (!where.empty()) {
    std::vector<std::string> variables = {"x", "y"};
    if (dim_ == 3) variables.emplace_back("z");
    s.where = std::make_shared<const io::Expression>(where, variables);
  }
  return s;
}

bool Geometry::contains(const Node& node, const Vec3& x) const {
  switch (node.op) {
    case Combine::kLeaf: {
      const Leaf& l = leaves_[static_cast<size_t>(node.leaf)];
      return l.shape->contains(l.map.inverse(x));
    }
    case Combine::kUnion:
      for (const Node& c : node.children)
        if (contains(c, x)) return true;
      return false;
    case Combine::kIntersection:
      for (const Node& c : node.children)
        if (!contains(c, x)) return false;
      return true;
    case Combine::kDifference:
      if (!contains(node.children.front(), x)) return false;
      for (size_t k = 1; k < node.children.size(); ++k)
        if (contains(node.children[k], x)) return false;
      return true;
  }
  return false;
}

bool Geometry::contains(const Vec3& x) const { return contains(root_, x); }

Eigen::Array<bool, Eigen::Dynamic, 1> Geometry::contains_rows(const Eigen::MatrixXd& points) const {
  if (points.cols() != dim_) throw std::invalid_argument("Geometry::contains: points need " + std::to_string(dim_) + " columns");
  Eigen::Array<bool, Eigen::Dynamic, 1> in(points.rows());
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    Vec3 x = Vec3::Zero();
    x.head(dim_) = points.row(r).transpose();
    in(r) = contains(root_, x);
  }
  return in;
}

Bounds Geometry::bounds(const Node& node) const {
  if (node.op == Combine::kLeaf) {
    const Leaf& l = leaves_[static_cast<size_t>(node.leaf)];
    const Bounds local = l.shape->bounds();
    Bounds b{Vec3::Constant(1e300), Vec3::Constant(-1e300)};
    for (int corner = 0; corner < 8; ++corner) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) p(a) = (corner >> a) & 1 ? local.upper(a) : local.lower(a);
      const Vec3 w = l.map.apply(p);
      b.lower = b.lower.cwiseMin(w);
      b.upper = b.upper.cwiseMax(w);
    }
    if (dim_ == 2) b.lower(2) = b.upper(2) = 0;
    return b;
  }
  Bounds b = bounds(node.children.front());
  for (size_t k = 1; k < node.children.size() && node.op != Combine::kDifference; ++k) {
    const Bounds c = bounds(node.children[k]);
    if (node.op == Combine::kUnion) {
      b.lower = b.lower.cwiseMin(c.lower);
      b.upper = b.upper.cwiseMax(c.upper);
    } else {
      b.lower = b.lower.cwiseMax(c.lower);
      b.upper = b.upper.cwiseMin(c.upper);
    }
  }
  return b;
}

Bounds Geometry::bounds() const { return bounds(root_); }

Scalar2 Geometry::leaf_psi(int leaf, const Coords& x) const {
  const Leaf& l = leaves_[static_cast<size_t>(leaf)];
  // local = Rᵀ (x − t) / s, linear in x; ψ_world = s ψ_local keeps |∇ψ| = 1 on the boundary.
  const Eigen::Matrix3d a = l.map.rotation.transpose() / l.map.scale;
  const Vec3 b = a * l.map.translation;
  Coords local;
  for (int i = 0; i < 3; ++i) {
    Scalar2 v(-b(i));
    for (int j = 0; j < 3; ++j)
      if (a(i, j) != 0) v = v + a(i, j) * x[static_cast<size_t>(j)];
    local[static_cast<size_t>(i)] = v;
  }
  return l.map.scale * l.shape->distance(local);
}

Scalar2 Geometry::psi(const Node& node, const Coords& x) const {
  if (node.op == Combine::kLeaf) return leaf_psi(node.leaf, x);
  Scalar2 d = psi(node.children.front(), x);
  for (size_t k = 1; k < node.children.size(); ++k) {
    const Scalar2 c = psi(node.children[k], x);
    d = node.op == Combine::kUnion ? r_or(d, c) : node.op == Combine::kIntersection ? r_and(d, c) : r_and(d, -c);
  }
  return d;
}

namespace {
template <class Node>
size_t child_of(const Node& node, int leaf) {
  for (size_t k = 0; k < node.children.size(); ++k)
    if (leaf >= node.children[k].first && leaf < node.children[k].end) return k;
  throw std::logic_error("geometry: leaf not below node");
}
}  // namespace

int Geometry::keep(const Node& node, int leaf, const Vec3& x) const {
  if (node.op == Combine::kLeaf) return 1;
  const size_t k = child_of(node, leaf);
  int s = keep(node.children[k], leaf, x);
  for (size_t j = 0; j < node.children.size() && s != 0; ++j) {
    if (j == k) continue;
    const bool in = contains(node.children[j], x);
    const bool want_in = node.op == Combine::kIntersection || (node.op == Combine::kDifference && k > 0 && j == 0);
    if (in != want_in) s = 0;
  }
  return node.op == Combine::kDifference && k > 0 ? -s : s;
}

std::optional<Scalar2> Geometry::trim(const Node& node, int leaf, const Coords& x) const {
  if (node.op == Combine::kLeaf) return std::nullopt;
  const size_t k = child_of(node, leaf);
  std::optional<Scalar2> t = trim(node.children[k], leaf, x);
  for (size_t j = 0; j < node.children.size(); ++j) {
    if (j == k) continue;
    const bool want_in = node.op == Combine::kIntersection || (node.op == Combine::kDifference && k > 0 && j == 0);
    const Scalar2 p = psi(node.children[j], x);
    const Scalar2 c = want_in ? p : -p;
    t = t ? r_and(*t, c) : c;
  }
  return t;
}

int Geometry::orientation(const Node& node, int leaf) const {
  if (node.op == Combine::kLeaf) return 1;
  const size_t k = child_of(node, leaf);
  const int s = orientation(node.children[k], leaf);
  return node.op == Combine::kDifference && k > 0 ? -s : s;
}

Scalar2 Geometry::distance(const Vec3& x) const { return psi(root_, variables(x)); }

Vec3 Geometry::normal(const Vec3& x) const {
  const Vec3 g = -psi(root_, variables(x)).g;
  const double n = g.norm();
  return n > 0 ? Vec3(g / n) : Vec3::Zero();
}

Scalar2 Geometry::distance(const Vec3& x, const Selection& selection) const {
  if (selection.where) throw std::invalid_argument("a distance function needs parts by name, not a `where` expression");
  const Coords c = variables(x);
  if (selection.all()) return psi(root_, c);
  Scalar2 sum_inverse(0.0);
  for (int leaf : selection.parts) {
    const Scalar2 f = leaf_psi(leaf, c);
    const std::optional<Scalar2> t = trim(root_, leaf, c);
    const Scalar2 phi = t ? sqrt(square(f) + square((sqrt(square(*t) + square(square(f))) - *t) * 0.5))
                          : orientation(root_, leaf) * f;
    sum_inverse = sum_inverse + inverse(phi);
  }
  return inverse(sum_inverse);
}

bool Geometry::selected(const Selection& s, int leaf, const Vec3& x) const {
  if (!s.parts.empty() && std::find(s.parts.begin(), s.parts.end(), leaf) == s.parts.end()) return false;
  return !s.where || s.where->evaluate(std::span<const double>(x.data(), static_cast<size_t>(dim_))) != 0;
}

}  // namespace nfield::solvers::geometry
