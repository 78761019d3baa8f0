// SPDX-License-Identifier: MIT
//
// A closed triangle surface as the boundary of a 3-D domain (STL, OBJ, PLY and VTP through
// VTK's readers, OFF through io/triangle_mesh.h).
//
// Checks. Every edge must be shared by exactly two triangles: an edge of one triangle only is
// a hole (refused with the number of such edges and the first one's vertices, indices and
// coordinates), an edge of three or more a non-manifold seam. The triangles are then oriented
// consistently (a walk over neighbours, which must traverse their shared edge in opposite
// directions; a Möbius-like surface is refused) and all flipped if the enclosed signed volume
// (Σ det(a, b, c)/6, the divergence theorem) is negative, so face normals point out. Self-
// intersection is checked by find_self_intersection (one triangle's edge piercing another that
// shares no vertex with it), on the same grid of buckets as below but in 3-D.
//
// Inside test: the parity of the crossings of the ray from x along +x. Only triangles whose
// (y, z) projection covers (x_y, x_z) can cross it, so the projections are binned once into a
// uniform G × G grid of buckets over the (y, z) bounds (G ≈ √m for m triangles: a few
// triangles per bucket on a surface), and a query tests the triangles of one bucket. This is a
// BVH flattened to the one query that parity needs: no tree walk, no stack, O(1) to find the
// candidates. VTK's locators answer "closest" or "first hit" (vtkStaticCellLocator,
// vtkCellLocator, vtkOBBTree); an all-hits line query fills a vtkIdList per call, and
// vtkSelectEnclosedPoints (FiltersModeling, not linked) casts rays through an OBB tree per
// point. Figures: docs/experiments.md (2026-11-26, geometry).
// A ray through a shared edge or vertex must count once: each point-in-triangle test is decided
// per edge by the sign of one orientation determinant computed for the edge's vertices in a
// canonical order (lower index first), 0 counting as positive, so the two triangles of an
// edge always disagree about which side the point is on and exactly one of them claims it
// (triangles that project to a segment are skipped; the ray then meets their neighbours).
//
// Boundary points: a triangle with probability ∝ its area (binary search in the cumulative
// areas), uniform in it by (1 − √u₁) a + √u₁ (1 − u₂) b + √u₁ u₂ c; the face normal.
//
// Distance: ψ = ± the Euclidean distance to the surface (+ inside), through a
// vtkStaticCellLocator's closest point. Its gradient is (x − c)/|x − c| (c the closest point),
// its Hessian 0 when c lies inside a face, (I − eeᵀ − ĝĝᵀ)/d on an edge of direction e and
// (I − ĝĝᵀ)/d at a vertex. It is exact, but only C¹: the Hessian jumps where the closest
// feature changes (the medial axis and the planes between faces and edges).
// With use_spline_distance(cells) (config `distance: smooth`) ψ is instead the quintic
// spline of spline_distance.h fitted to that signed distance: C⁴, what a hard Dirichlet
// condition's φ needs, with its zero set a smooth surface close to the mesh (not on it).
#pragma once

#include <filesystem>
#include <memory>

#include "io/triangle_mesh.h"
#include "solvers/geometry/primitive.h"
#include "solvers/geometry/spline_distance.h"

namespace nfield::solvers::geometry {

class MeshShape final : public Primitive {
 public:
  // Throws std::invalid_argument saying what is wrong and where (see above).
  explicit MeshShape(io::TriangleMesh mesh);
  ~MeshShape() override;
  std::string type() const override { return "mesh"; }
  int dim() const override { return 3; }
  bool contains(const Vec3& x) const override;
  Bounds bounds() const override { return bounds_; }
  double volume() const override { return volume_; }
  Scalar2 distance(const Coords& x) const override;
  SurfacePoint boundary_point(const double* u) const override;
  double proposal_measure() const override { return cumulative_.back(); }
  std::vector<double> pieces() const override { return cumulative_; }
  const io::TriangleMesh& mesh() const { return mesh_; }
  // ψ from here on: the spline fitted to the exact signed distance on a grid of `cells` along
  // the longest side of the bounding box (spline_distance.h); throws for cells < 4.
  void use_spline_distance(int cells);
  const SplineDistance* spline_distance() const { return spline_.get(); }

 private:
  struct Locator;
  io::TriangleMesh mesh_;  // oriented outward
  Eigen::MatrixXd normals_;
  std::vector<double> cumulative_;
  double volume_ = 0;
  Bounds bounds_;
  // (y, z) buckets: triangles of bucket b are bucket_items_[bucket_start_[b] … bucket_start_[b+1]).
  int grid_ = 1;
  double y0_ = 0, z0_ = 0, cell_y_ = 1, cell_z_ = 1;
  std::vector<int> bucket_start_, bucket_items_;
  std::unique_ptr<Locator> locator_;
  std::unique_ptr<SplineDistance> spline_;
};

// Reads a mesh file (io::read_triangle_mesh) and builds the shape; errors name the file.
std::unique_ptr<MeshShape> read_mesh_shape(const std::filesystem::path& path);

// The first pair of triangles that intersect without sharing a vertex, or (−1, −1).
std::pair<int, int> find_self_intersection(const io::TriangleMesh& mesh);

}  // namespace nfield::solvers::geometry
