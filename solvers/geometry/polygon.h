// SPDX-License-Identifier: MIT
//
// A simple polygon (2-D): its vertices in order, either winding (stored counter-clockwise), or
// read from a text file of `x y` lines (`#` comments, blank lines skipped). A closed polyline
// bounds a 2-D domain this way, as a closed triangle surface bounds a 3-D one (mesh_shape.h).
//
// Refused (std::invalid_argument saying where): fewer than three vertices, a zero-length edge,
// and two edges that cross or touch other than at their shared vertex (checked for all pairs,
// O(n²): a polygon of 10⁴ vertices takes about a second).
//
// Inside test: the even–odd rule along +x (a crossing counts when one end lies strictly above
// the point's y and the other not, so a vertex on the ray counts once).
//
// Distance (Sukumar & Srivastava 2022, §3): for the edge x₁x₂ of length L and centre x_c,
//     f = (x − x₁) × (x₂ − x₁) / L          signed distance to the edge's line
//     t = ((L/2)² − |x − x_c|²) / L        ≥ 0 on the segment, < 0 on the rest of the line
//     φ_e = √(f² + ((√(t² + f⁴) − t)/2)²)  0 exactly on the segment, ≈ |f| near it
// joined by R-equivalence φ = (Σ_e φ_e⁻¹)⁻¹, which is 0 on ∂Ω and normalised to first order
// away from vertices, and signed: ψ = φ inside, −φ outside (smooth off ∂Ω, where φ > 0).
// Boundary points: an edge with probability ∝ its length, uniform along it; the normal is the
// edge's direction turned clockwise (outward for the counter-clockwise order).
#pragma once

#include <filesystem>

#include <Eigen/Core>

#include "solvers/geometry/primitive.h"

namespace nfield::solvers::geometry {

class Polygon final : public Primitive {
 public:
  // vertices: n×2, n ≥ 3.
  explicit Polygon(const Eigen::MatrixXd& vertices);
  std::string type() const override { return "polygon"; }
  int dim() const override { return 2; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override;
  double volume() const override { return area_; }
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override { return cumulative_.back(); }
  std::vector<double> pieces() const override { return cumulative_; }
  const Eigen::MatrixXd& vertices() const { return v_; }

 private:
  Eigen::MatrixXd v_;  // n×2, counter-clockwise
  std::vector<double> cumulative_;
  double area_ = 0;
};

// `x y` per line; throws std::runtime_error naming the file (and line) when it is missing or
// a line is not two numbers.
Eigen::MatrixXd read_polygon_file(const std::filesystem::path& path);

// The first pair of edges (i, j) that cross, or (−1, −1) when there is none; edges i join
// vertices i and i + 1 (mod n).
std::pair<int, int> crossing_edges(const Eigen::MatrixXd& vertices);

}  // namespace nfield::solvers::geometry
