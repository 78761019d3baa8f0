// SPDX-License-Identifier: MIT
//
// The eikonal residual as it was written by hand before it went through JetResidual
// (solvers/problems/eikonal_residual.cc): value and adjoint coded separately. Kept only as
// the reference that jet_residual_test compares the Jet-derived residuals with.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

#include "solvers/problems/eikonal_residual.h"

namespace nfield::solvers::reference {

// The residuals of the three loss terms on one point set; u is the network output (plain) or
// T₀ (1 + τ) (factored):
//   eikonal  r = |∇u| − s(x) − ε·(viscous term), s = 1/v
//   outflow  r = [min(0, ∇u·n), min(0, u)/L] with outward normals n
//   source   r = the output itself (u or τ) at x₀
//   interface  r = max(0, −∇u·n) (1/v_far − |∇u − (∇u·n) n|), n the normal from the source's
//            layer to the far one, on the source's side of the plane
class EikonalResidual final : public Residual {
 public:
  using Kind = EikonalKind;
  using Setup = EikonalSetup;

  // per_point: the slowness s (eikonal, one value per point) or the normals (outflow and
  // interface, one row per point); unused for the source.
  EikonalResidual(Kind kind, Eigen::MatrixXd points, Eigen::MatrixXd per_point, Setup setup)
      : kind_(kind), points_(std::move(points)), per_point_(std::move(per_point)),
        setup_(std::move(setup)) {}

  int components() const override { return kind_ == Kind::kOutflow ? 2 : 1; }

  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    const Eigen::Index n = out.points;
    const int d = static_cast<int>(points_.cols());
    r.resize(n, components());
    Eigen::VectorXd g(d), grad_t0(d);
    for (Eigen::Index p = 0; p < n; ++p) {
      if (kind_ == Kind::kSource) {
        r(p, 0) = out.stream(StreamLayout::value())(p, 0);
        continue;
      }
      const double t0 = gradient(first + p, p, layout, out, g, grad_t0);
      if (kind_ == Kind::kOutflow) {
        r(p, 0) = std::min(0.0, per_point_.row(first + p).dot(g));
        r(p, 1) = std::min(0.0, value(t0, p, out)) / setup_.length;
      } else if (kind_ == Kind::kInterface) {
        const Eigen::VectorXd normal = per_point_.row(first + p).transpose();
        const double s = normal.dot(g);
        r(p, 0) = s < 0 ? -s * (setup_.far_slowness - (g - s * normal).norm()) : 0.0;
      } else {
        r(p, 0) = g.norm() - per_point_(first + p, 0);
        if (setup_.viscosity > 0)
          r(p, 0) -= setup_.viscosity * viscous_laplacian(first + p, p, t0, layout, out);
      }
    }
  }

  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    const Eigen::Index n = out.points;
    const int d = static_cast<int>(points_.cols());
    Eigen::VectorXd g(d), grad_t0(d), g_bar(d);
    for (Eigen::Index p = 0; p < n; ++p) {
      if (kind_ == Kind::kSource) {
        adjoint.stream(StreamLayout::value())(p, 0) += r_bar(p, 0);
        continue;
      }
      const double t0 = gradient(first + p, p, layout, out, g, grad_t0);
      if (kind_ == Kind::kOutflow) {
        if (value(t0, p, out) < 0)
          adjoint.stream(StreamLayout::value())(p, 0) +=
              r_bar(p, 1) * (setup_.factored ? t0 : 1.0) / setup_.length;
        const Eigen::VectorXd normal = per_point_.row(first + p).transpose();
        if (!(normal.dot(g) < 0)) continue;
        g_bar = r_bar(p, 0) * normal;
      } else if (kind_ == Kind::kInterface) {
        const Eigen::VectorXd normal = per_point_.row(first + p).transpose();
        const double s = normal.dot(g);
        if (!(s < 0)) continue;
        const Eigen::VectorXd tangential = g - s * normal;
        const double t = tangential.norm();
        g_bar = -(setup_.far_slowness - t) * normal;
        if (t > 1e-12) g_bar += (s / t) * tangential;  // |t| not differentiable at 0
        g_bar *= r_bar(p, 0);
      } else {
        if (setup_.viscosity > 0 &&
            (!setup_.concave || viscous_laplacian(first + p, p, t0, layout, out) < 0))
          laplacian_backward(first + p, p, t0, -setup_.viscosity * r_bar(p, 0), layout, adjoint);
        const double norm = g.norm();
        if (!(norm > 1e-12)) continue;  // |g| is not differentiable at 0: subgradient 0
        g_bar = (r_bar(p, 0) / norm) * g;
      }
      if (setup_.factored) {
        adjoint.stream(StreamLayout::value())(p, 0) += g_bar.dot(grad_t0);
        for (int a = 0; a < d; ++a) adjoint.stream(layout.tangent(a))(p, 0) += t0 * g_bar(a);
      } else {
        for (int a = 0; a < d; ++a) adjoint.stream(layout.tangent(a))(p, 0) += g_bar(a);
      }
    }
  }

 private:
  // The Laplacian in the viscous term, ε times which is subtracted from the residual, at point
  // `index` (row `row`); plain: Δu, the Laplacian stream, or min(0, Δu) (concave). Factored,
  // with T₀ from gradient(), Δu = (1 + τ) ΔT₀ + 2 ∇T₀·∇τ + T₀ Δτ: the `laplacian` form leaves
  // out the curvature ΔT₀ = (d − 1)/(v₀ |x − x₀|) of the analytic factor, the concave form keeps
  // it (near x₀ it makes Δu > 0, which the form drops). See the header.
  // ∇T₀ is formed here again rather than taken from gradient(): the two round differently in
  // the last bit, and the two-layer accuracy run is that sensitive (docs/results.md, Accuracy).
  double viscous_laplacian(Eigen::Index index, Eigen::Index row, double t0,
                           const StreamLayout& layout, const Streams<double>& out) const {
    const double lap = out.stream(layout.op(0))(row, 0);
    if (!setup_.factored) return setup_.concave ? std::min(0.0, lap) : lap;
    const int d = static_cast<int>(points_.cols());
    const Eigen::VectorXd e = points_.row(index).transpose() - setup_.x0;
    const double distance = e.norm();
    if (!(distance > 0)) return 0;
    double grad_dot = 0;
    for (int a = 0; a < d; ++a)
      grad_dot += e(a) / (distance * setup_.v0) * out.stream(layout.tangent(a))(row, 0);
    if (!setup_.concave) return 2 * grad_dot + t0 * lap;
    const double factor_curvature =
        (1 + out.stream(StreamLayout::value())(row, 0)) * (d - 1) / (distance * setup_.v0);
    return std::min(0.0, 2 * grad_dot + t0 * lap + factor_curvature);
  }

  // Adds weight · ∂(viscous Laplacian)/∂(streams) to the adjoint streams; for the concave
  // form, only where the Laplacian is < 0 (the caller checks).
  void laplacian_backward(Eigen::Index index, Eigen::Index row, double t0, double weight,
                          const StreamLayout& layout, Streams<double>& adjoint) const {
    if (!setup_.factored) {
      adjoint.stream(layout.op(0))(row, 0) += weight;
      return;
    }
    const int d = static_cast<int>(points_.cols());
    const Eigen::VectorXd e = points_.row(index).transpose() - setup_.x0;
    const double distance = e.norm();
    if (!(distance > 0)) return;
    for (int a = 0; a < d; ++a)
      adjoint.stream(layout.tangent(a))(row, 0) += weight * 2 * e(a) / (distance * setup_.v0);
    adjoint.stream(layout.op(0))(row, 0) += weight * t0;
    if (setup_.concave)
      adjoint.stream(StreamLayout::value())(row, 0) += weight * (d - 1) / (distance * setup_.v0);
  }

  // u at row `row`, T₀ from gradient().
  double value(double t0, Eigen::Index row, const Streams<double>& out) const {
    const double v = out.stream(StreamLayout::value())(row, 0);
    return setup_.factored ? t0 * (1 + v) : v;
  }

  // ∇u at point `index` of the set (row `row` of the streams); factored: also ∇T₀
  // and returns T₀ (∇T₀ = 0 at x₀ itself, where it is undefined); u = T₀ (1 + τ).
  double gradient(Eigen::Index index, Eigen::Index row, const StreamLayout& layout,
                  const Streams<double>& out, Eigen::VectorXd& g, Eigen::VectorXd& grad_t0) const {
    const int d = static_cast<int>(points_.cols());
    for (int a = 0; a < d; ++a) g(a) = out.stream(layout.tangent(a))(row, 0);
    if (!setup_.factored) return 0;
    const Eigen::VectorXd e = points_.row(index).transpose() - setup_.x0;
    const double distance = e.norm();
    const double t0 = distance / setup_.v0;
    if (distance > 0)
      grad_t0 = e / (distance * setup_.v0);
    else
      grad_t0.setZero();
    const double tau = 1 + out.stream(StreamLayout::value())(row, 0);
    g = tau * grad_t0 + t0 * g;
    return t0;
  }

  Kind kind_;
  Eigen::MatrixXd points_;
  Eigen::MatrixXd per_point_;
  Setup setup_;
};

}  // namespace nfield::solvers::reference
