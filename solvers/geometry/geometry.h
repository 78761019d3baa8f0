// SPDX-License-Identifier: MIT
//
// A domain made of shapes: primitives (primitives.h, polygon.h, mesh_shape.h) combined by
// union, intersection and difference, nested to any depth, each primitive placed by a
// similarity x ↦ s R x + t (uniform scale s > 0, rotation R, translation t) and named. The
// named primitives are the parts of the boundary that conditions can be put on.
//
// Tree. Transforms are pushed down to the leaves when the tree is built (a transform of a
// union is the union of the transformed operands), so every leaf knows its own map to world
// coordinates and the inner nodes only combine. Leaves are numbered in depth-first order, so
// a node's leaves are a contiguous range; a leaf's number is its part id.
//
// Inside test:   union: in any operand; intersection: in all; difference A ∖ B ∖ C …: in A
//                and in none of the others (closed sets: a point on ∂B counts as in B).
//
// Interior points are drawn uniformly in the axis-aligned bounding box (union: the hull of the
// operands' boxes, intersection: their overlap, difference: the minuend's; a leaf: its box's
// image under the map) and kept when inside: the kept points are uniform in Ω. Each candidate
// uses d coordinates of the engine; candidates come in batches, and a batch's surplus is
// dropped, so the number of draws per call varies with the acceptance rate (|Ω| / |box|).
// With a sobol or halton sequence attached (solvers/sampling/random.h) the candidates are
// consecutive sequence points, and the accepted ones are the sequence restricted to Ω: a
// deterministic function of the seed and the counts drawn (checkpoints stay exact), and as
// even as the sequence's discrepancy over the sets {box ∩ Ω} allows, which for a curved
// boundary is the isotropic discrepancy, O(N^{-1/d}) in the worst case rather than the
// (log N)^d/N of boxes (in practice far better than random: the Koksma–Hlawka variation of a
// smooth integrand times the indicator is what enters).
//
// Boundary points come from the leaves: a candidate takes d + 1 engine coordinates u; u₀ picks
// a selected leaf with probability ∝ its proposal measure (pick_piece) and, rescaled, goes on
// with u₁ … u_{d−1} into the leaf's boundary_point, which gives a point uniform on the leaf's
// boundary after the acceptance test u_d < w (primitive.h). The point is kept when it lies on
// the final boundary: walking from the leaf up to the root, at each node the other operands
// must be — union: all outside; intersection: all inside; difference, leaf in the minuend:
// all outside; leaf in a subtrahend: inside the minuend and outside the other subtrahends, and
// the normal is flipped (a hole's outward normal points into the hole). Keeping a subset of a
// uniform sample leaves it uniform on that subset, so the points are uniform over the selected
// part of ∂Ω, each carrying its leaf's id and exact normal. Where two operands' boundaries
// coincide on a set of positive measure (a shared face) the closed-set test drops the points
// of both: such a face is not part of ∂Ω of a union, and is of a difference only when the
// tree says so twice; keep such touching faces apart by a margin if they matter.
//
// Quadrature. boundary_quadrature is the deterministic counterpart of sample_boundary, for
// integrals over parts of ∂Ω (forces on a body): each selected leaf's pieces (primitive.h,
// pieces) in turn, a midpoint grid in u₁ (2-D) or u₁ × u₂ (3-D) over each, of about n points
// in all shared by measure, each weighted by its piece's measure × w / the piece's count, and
// the points that do not lie on the final boundary (or fail `where`) dropped. On a whole
// circle this is the periodic midpoint rule, exact for trigonometric polynomials of degree
// below the count (spectral for smooth integrands); on faces and edges it is the midpoint
// rule, O(h²); where another operand trims a piece the cut is resolved to one cell, O(h).
//
// Measures. A single leaf's volume and boundary measure are exact (× s^d, × s^{d−1}). Otherwise
// they are Monte Carlo estimates: |Ω| ≈ |box| · k/N from N candidates of which k are inside,
// with standard error |box| √(p(1 − p)/N), p = k/N; the boundary likewise as the proposal
// measure times the accepted share. `Measure` carries the value, that standard error and
// whether it is exact; a test at 4 standard errors fails by chance with probability 6·10⁻⁵.
//
// Distance functions (Sukumar & Srivastava, CMAME 389 (2022) 114333). ψ of the whole domain
// joins the leaves' ψ (each normalised to first order, positive inside) by the R0 functions
// r_or / r_and (scalar2.h), with −ψ for subtrahends: positive inside, 0 on all of ∂Ω, smooth
// inside. For a selection of parts (φ = 0 on those only) each selected leaf ℓ gives the trimmed
// distance to the part of its boundary that survives,
//     f = ψ_ℓ,  t = the R0 conjunction of the conditions of the walk above (−ψ for "outside",
//     ψ for "inside"),  φ_ℓ = √(f² + ((√(t² + f⁴) − t)/2)²)  (or σf when the leaf has no
//     conditions, σ = −1 for a hole),
// which vanishes exactly where f = 0 and t ≥ 0, is ≈ |f| near the kept part, and positive
// elsewhere; the parts are joined by R-equivalence φ = (Σ φ_ℓ⁻¹)⁻¹, normalised to first order
// (∂φ/∂n = −1 on each chosen part away from where parts meet). Value, gradient and Hessian
// come from Scalar2.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/expression.h"
#include "solvers/geometry/primitive.h"
#include "solvers/sampling/random.h"

namespace nfield::solvers::geometry {

// x ↦ s R x + t.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  Vec3 apply(const Vec3& x) const { return scale * (rotation * x) + translation; }
  Vec3 inverse(const Vec3& x) const { return rotation.transpose() * (x - translation) / scale; }
  // This map after `inner`: x ↦ this(inner(x)).
  Similarity after(const Similarity& inner) const;
  // Rotations from angles in degrees: 2-D about z; 3-D about x, then y, then z (fixed axes).
  static Eigen::Matrix3d rotation_2d(double degrees);
  static Eigen::Matrix3d rotation_3d(const Vec3& degrees);
};

enum class Combine { kLeaf, kUnion, kIntersection, kDifference };

// A tree under construction.
class ShapeTree {
 public:
  static ShapeTree primitive(std::string name, std::unique_ptr<Primitive> shape);
  // At least one operand; a difference removes the second and later ones from the first.
  static ShapeTree combine(Combine op, std::vector<ShapeTree> operands);
  // Places the whole tree: applied after any placement already given.
  ShapeTree&& place(const Similarity& map) &&;

 private:
  friend class Geometry;
  struct Leaf {
    std::string name;
    std::unique_ptr<Primitive> shape;
    Similarity map;
  };
  Combine op_ = Combine::kLeaf;
  std::vector<ShapeTree> operands_;
  std::unique_ptr<Leaf> leaf_;
};

struct Measure {
  double value = 0;
  double std_error = 0;  // 0 when exact
  bool exact = false;
};

// The boundary points of one draw: n×d points and outward unit normals, and the part id of each.
struct BoundarySample {
  Eigen::MatrixXd points, normals;
  Eigen::VectorXi parts;
};

// Nodes of a quadrature over part of ∂Ω: ∫ f dS ≈ Σ weights(i) f(points.row(i)).
struct BoundaryQuadrature {
  Eigen::MatrixXd points, normals;  // n × d; the outward unit normals
  Eigen::VectorXd weights;
  Eigen::VectorXi parts;
};

// Which part of the boundary: leaves (empty = all) and optionally an expression over x, y, z
// that must be nonzero (`x < -0.49` is 1 or 0). io::Expression (muparser) rather than
// io::CompiledExpression: the selection needs comparisons, which the compiled tape lacks, and
// costs one evaluation per candidate, not per training step.
struct Selection {
  std::vector<int> parts;
  std::shared_ptr<const io::Expression> where;
  bool all() const { return parts.empty() && !where; }
};

class Geometry {
 public:
  // Throws std::invalid_argument: dimensions that differ, duplicate part names (any case).
  explicit Geometry(ShapeTree tree);
  Geometry(Geometry&&) noexcept;
  Geometry& operator=(Geometry&&) noexcept;
  ~Geometry();

  int dim() const { return dim_; }
  int part_count() const { return static_cast<int>(leaves_.size()); }
  const std::string& part_name(int part) const;
  const Primitive& part_shape(int part) const;
  // Case-insensitive; the error lists the names.
  int part(const std::string& name) const;
  // Parts by name ("boundary" alone means all) and an optional `where` expression over x, y, z;
  // errors as io::ExpressionError (position in `where`) or std::invalid_argument (a name).
  Selection select(const std::vector<std::string>& names, const std::string& where = "") const;

  Bounds bounds() const;
  bool contains(const Vec3& x) const;
  Eigen::Array<bool, Eigen::Dynamic, 1> contains_rows(const Eigen::MatrixXd& points) const;  // n×d

  // The outward unit normal at a point of ∂Ω: −∇ψ/|∇ψ| of the whole domain's ψ. On a leaf's
  // boundary the R0 joins reduce ∇ψ to that leaf's ±∇ψ_ℓ (the other operand's terms cancel
  // where it is nonzero), so this is the leaf's exact normal, flipped for holes; at corners
  // (where two leaves meet, a set of measure zero) it is some average.
  Vec3 normal(const Vec3& x) const;
  // ψ of the whole domain, or the ADF φ vanishing on `selection`'s parts (no `where`).
  Scalar2 distance(const Vec3& x) const;
  Scalar2 distance(const Vec3& x, const Selection& selection) const;

  // n×d interior points, uniform over Ω. Throws std::runtime_error when 10⁶ candidates in a
  // row miss Ω (an empty domain).
  Eigen::MatrixXd sample_interior(Random& rng, Eigen::Index n) const;
  BoundarySample sample_boundary(Random& rng, Eigen::Index n, const Selection& selection = {}) const;
  // About n nodes (at least one per piece) over the selected part (see Quadrature above).
  BoundaryQuadrature boundary_quadrature(const Selection& selection, Eigen::Index n) const;

  // |Ω| (area in 2-D): exact for one leaf, else estimated from `samples` candidates of a
  // private engine seeded with `seed`.
  Measure volume(Eigen::Index samples = 1 << 16, std::uint64_t seed = 1) const;
  Measure boundary_measure(const Selection& selection = {}, Eigen::Index samples = 1 << 16,
                           std::uint64_t seed = 1) const;

 private:
  struct Node {
    Combine op = Combine::kLeaf;
    int leaf = -1;
    int first = 0, end = 0;  // leaves [first, end)
    std::vector<Node> children;
  };
  struct Leaf {
    std::string name;
    std::unique_ptr<Primitive> shape;
    Similarity map;
  };
  Node build(ShapeTree&& tree, const Similarity& outer);
  bool contains(const Node& node, const Vec3& x) const;
  Bounds bounds(const Node& node) const;
  Scalar2 psi(const Node& node, const Coords& x) const;
  Scalar2 leaf_psi(int leaf, const Coords& x) const;
  // +1 / −1 (normal flipped) when a point of leaf's boundary lies on node's boundary, else 0.
  int keep(const Node& node, int leaf, const Vec3& x) const;
  // The trimming function of leaf's surviving boundary, or nullopt when nothing trims it.
  std::optional<Scalar2> trim(const Node& node, int leaf, const Coords& x) const;
  int orientation(const Node& node, int leaf) const;
  bool selected(const Selection& s, int leaf, const Vec3& x) const;

  int dim_ = 0;
  std::vector<Leaf> leaves_;
  Node root_;
};

}  // namespace nfield::solvers::geometry
