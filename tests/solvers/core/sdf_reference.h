// SPDX-License-Identifier: MIT
//
// The SDF residual as it was written by hand before it went through JetResidual
// (solvers/problems/sdf_residual.cc): value and adjoint coded separately. Kept only as the
// reference that jet_residual_test compares the Jet-derived residual with.
#pragma once

#include <Eigen/Core>

#include <cmath>

#include "solvers/problems/sdf_residual.h"

namespace nfield::solvers::reference {

// A residual component whose square is |x| (absolute) or x² (squares): sign(x) √|x| or x,
// and its derivative (0 at x = 0 for √|x|: the loss's own derivative, r̄ ∂r/∂x with
// r̄ ∝ r, tends to ±1 there; 0 is a subgradient).
inline double part(double x, bool absolute) {
  if (!absolute) return x;
  return x < 0 ? -std::sqrt(-x) : std::sqrt(x);
}
inline double part_derivative(double x, bool absolute) {
  if (!absolute) return 1;
  const double root = std::sqrt(std::abs(x));
  return root > 0 ? 0.5 / root : 0.0;
}

// The "surface" (normals given) or "interior" (normals empty) residual; see the header.
class SdfResidual final : public Residual {
 public:
  SdfResidual(Eigen::MatrixXd normals, bool surface, const SdfWeights& w)
      : normals_(std::move(normals)), surface_(surface), w_(w) {}

  int components() const override { return surface_ ? 5 : 2; }

  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    const Eigen::Index n = out.points;
    r.resize(n, components());
    const double ce = std::sqrt(w_.eikonal);
    for (Eigen::Index p = 0; p < n; ++p) {
      const double u = out.stream(StreamLayout::value())(p, 0);
      const Eigen::Vector3d g = gradient(layout, out, p);
      const double norm = g.norm();
      if (surface_) {
        const Eigen::Vector3d unit = norm > 1e-12 ? Eigen::Vector3d(g / norm) : Eigen::Vector3d::Zero();
        const Eigen::Vector3d e = std::sqrt(0.5 * w_.normal) * (unit - normals_.row(first + p).transpose());
        r(p, 0) = std::sqrt(w_.sdf) * part(u, w_.absolute);
        r.block<1, 3>(p, 1) = e.transpose();
        r(p, 4) = ce * part(norm - 1, w_.absolute);
      } else {
        r(p, 0) = ce * part(norm - 1, w_.absolute);
        r(p, 1) = std::sqrt(w_.off_surface) * std::exp(-0.5 * w_.alpha * std::abs(u));
      }
    }
  }

  void backward(Eigen::Index, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    const Eigen::Index n = out.points;
    const double ce = std::sqrt(w_.eikonal);
    for (Eigen::Index p = 0; p < n; ++p) {
      const double u = out.stream(StreamLayout::value())(p, 0);
      const Eigen::Vector3d g = gradient(layout, out, p);
      const double norm = g.norm();
      double u_bar = 0;
      Eigen::Vector3d g_bar = Eigen::Vector3d::Zero();
      const bool smooth = norm > 1e-12;
      const Eigen::Vector3d unit = smooth ? Eigen::Vector3d(g / norm) : Eigen::Vector3d::Zero();
      if (surface_) {
        u_bar += std::sqrt(w_.sdf) * r_bar(p, 0) * part_derivative(u, w_.absolute);
        if (smooth) {
          // ∂ĝ/∂g = (I − ĝĝᵀ)/|g|, symmetric.
          const Eigen::Vector3d e_bar = std::sqrt(0.5 * w_.normal) * r_bar.block<1, 3>(p, 1).transpose();
          g_bar += (e_bar - unit * unit.dot(e_bar)) / norm;
          g_bar += ce * r_bar(p, 4) * part_derivative(norm - 1, w_.absolute) * unit;
        }
      } else {
        if (smooth) g_bar += ce * r_bar(p, 0) * part_derivative(norm - 1, w_.absolute) * unit;
        const double penalty = std::sqrt(w_.off_surface) * std::exp(-0.5 * w_.alpha * std::abs(u));
        const double sign = u > 0 ? 1.0 : u < 0 ? -1.0 : 0.0;
        u_bar += r_bar(p, 1) * penalty * (-0.5 * w_.alpha * sign);
      }
      adjoint.stream(StreamLayout::value())(p, 0) += u_bar;
      for (int a = 0; a < 3; ++a) adjoint.stream(layout.tangent(a))(p, 0) += g_bar(a);
    }
  }

 private:
  static Eigen::Vector3d gradient(const StreamLayout& layout, const Streams<double>& out,
                                  Eigen::Index p) {
    return {out.stream(layout.tangent(0))(p, 0), out.stream(layout.tangent(1))(p, 0),
            out.stream(layout.tangent(2))(p, 0)};
  }

  Eigen::MatrixXd normals_;  // surface: one row per point of the set
  bool surface_;
  SdfWeights w_;
};

}  // namespace nfield::solvers::reference
