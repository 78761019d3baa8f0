// SPDX-License-Identifier: MIT
//
// A smooth signed distance: a quintic tensor B-spline fitted to a signed distance sampled on a
// uniform grid. What the hard Dirichlet ansatz u = A + φ·N (solvers/core/ansatz.h) needs of a
// mesh domain, whose exact distance (mesh_shape.h) does not have it.
//
// Why not the exact distance. Δu = N Δφ + 2 ∇φ·∇N + φ ΔN reads φ's Hessian, and a triangle
// surface's exact distance is only C¹: its Hessian is 0 over a face, (I − eeᵀ − ĝĝᵀ)/d beside
// an edge and (I − ĝĝᵀ)/d beside a vertex, so Δφ jumps across every plane between a face's and
// an edge's region and grows like 1/d towards every convex edge, and it has a kink on the
// medial axis. The residual the network must cancel would be discontinuous in every cell of a
// 75 000-triangle bunny. Why not R-functions over the triangles (Sukumar & Srivastava 2022,
// φ = (Σ φ_i⁻ᵐ)^(−1/m) of each triangle's trimmed distance): smooth, and exactly 0 on the
// surface, but O(triangles) per point, 75 000 terms for every collocation point and every
// finite-difference stencil point of A.
//
// This one. Sample the signed distance f at the nodes x_i = o + h i of a grid (h = the longest
// side of the bounding box / `cells`, 4 nodes of margin on every side), prefilter the samples
// once, and evaluate
//
//     φ(x) = Σ_i c_i B((x − x_i)/h),   B = the centred quintic B-spline (support 6h, C⁴),
//
// 6³ = 216 terms for the value, gradient and Hessian at any point: O(1) per point, C⁴ (a
// cubic would do for D = φ, which needs C²; the quintic leaves room for A = g·exp(−φ/δ),
// whose Hessian solvers/core/ansatz.h takes by finite differences). With c_i = f_i the spline would smooth f by (h²/4)·f'' (the quintic
// quasi-interpolant's leading error), moving the zero level by about (h²/4)(κ₁ + κ₂) on a
// surface of curvatures κ; one step of the prefilter's Neumann series, c = 2f − S f with S
// the spline's own values at the nodes (the separable filter (1, 26, 66, 26, 1)/120), cancels
// that term: the error is O(h⁴) where f is smooth, which it is within the reach of the
// surface (the distance to the closest sample of a mesh with edges still smooths its corners
// at the scale h, which is the point).
//
// What it is not. Its zero set is a smooth surface within a small distance of the mesh, not
// the mesh: at the vertices of the test's coarse sphere (32 cells) the largest |φ| is 0.09 h,
// where the polyhedron's corners are rounded (tests/solvers/geometry/spline_distance_test.cc).
// A hard condition then holds exactly on that surface, and the equation is solved inside it.
// Fewer cells smooth more: the distance's ridges on the medial axis (a kink the spline rounds
// over about one cell, so |H| ~ 1/h there) get gentler, the zero set moves further from sharp
// features; configs/poisson_bunny.yaml's choice is in docs/experiments.md. |∇φ| ≈ 1 near the surface (the
// distance normalised to first order), smaller near the medial axis where the spline rounds
// the distance's ridge. Points outside the grid are clamped to its border (φ is meant for the
// domain and a few cells around it).
#pragma once

#include <array>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "solvers/geometry/primitive.h"

namespace nfield::solvers::geometry {

class SplineDistance {
 public:
  // The signed distance at each row of an n×3 point matrix (positive inside).
  using Sampler = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;
  // A grid over `box` with `cells` cells along its longest side (≥ 4); throws
  // std::invalid_argument for fewer cells or an empty box.
  SplineDistance(const Bounds& box, int cells, const Sampler& sample);

  // φ at x with its gradient and Hessian in x.
  Scalar2 operator()(const Vec3& x) const;
  double spacing() const { return h_; }
  const std::array<int, 3>& nodes() const { return n_; }

 private:
  double& c(int i, int j, int k) { return coefficients_[(static_cast<size_t>(k) * n_[1] + j) * n_[0] + i]; }
  double c(int i, int j, int k) const { return coefficients_[(static_cast<size_t>(k) * n_[1] + j) * n_[0] + i]; }

  Vec3 origin_ = Vec3::Zero();
  double h_ = 1;
  std::array<int, 3> n_{};
  std::vector<double> coefficients_;
};

// The six weights B(t + 2 − k), k = 0…5, of the nodes i0 − 2 … i0 + 3 around u = i0 + t
// (t ∈ [0, 1)), with their first and second derivatives in u.
struct QuinticWeights {
  std::array<double, 6> w{}, d1{}, d2{};
};
QuinticWeights quintic_weights(double t);

}  // namespace nfield::solvers::geometry
