// SPDX-License-Identifier: MIT
//
// The interface of one shape of the geometry layer: a closed set Ω ⊂ Rᵈ (d = 2 or 3) in its
// own frame, with what sampling, named boundary parts and distance functions need of it.
//
//   contains(x)            the inside test (the closed set: boundary points count as inside)
//   bounds()               an axis-aligned box around Ω (interior points are drawn from it)
//   volume()               |Ω| (area in 2-D), exact
//   distance(x)            ψ: positive inside, 0 on ∂Ω, negative outside, normalised to first
//                          order (|∇ψ| = 1 and ∇ψ = −n on ∂Ω), smooth inside Ω, with gradient and
//                          Hessian (Scalar2)
//   boundary_point(u)      a map from u ∈ [0, 1)ᵈ onto ∂Ω with the exact outward unit normal and
//                          an acceptance weight w ∈ (0, 1]
//   proposal_measure()     the measure of the proposal that boundary_point makes
//
// Uniform boundary points. boundary_point pushes uniform u forward to a density p on ∂Ω; a
// caller keeps the point with probability w (one more uniform draw), and the kept points are
// uniform on ∂Ω when w ∝ 1/p. Shapes with an area-preserving map (box faces, sphere through
// z = 1 − 2u, disk caps through ρ = r√u) have w ≡ 1 and proposal_measure() = |∂Ω|; an ellipse(oid)
// pushes the circle's (sphere's) uniform measure through x = a∘s and keeps a point with the
// ratio of its area element to the largest one (w = min aᵢ · |s/a|), proposal_measure() = that
// largest element times |S^{d−1}|. The first coordinate u₀ also picks the piece of a boundary
// made of pieces (faces, caps): with cumulative shares c_k it picks k where c_{k−1} ≤ u₀ < c_k
// and is rescaled to (u₀ − c_{k−1}) / (c_k − c_{k−1}), so one coordinate serves both (pick_piece).
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/geometry/scalar2.h"

namespace nfield::solvers::geometry {

using Vec3 = Eigen::Vector3d;          // 2-D shapes leave z = 0
using Coords = std::array<Scalar2, 3>;  // a point whose coordinates carry derivatives

struct Bounds {
  Vec3 lower = Vec3::Zero(), upper = Vec3::Zero();
  bool empty(int dim) const {
    for (int i = 0; i < dim; ++i)
      if (!(upper(i) > lower(i))) return true;
    return false;
  }
};

struct SurfacePoint {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // outward, unit
  double accept = 1;           // w ∈ (0, 1]
};

class Primitive {
 public:
  virtual ~Primitive() = default;
  virtual std::string type() const = 0;
  virtual int dim() const = 0;
  virtual bool contains(const Vec3& x) const = 0;
  virtual Bounds bounds() const = 0;
  virtual double volume() const = 0;
  virtual Scalar2 distance(const Coords& x) const = 0;
  virtual SurfacePoint boundary_point(const double* u) const = 0;
  virtual double proposal_measure() const = 0;
  // |∂Ω| in closed form, or NaN where there is none (the ellipse's perimeter).
  virtual double boundary_measure() const { return proposal_measure(); }
  // The cumulative proposal measures of the pieces u₀ picks among (pick_piece; the last is
  // proposal_measure()); one piece by default. Within a piece, u₁ … u_{d−1} map onto it with
  // a constant density (up to the weight w), which the boundary quadrature relies on.
  virtual std::vector<double> pieces() const { return {proposal_measure()}; }
};

// Picks the piece k of `cumulative` (increasing, last = total) that u ∈ [0, 1) falls in and
// rescales u to [0, 1) within it.
int pick_piece(double& u, const std::vector<double>& cumulative);

// Coordinates of a plain point as constants-with-gradient: x_i with gradient e_i.
Coords variables(const Vec3& x);

}  // namespace nfield::solvers::geometry
