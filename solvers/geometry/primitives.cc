// SPDX-License-Identifier: MIT
#include "solvers/geometry/primitives.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

namespace nfield::solvers::geometry {
namespace {
constexpr double kPi = std::numbers::pi;

void check_dim(int dim, const char* what) {
  if (dim != 2 && dim != 3) throw std::invalid_argument(std::string(what) + ": dimension must be 2 or 3");
}
void check_positive(double v, const char* what) {
  if (!(v > 0) || !std::isfinite(v)) throw std::invalid_argument(std::string(what) + " must be positive");
}
Scalar2 slab(const Scalar2& x, double c, double h) { return (h * h - square(x - c)) / (2 * h); }
Scalar2 ball_distance(const Coords& x, const Vec3& c, double r, int dim) {
  Scalar2 q2(0.0);
  for (int i = 0; i < dim; ++i) q2 = q2 + square(x[i] - c(i));
  return (r * r - q2) / (2 * r);
}
// A unit vector of the sphere from u1, u2 ∈ [0, 1): z = 1 − 2u₁ is uniform (Archimedes).
Vec3 sphere_point(double u1, double u2) {
  const double z = 1 - 2 * u1, s = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u2;
  return {s * std::cos(phi), s * std::sin(phi), z};
}
}  // namespace

int pick_piece(double& u, const std::vector<double>& cumulative) {
  const double total = cumulative.back(), t = u * total;
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), t);
  const int k = std::min(static_cast<int>(it - cumulative.begin()), static_cast<int>(cumulative.size()) - 1);
  const double lo = k == 0 ? 0 : cumulative[static_cast<size_t>(k - 1)], hi = cumulative[static_cast<size_t>(k)];
  u = hi > lo ? std::clamp((t - lo) / (hi - lo), 0.0, std::nextafter(1.0, 0.0)) : 0.0;
  return k;
}

Coords variables(const Vec3& x) {
  return {Scalar2::variable(x(0), 0), Scalar2::variable(x(1), 1), Scalar2::variable(x(2), 2)};
}

// ---- Box ---------------------------------------------------------------------------------
Box::Box(int dim, const Vec3& lower, const Vec3& upper) : dim_(dim), lower_(lower), upper_(upper) {
  check_dim(dim, "box");
  for (int a = 0; a < dim; ++a)
    if (!(upper(a) > lower(a))) throw std::invalid_argument("box: upper must exceed lower on every axis");
  if (dim == 2) lower_(2) = upper_(2) = 0;
  double total = 0;
  for (int a = 0; a < dim; ++a) {
    double m = 1;
    for (int b = 0; b < dim; ++b)
      if (b != a) m *= upper_(b) - lower_(b);
    faces_.push_back(total += m);
    faces_.push_back(total += m);
  }
}

bool Box::contains(const Vec3& x) const {
  for (int a = 0; a < dim_; ++a)
    if (x(a) < lower_(a) || x(a) > upper_(a)) return false;
  return true;
}

double Box::volume() const {
  double v = 1;
  for (int a = 0; a < dim_; ++a) v *= upper_(a) - lower_(a);
  return v;
}

Scalar2 Box::distance(const Coords& x) const {
  Scalar2 d;
  for (int a = 0; a < dim_; ++a) {
    const Scalar2 s = slab(x[a], 0.5 * (lower_(a) + upper_(a)), 0.5 * (upper_(a) - lower_(a)));
    d = a == 0 ? s : r_and(d, s);
  }
  return d;
}

SurfacePoint Box::boundary_point(const double* u) const {
  double u0 = u[0];
  const int face = pick_piece(u0, faces_), axis = face / 2;
  SurfacePoint p;
  int k = 1;
  for (int a = 0; a < dim_; ++a) {
    if (a == axis) continue;
    p.point(a) = lower_(a) + (upper_(a) - lower_(a)) * u[k++];
  }
  const bool high = face % 2 == 1;
  p.point(axis) = high ? upper_(axis) : lower_(axis);
  p.normal(axis) = high ? 1 : -1;
  return p;
}

// ---- Ball --------------------------------------------------------------------------------
Ball::Ball(int dim, const Vec3& center, double radius) : dim_(dim), center_(center), radius_(radius) {
  check_dim(dim, "ball");
  check_positive(radius, "radius");
  if (dim == 2) center_(2) = 0;
}
bool Ball::contains(const Vec3& x) const { return (x - center_).squaredNorm() <= radius_ * radius_; }
Bounds Ball::bounds() const {
  Vec3 r = Vec3::Constant(radius_);
  if (dim_ == 2) r(2) = 0;
  return {center_ - r, center_ + r};
}
double Ball::volume() const {
  return dim_ == 2 ? kPi * radius_ * radius_ : 4.0 / 3.0 * kPi * radius_ * radius_ * radius_;
}
Scalar2 Ball::distance(const Coords& x) const { return ball_distance(x, center_, radius_, dim_); }
SurfacePoint Ball::boundary_point(const double* u) const {
  SurfacePoint p;
  if (dim_ == 2) {
    const double t = 2 * kPi * u[1];
    p.normal = Vec3(std::cos(t), std::sin(t), 0);
  } else {
    p.normal = sphere_point(u[1], u[2]);
  }
  p.point = center_ + radius_ * p.normal;
  return p;
}
double Ball::proposal_measure() const {
  return dim_ == 2 ? 2 * kPi * radius_ : 4 * kPi * radius_ * radius_;
}

// ---- Ellipsoid ---------------------------------------------------------------------------
Ellipsoid::Ellipsoid(int dim, const Vec3& center, const Vec3& semi_axes)
    : dim_(dim), center_(center), axes_(semi_axes) {
  check_dim(dim, "ellipsoid");
  for (int a = 0; a < dim; ++a) check_positive(semi_axes(a), "semi_axes");
  if (dim == 2) center_(2) = 0, axes_(2) = 1;
}
bool Ellipsoid::contains(const Vec3& x) const {
  double s = 0;
  for (int a = 0; a < dim_; ++a) s += std::pow((x(a) - center_(a)) / axes_(a), 2);
  return s <= 1;
}
Bounds Ellipsoid::bounds() const {
  Vec3 r = axes_;
  if (dim_ == 2) r(2) = 0;
  return {center_ - r, center_ + r};
}
double Ellipsoid::volume() const {
  return dim_ == 2 ? kPi * axes_(0) * axes_(1) : 4.0 / 3.0 * kPi * axes_.prod();
}
Scalar2 Ellipsoid::distance(const Coords& x) const {
  Scalar2 g(1.0), grad2(0.0);
  for (int a = 0; a < dim_; ++a) {
    const Scalar2 q = x[a] - center_(a);
    const double a2 = axes_(a) * axes_(a);
    g = g - square(q) / a2;
    grad2 = grad2 + square(q) * (4 / (a2 * a2));
  }
  return g / sqrt(square(g) + grad2);
}
// The unit circle (sphere) s mapped to x = c + a∘s; the area element there, relative to the
// circle's, is Πa · |s/a| (2-D: a₀a₁ |s/a| = √(a₀² s₁² + a₁² s₀²)), kept with the ratio to its
// largest value Πa / min a.
SurfacePoint Ellipsoid::boundary_point(const double* u) const {
  Vec3 s = dim_ == 2 ? Vec3(std::cos(2 * kPi * u[1]), std::sin(2 * kPi * u[1]), 0) : sphere_point(u[1], u[2]);
  SurfacePoint p;
  Vec3 n = Vec3::Zero();
  double min_axis = axes_(0);
  for (int a = 0; a < dim_; ++a) {
    p.point(a) = center_(a) + axes_(a) * s(a);
    n(a) = s(a) / axes_(a);
    min_axis = std::min(min_axis, axes_(a));
  }
  p.accept = std::min(1.0, min_axis * n.norm());
  p.normal = n.normalized();
  return p;
}
double Ellipsoid::proposal_measure() const {
  const double min_axis = dim_ == 2 ? std::min(axes_(0), axes_(1)) : axes_.minCoeff();
  return dim_ == 2 ? 2 * kPi * axes_(0) * axes_(1) / min_axis : 4 * kPi * axes_.prod() / min_axis;
}

// ---- Cylinder ----------------------------------------------------------------------------
Cylinder::Cylinder(const Vec3& center, double radius, double height)
    : center_(center), radius_(radius), half_height_(0.5 * height) {
  check_positive(radius, "radius");
  check_positive(height, "height");
  const double side = 2 * kPi * radius * height, cap = kPi * radius * radius;
  pieces_ = {side, side + cap, side + 2 * cap};
}
bool Cylinder::contains(const Vec3& x) const {
  const Vec3 q = x - center_;
  return q.head<2>().squaredNorm() <= radius_ * radius_ && std::abs(q(2)) <= half_height_;
}
Bounds Cylinder::bounds() const {
  const Vec3 r(radius_, radius_, half_height_);
  return {center_ - r, center_ + r};
}
double Cylinder::volume() const { return kPi * radius_ * radius_ * 2 * half_height_; }
Scalar2 Cylinder::distance(const Coords& x) const {
  const Scalar2 disk = (radius_ * radius_ - square(x[0] - center_(0)) - square(x[1] - center_(1))) / (2 * radius_);
  return r_and(disk, slab(x[2], center_(2), half_height_));
}
SurfacePoint Cylinder::boundary_point(const double* u) const {
  double u0 = u[0];
  const int piece = pick_piece(u0, pieces_);
  SurfacePoint p;
  const double t = 2 * kPi * u[2];
  if (piece == 0) {
    p.normal = Vec3(std::cos(t), std::sin(t), 0);
    p.point = center_ + radius_ * p.normal;
    p.point(2) = center_(2) - half_height_ + 2 * half_height_ * u[1];
  } else {
    const double rho = radius_ * std::sqrt(u[1]), side = piece == 2 ? 1 : -1;
    p.point = center_ + Vec3(rho * std::cos(t), rho * std::sin(t), side * half_height_);
    p.normal = Vec3(0, 0, side);
  }
  return p;
}

// ---- Capsule -----------------------------------------------------------------------------
Capsule::Capsule(int dim, const Vec3& a, const Vec3& b, double radius)
    : dim_(dim), a_(a), b_(b), radius_(radius) {
  check_dim(dim, "capsule");
  check_positive(radius, "radius");
  if (dim == 2) a_(2) = b_(2) = 0;
  const double length = (b_ - a_).norm();
  check_positive(length, "capsule: the distance between its ends");
  mid_ = 0.5 * (a_ + b_);
  axis_ = (b_ - a_) / length;
  half_length_ = 0.5 * length;
  if (dim == 2) {
    p1_ = Vec3(-axis_(1), axis_(0), 0);
    p2_ = Vec3::Zero();
    const double side = 2 * half_length_, cap = kPi * radius;
    pieces_ = {side, 2 * side, 2 * side + cap, 2 * side + 2 * cap};
  } else {
    const Vec3 helper = std::abs(axis_(0)) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    p1_ = axis_.cross(helper).normalized();
    p2_ = axis_.cross(p1_);
    const double side = 2 * kPi * radius * 2 * half_length_, cap = 2 * kPi * radius * radius;
    pieces_ = {side, side + cap, side + 2 * cap};
  }
}
bool Capsule::contains(const Vec3& x) const {
  const double s = std::clamp((x - mid_).dot(axis_), -half_length_, half_length_);
  return (x - (mid_ + s * axis_)).squaredNorm() <= radius_ * radius_;
}
Bounds Capsule::bounds() const {
  Vec3 r = Vec3::Constant(radius_);
  if (dim_ == 2) r(2) = 0;
  return {a_.cwiseMin(b_) - r, a_.cwiseMax(b_) + r};
}
double Capsule::volume() const {
  const double r = radius_, l = 2 * half_length_;
  return dim_ == 2 ? 2 * r * l + kPi * r * r : kPi * r * r * l + 4.0 / 3.0 * kPi * r * r * r;
}
Scalar2 Capsule::distance(const Coords& x) const {
  Scalar2 s(0.0), q2(0.0);
  for (int i = 0; i < dim_; ++i) {
    const Scalar2 q = x[i] - mid_(i);
    s = s + q * axis_(i);
    q2 = q2 + square(q);
  }
  const double r = radius_, h = half_length_;
  const Scalar2 tube = (r * r - (q2 - square(s))) / (2 * r);
  const Scalar2 slab_d = (h * h - square(s)) / (2 * h);
  return r_or(r_or(r_and(tube, slab_d), ball_distance(x, a_, r, dim_)), ball_distance(x, b_, r, dim_));
}
SurfacePoint Capsule::boundary_point(const double* u) const {
  double u0 = u[0];
  const int piece = pick_piece(u0, pieces_);
  SurfacePoint p;
  if (dim_ == 2) {
    if (piece < 2) {
      const double side = piece == 0 ? 1 : -1;
      p.normal = side * p1_;
      p.point = mid_ + (2 * u[1] - 1) * half_length_ * axis_ + radius_ * p.normal;
    } else {
      const double sign = piece == 2 ? 1 : -1, t = kPi * (u[1] - 0.5);
      p.normal = sign * (std::cos(t) * axis_ + std::sin(t) * p1_);
      p.point = (piece == 2 ? b_ : a_) + radius_ * p.normal;
    }
    return p;
  }
  const double t = 2 * kPi * u[2];
  if (piece == 0) {
    p.normal = std::cos(t) * p1_ + std::sin(t) * p2_;
    p.point = mid_ + (2 * u[1] - 1) * half_length_ * axis_ + radius_ * p.normal;
  } else {
    // A hemisphere: the axial component uniform in [0, 1] (Archimedes again).
    const double sign = piece == 1 ? 1 : -1, z = u[1], s = std::sqrt(std::max(0.0, 1 - z * z));
    p.normal = sign * z * axis_ + s * (std::cos(t) * p1_ + std::sin(t) * p2_);
    p.point = (piece == 1 ? b_ : a_) + radius_ * p.normal;
  }
  return p;
}

}  // namespace nfield::solvers::geometry
