// SPDX-License-Identifier: MIT
//
// The analytic primitives: box, ball (disk in 2-D), ellipse(oid), cylinder (3-D, axis z) and
// capsule (the points within r of a segment). Each is given in world coordinates; rotations
// and scalings come from the tree around it (solvers/geometry/shape_tree.h).
//
// Distance functions ψ (positive inside, normalised to first order, smooth inside):
//   slab |x_a − c_a| ≤ h        (h² − (x_a − c_a)²) / 2h
//   ball |x − c| ≤ r            (r² − |x − c|²) / 2r
//   box                         the slabs joined by the R0 conjunction (scalar2.h)
//   ellipsoid g = 1 − Σ(q_i/a_i)²   g / √(g² + |∇g|²): on ∂Ω this is g/|∇g|, whose gradient is
//                               the unit inward normal; the root never vanishes (∇g = 0 only
//                               at the centre, where g = 1)
//   cylinder                    disk(x, y) ∧ slab(z)
//   capsule                     (tube ∧ slab) ∨ ball(a) ∨ ball(b): the flat ends of the finite
//                               tube lie inside the end balls, so only the true surface is a zero
// The exact Euclidean distance is avoided on purpose: it is not C² (its Hessian jumps across
// the medial axis, inside the domain), which the second derivatives of the ansatz would see.
#pragma once

#include "solvers/geometry/primitive.h"

namespace nfield::solvers::geometry {

class Box final : public Primitive {
 public:
  Box(int dim, const Vec3& lower, const Vec3& upper);
  std::string type() const override { return "box"; }
  int dim() const override { return dim_; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override { return {lower_, upper_}; }
  double volume() const override;
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override { return faces_.back(); }
  std::vector<double> pieces() const override { return faces_; }

 private:
  int dim_;
  Vec3 lower_, upper_;
  std::vector<double> faces_;  // cumulative measure of faces (axis 0 low, high, axis 1 …)
};

class Ball final : public Primitive {
 public:
  Ball(int dim, const Vec3& center, double radius);
  std::string type() const override { return dim_ == 2 ? "disk" : "ball"; }
  int dim() const override { return dim_; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override;
  double volume() const override;
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override;

 private:
  int dim_;
  Vec3 center_;
  double radius_;
};

class Ellipsoid final : public Primitive {
 public:
  Ellipsoid(int dim, const Vec3& center, const Vec3& semi_axes);
  std::string type() const override { return dim_ == 2 ? "ellipse" : "ellipsoid"; }
  int dim() const override { return dim_; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override;
  double volume() const override;
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override;
  double boundary_measure() const override { return std::numeric_limits<double>::quiet_NaN(); }

 private:
  int dim_;
  Vec3 center_, axes_;
};

class Cylinder final : public Primitive {
 public:
  Cylinder(const Vec3& center, double radius, double height);
  std::string type() const override { return "cylinder"; }
  int dim() const override { return 3; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override;
  double volume() const override;
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override { return pieces_.back(); }
  std::vector<double> pieces() const override { return pieces_; }

 private:
  Vec3 center_;
  double radius_, half_height_;
  std::vector<double> pieces_;  // side, bottom, top
};

class Capsule final : public Primitive {
 public:
  Capsule(int dim, const Vec3& a, const Vec3& b, double radius);
  std::string type() const override { return "capsule"; }
  int dim() const override { return dim_; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override;
  double volume() const override;
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override { return pieces_.back(); }
  std::vector<double> pieces() const override { return pieces_; }

 private:
  int dim_;
  Vec3 a_, b_, mid_, axis_, p1_, p2_;  // axis unit; p1, p2 complete an orthonormal frame
  double radius_, half_length_;
  std::vector<double> pieces_;
};

}  // namespace nfield::solvers::geometry
