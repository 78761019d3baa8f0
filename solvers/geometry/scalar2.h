// SPDX-License-Identifier: MIT
//
// A number that carries its first and second derivatives with respect to the (up to three)
// space coordinates: value v, gradient g ∈ R³, Hessian H ∈ R³ˣ³. The distance functions of
// solvers/geometry are written once over this type and so give the value, gradient and
// Hessian that the ansatz u = A + φ·N needs (solvers/core/ansatz.h evaluates D
// with its first and second derivatives).
//
// Rules (forward mode, second order). For a unary f:
//     f(a) = f(v),  ∇ = f'(v) g,  H = f'(v) H_a + f''(v) g gᵀ;
// for a product:  ∇(ab) = a ∇b + b ∇a,  H(ab) = a H_b + b H_a + g_a g_bᵀ + g_b g_aᵀ.
// Division is a product with 1/b. The cost is a fixed 13 doubles per number, fine for the
// few dozen operations of a primitive; 2-D shapes simply leave the third coordinate's entries 0.
//
// Pitfalls: sqrt at 0 has an infinite derivative (R-function corners lie on the boundary,
// where φ = 0, so interior points never meet it); a Scalar2 built from a double is a constant.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace nfield::solvers::geometry {

struct Scalar2 {
  double v = 0;
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();

  Scalar2() = default;
  Scalar2(double value) : v(value) {}  // NOLINT: a constant
  // The coordinate `axis` at `value` (gradient e_axis, Hessian 0).
  static Scalar2 variable(double value, int axis) {
    Scalar2 s(value);
    s.g(axis) = 1;
    return s;
  }
  // A function of this number with derivatives d1 = f'(v), d2 = f''(v).
  Scalar2 chain(double f, double d1, double d2) const {
    Scalar2 r(f);
    r.g = d1 * g;
    r.h = d1 * h + d2 * g * g.transpose();
    return r;
  }
};

inline Scalar2 operator-(const Scalar2& a) {
  Scalar2 r(-a.v);
  r.g = -a.g;
  r.h = -a.h;
  return r;
}
inline Scalar2 operator+(const Scalar2& a, const Scalar2& b) {
  Scalar2 r(a.v + b.v);
  r.g = a.g + b.g;
  r.h = a.h + b.h;
  return r;
}
inline Scalar2 operator-(const Scalar2& a, const Scalar2& b) { return a + (-b); }
inline Scalar2 operator*(const Scalar2& a, const Scalar2& b) {
  Scalar2 r(a.v * b.v);
  r.g = a.v * b.g + b.v * a.g;
  r.h = a.v * b.h + b.v * a.h + a.g * b.g.transpose() + b.g * a.g.transpose();
  return r;
}
inline Scalar2 operator*(double c, const Scalar2& a) {
  Scalar2 r(c * a.v);
  r.g = c * a.g;
  r.h = c * a.h;
  return r;
}
inline Scalar2 operator*(const Scalar2& a, double c) { return c * a; }
inline Scalar2 inverse(const Scalar2& b) {
  const double i = 1 / b.v;
  return b.chain(i, -i * i, 2 * i * i * i);
}
inline Scalar2 operator/(const Scalar2& a, const Scalar2& b) { return a * inverse(b); }
inline Scalar2 operator/(const Scalar2& a, double c) { return (1 / c) * a; }
inline Scalar2 sqrt(const Scalar2& a) {
  const double s = std::sqrt(a.v);
  return a.chain(s, 0.5 / s, -0.25 / (s * a.v));
}
inline Scalar2 square(const Scalar2& a) { return a * a; }

// R-functions of the R0 system (Rvachev; Sukumar & Srivastava 2022, eq. 9): for ψ₁, ψ₂
// positive inside their sets and normalised to first order, these are positive inside the
// intersection / union, zero on its boundary, and again normalised to first order away from
// the points where ψ₁ = ψ₂ = 0 (corners, which lie on the boundary).
inline Scalar2 r_and(const Scalar2& a, const Scalar2& b) { return a + b - sqrt(a * a + b * b); }
inline Scalar2 r_or(const Scalar2& a, const Scalar2& b) { return a + b + sqrt(a * a + b * b); }

}  // namespace nfield::solvers::geometry
