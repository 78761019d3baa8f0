// SPDX-License-Identifier: MIT
//
// Signed distance fields from oriented point clouds, with the loss of SIREN (Sitzmann et al.
// 2020, Sec. 4.2): the field u is fitted so that u = 0 and ∇u ∥ n on the surface samples,
// |∇u| = 1 everywhere, and |u| is kept away from 0 off the surface.
//
//   problem: sdf
//   domain: {lower: [-1, -1, -1], upper: [1, 1, 1]}   # optional, this is the default; 3D
//   equation:
//     points: ../data/points/kitten.xyz   # .xyz/.pwn (x y z nx ny nz), .ply/.obj/.vtp/.off
//                                         # (normals from the file or from its faces);
//                                         # relative to the config file's folder
//     normalize: true          # move and scale the cloud into the domain (default true)
//     margin: 0.1              # normalize: the fraction of the domain's half-width left free
//     sdf_weight: 3000         # loss weights, SIREN's defaults (see below)
//     normal_weight: 100
//     eikonal_weight: 50
//     off_surface_weight: 100
//     off_surface_alpha: 100   # α of the off-surface penalty exp(−α|u|)
//     reference_mesh: ../data/meshes/bunny00.ply   # optional: error metrics against it
//     box_weight: 0            # > 0: the "box" term below (training.batch.box points a step)
//
//     loss: siren              # siren | squares (below)
//
// Loss terms (each a mean over its points; w_* the weights above, ĝ = ∇u/|∇u|):
//   "surface"   batch `surface`: points drawn uniformly (with replacement) from the cloud,
//               ‖r‖² = w_sdf |u| + w_normal (1 − cos(∇u, n)) + w_eikonal ||∇u| − 1|,
//               r = [√w_sdf ρ(u),  √(w_normal/2) (ĝ − n),  √w_eikonal ρ(|∇u| − 1)];
//   "interior"  batch `interior`: uniform points in the domain,
//               ‖r‖² = w_eikonal ||∇u| − 1| + w_off exp(−α|u|),
//               r = [√w_eikonal ρ(|∇u| − 1),  √w_off exp(−α|u|/2)],
//   "box"       (only with box_weight > 0) batch `box`: points on the domain's faces,
//               r = √w_box (u − d(x)), d the distance to the nearest cloud point.
// with ρ(x) = sign(x) √|x|, so that these are exactly the per-point losses of SIREN's
// reference code (its means of |u| weighted 3e3, of 1 − cos 1e2, of ||∇u| − 1| 5e1, of
// exp(−α|u|) 1e2 with α = 100; (ĝ − n)²/2 = 1 − cos). `loss: squares` takes ρ(x) = x
// instead (u² and (|∇u| − 1)², least squares proper); on a sphere it places the surface
// about 4 times less accurately with these weights, as small errors then cost little.
// The term weights themselves are 1 (the w_* are inside the residuals). ∂|g|/∂g and ∂ĝ/∂g
// are taken as 0 where |g| = 0, ∂|u|/∂u as 0 at u = 0, and ρ'(0) as 0.
//
// Why the box term: nothing in SIREN's loss fixes the sign far from the cloud, and a level
// set that bends back towards the box's edges (where few interior samples fall per unit of
// face) leaves spurious pieces there. With the normalized cloud inside the domain (margin
// > 0), the faces are outside the shape and the SDF there is the distance to the surface,
// which the distance to the nearest cloud point approximates from above by at most half the
// point spacing. The face points come from a pool of 6 × 96² stratified points whose
// distances are computed once (vtkStaticPointLocator); a step draws from it.
//
// The surface residual finds each point's normal by the point's exact coordinates (the
// samples are copies of cloud points); other points get the normal of the nearest cloud
// point. Cloud points whose normal is zero (none could be found) are dropped.
//
// write_outputs (after training), in the cloud's original coordinates:
//   surface.vtp, surface.ply   the zero level set of u on output.grid (flying edges), with
//                              outward normals in the .vtp;
//   metrics   surface_vertices, surface_triangles, surface_components (connected pieces of the
//             zero level set) and surface_largest_component_area_share (io/surface_components.h);
//             the comparison with reference_mesh, or without one with the input points
//             (io/mesh_distance.h, from the vertices of each):
//             chamfer_surface_to_mesh, chamfer_mesh_to_surface (mean distances of the vertices
//             of one surface to the other; to the nearest input point and from each input point
//             to the surface without a mesh), chamfer_mean (their mean: the symmetric Chamfer
//             distance), chamfer_max (the largest of all those distances, a Hausdorff estimate),
//             both also divided by the bounding-box diagonal of the mesh or points
//             (chamfer_mean_per_diagonal, chamfer_max_per_diagonal), normal_consistency (mean
//             |n · n'| of vertex normals against the nearest triangle's; without a mesh, the
//             input normals against the surface's) and chamfer_seconds (their cost);
//             with reference_mesh also
//             sign_accuracy (the fraction of output grid points where sign(u) agrees with
//             inside (−)/outside (+) of the reference mesh, by the parity of crossings along
//             grid lines: io/inside_mesh.h; the mesh must be closed)
//             and sign_accuracy_band (the same over the grid points closer to the reference
//             surface than 5% of its bounding-box diagonal), and sign_seconds.
//   A field with several scales (field.type: bacon) adds surface_scale<s>.vtp/.ply per scale s
//   (0 the coarsest) and every metric above with the suffix _scale<s>; the unsuffixed ones are
//   the field's output scale's, computed once.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <unordered_map>


#include "io/grid.h"
#include "io/inside_mesh.h"
#include "io/isosurface.h"
#include "io/mesh_distance.h"
#include "io/surface_components.h"
#include "io/point_cloud.h"
#include "io/triangle_mesh.h"
#include "io/vtk_polydata.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/sdf_residual.h"

namespace nfield::solvers {
namespace {

// Exact lookup of cloud points by their coordinates' bits.
struct PointKey {
  std::uint64_t bits[3];
  bool operator==(const PointKey& o) const { return std::memcmp(bits, o.bits, sizeof bits) == 0; }
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint64_t b : k.bits) h = (h ^ b) * 1099511628211ull + (h >> 29);
    return static_cast<std::size_t>(h);
  }
};
PointKey key_of(const double* p) {
  PointKey k;
  std::memcpy(k.bits, p, sizeof k.bits);
  return k;
}

// n rows of `pool` drawn uniformly, with replacement.
Eigen::MatrixXd draw_rows(const Eigen::MatrixXd& pool, Random& rng, Eigen::Index n) {
  Eigen::MatrixXd x(n, pool.cols());
  const auto count = static_cast<double>(pool.rows());
  for (Eigen::Index p = 0; p < n; ++p)
    x.row(p) = pool.row(std::min(pool.rows() - 1, static_cast<Eigen::Index>(uniform01(rng) * count)));
  return x;
}

Domain sdf_domain(const io::ConfigNode& root) {
  if (!root.has("domain")) return Domain({-1, -1, -1}, {1, 1, 1});
  const io::ConfigNode node = root.child("domain");
  Domain domain = Domain::from_config(node);
  if (domain.has_time()) throw node.error("time", "a signed distance field has no time axis");
  if (domain.space_dim() != 3) throw node.error("lower", "a signed distance field needs a 3D domain");
  return domain;
}


class Sdf final : public Problem {
 public:
  explicit Sdf(const ProblemContext& context) : domain_(sdf_domain(context.root)) {
    const io::ConfigNode equation = context.root.child("equation");
    const std::filesystem::path path = context.config_dir / equation.get<std::string>("points");
    io::OrientedPoints cloud;
    try {
      cloud = io::read_oriented_points(path);
    } catch (const std::exception& e) {
      throw equation.error("points", e.what());
    }
    // Drop points without a normal.
    std::vector<Eigen::Index> keep;
    for (Eigen::Index i = 0; i < cloud.points.rows(); ++i)
      if (cloud.normals.row(i).squaredNorm() > 0.5 && cloud.points.row(i).allFinite()) keep.push_back(i);
    equation.require("points", !keep.empty(), "the point cloud has no points with normals");
    if (keep.size() < static_cast<size_t>(cloud.points.rows()))
      std::printf("sdf: dropped %ld of %ld points without a normal\n",
                  static_cast<long>(cloud.points.rows() - static_cast<Eigen::Index>(keep.size())),
                  static_cast<long>(cloud.points.rows()));
    points_.resize(static_cast<Eigen::Index>(keep.size()), 3);
    normals_.resize(points_.rows(), 3);
    for (size_t k = 0; k < keep.size(); ++k) {
      points_.row(static_cast<Eigen::Index>(k)) = cloud.points.row(keep[k]);
      normals_.row(static_cast<Eigen::Index>(k)) = cloud.normals.row(keep[k]);
    }

    normalize_ = equation.get_or("normalize", true);
    margin_ = equation.get_or("margin", 0.1);
    equation.require("margin", margin_ >= 0 && margin_ < 1, "expected a margin in [0, 1)");
    const Eigen::Vector3d lower(domain_.lower().data()), upper(domain_.upper().data());
    if (normalize_) {
      const Eigen::Vector3d lo = points_.colwise().minCoeff(), hi = points_.colwise().maxCoeff();
      center_ = 0.5 * (lo + hi);
      domain_center_ = 0.5 * (lower + upper);
      const double half = 0.5 * (hi - lo).maxCoeff();
      const double room = 0.5 * (upper - lower).minCoeff();
      scale_ = half > 0 ? (1 - margin_) * room / half : 1.0;
      points_ = ((points_.rowwise() - center_.transpose()) * scale_).rowwise() + domain_center_.transpose();
    } else {
      const bool inside = ((points_.rowwise() - lower.transpose()).array() >= 0).all() &&
                          ((points_.rowwise() - upper.transpose()).array() <= 0).all();
      equation.require("normalize", inside,
                       "the points leave the domain: set normalize: true or widen the domain");
    }
    for (Eigen::Index i = 0; i < points_.rows(); ++i) index_.emplace(key_of(points_.row(i).eval().data()), i);

    weights_.sdf = equation.get_or("sdf_weight", weights_.sdf);
    weights_.normal = equation.get_or("normal_weight", weights_.normal);
    weights_.eikonal = equation.get_or("eikonal_weight", weights_.eikonal);
    weights_.off_surface = equation.get_or("off_surface_weight", weights_.off_surface);
    weights_.alpha = equation.get_or("off_surface_alpha", weights_.alpha);
    weights_.absolute = equation.get_choice("loss", {"siren", "squares"}, "siren") == "siren";
    for (const char* key : {"sdf_weight", "normal_weight", "eikonal_weight", "off_surface_weight",
                            "off_surface_alpha"})
      if (equation.has(key)) {
        const double w = equation.get<double>(key);
        equation.require(key, w >= 0 && std::isfinite(w), "expected a number >= 0");
      }
    if (equation.has("reference_mesh")) {
      try {
        reference_ = std::make_shared<io::TriangleMesh>(
            io::read_triangle_mesh(context.config_dir / equation.get<std::string>("reference_mesh")));
      } catch (const std::exception& e) {
        throw equation.error("reference_mesh", e.what());
      }
      equation.require("reference_mesh", reference_->triangles.rows() > 0, "expected a mesh with triangles");
    }
    box_weight_ = equation.has("box_weight") ? equation.get_nonnegative<double>("box_weight") : 0.0;
    equation.reject_unknown_keys();
    if (box_weight_ > 0) {
      equation.require("box_weight", !normalize_ || margin_ > 0,
                       "the box term needs the cloud strictly inside the domain: margin > 0");
      make_box_pool();
    }
  }

  const Domain& domain() const override { return domain_; }
  // The interior term (eikonal and off-surface parts) is written on the output grid.
  int residual_term() const override { return 1; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm surface;
    surface.name = "surface";
    surface.batch_key = "surface";
    surface.spec = autodiff::StreamSpec::gradient(3);
    surface.sample = [this](Random& rng, Eigen::Index n) { return draw_rows(points_, rng, n); };
    surface.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
      return make_sdf_residual(normals_at(x), true, weights_);
    };
    LossTerm interior;
    interior.name = "interior";
    interior.batch_key = "interior";
    interior.spec = autodiff::StreamSpec::gradient(3);
    interior.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    interior.residual = [this](const Eigen::MatrixXd&) -> std::unique_ptr<Residual> {
      return make_sdf_residual(Eigen::MatrixXd(), false, weights_);
    };
    if (box_weight_ == 0) return {surface, interior};
    LossTerm box;
    box.name = "box";
    box.batch_key = "box";
    box.spec = autodiff::StreamSpec::values(3);
    box.sample = [this](Random& rng, Eigen::Index n) { return draw_rows(box_points_, rng, n); };
    box.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
      const double root = std::sqrt(box_weight_);
      Eigen::MatrixXd target(x.rows(), 1);
      for (Eigen::Index p = 0; p < x.rows(); ++p) {
        const Eigen::RowVector3d row = x.row(p);
        const auto it = box_index_.find(key_of(row.data()));
        // Not a pool point (a checkpoint of another pool): the distance computed now.
        target(p, 0) = root * (it != box_index_.end() ? box_distances_(it->second)
                                                      : io::point_cloud_distance(row, points_)(0));
      }
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{
              {0, autodiff::StreamLayout::value(), 0, Eigen::VectorXd::Constant(1, root)}},
          target);
    };
    return {surface, interior, box};
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    const io::Grid grid = io::make_grid(domain_.lower(), domain_.upper(), context.grid);
    const Eigen::MatrixXd x = grid.points(3);
    const Surface output = surface_of(grid, on_grid(x, context.values));
    write_surface(context.dir, output, "", metrics);
    // A multiscale field (field.type: bacon): each scale's zero level set too (the output
    // scale's is the one above).
    if (context.scales > 1 && context.scale_values)
      for (int scale = 0; scale < context.scales; ++scale) {
        const std::string suffix = "_scale" + std::to_string(scale);
        if (scale == context.output_scale) {
          write_surface(context.dir, output, suffix, metrics);
          continue;
        }
        const auto values = [&](const Eigen::MatrixXd& points) { return context.scale_values(points, scale); };
        write_surface(context.dir, surface_of(grid, on_grid(x, values)), suffix, metrics);
      }
  }

 private:
  // The field's first output at the grid points x, in chunks that keep the passes' memory small.
  template <class Values>
  static Eigen::VectorXd on_grid(const Eigen::MatrixXd& x, const Values& values) {
    const Eigen::Index n = x.rows();
    Eigen::VectorXd u(n);
    constexpr Eigen::Index kChunk = 1 << 16;
    for (Eigen::Index start = 0; start < n; start += kChunk) {
      const Eigen::Index count = std::min(kChunk, n - start);
      u.segment(start, count) = values(x.middleRows(start, count)).col(0);
    }
    return u;
  }

  // The zero level set of u on the grid, in the cloud's coordinates, and its metrics (below).
  struct Surface {
    io::TriangleMesh mesh;
    std::vector<std::pair<std::string, double>> metrics;
  };
  Surface surface_of(const io::Grid& grid, const Eigen::VectorXd& u) const {
    Surface out;
    out.mesh = io::extract_isosurface(grid, u, 0.0, true);
    out.mesh.vertices = to_original(out.mesh.vertices);
    const io::TriangleMesh& surface = out.mesh;
    const io::SurfaceComponents pieces = io::surface_components(surface);
    std::vector<std::pair<std::string, double>>& metrics = out.metrics;
    metrics = {{"surface_vertices", static_cast<double>(surface.vertices.rows())},
               {"surface_triangles", static_cast<double>(surface.triangles.rows())}};
    metrics.emplace_back("surface_components", pieces.count);
    metrics.emplace_back("surface_largest_component_area_share", pieces.largest_area_share);
    if (surface.triangles.rows() > 0) {
      chamfer_metrics(surface, metrics);
      if (reference_) sign_metrics(grid, u, metrics);
    } else {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (const char* key : {"chamfer_surface_to_mesh", "chamfer_mesh_to_surface", "chamfer_mean", "chamfer_max",
                              "chamfer_mean_per_diagonal", "chamfer_max_per_diagonal", "normal_consistency"})
        metrics.emplace_back(key, nan);
      if (reference_) {
        metrics.emplace_back("sign_accuracy", nan);
        metrics.emplace_back("sign_accuracy_band", nan);
      }
    }
    return out;
  }

  // surface{suffix}.vtp and .ply, and the surface's metrics with keys ending in `suffix`.
  static void write_surface(const std::filesystem::path& dir, const Surface& surface, const std::string& suffix,
                            std::vector<std::pair<std::string, double>>& all) {
    io::write_vtp_mesh(dir / ("surface" + suffix + ".vtp"), surface.mesh);
    io::write_ply(dir / ("surface" + suffix + ".ply"), surface.mesh);
    for (const auto& [key, value] : surface.metrics) all.emplace_back(key + suffix, value);
  }

  // Chamfer distances and normal consistency of the extracted surface against the reference
  // mesh, or else against the input cloud (its points and normals).
  void chamfer_metrics(const io::TriangleMesh& surface,
                       std::vector<std::pair<std::string, double>>& metrics) const {
    const auto started = std::chrono::steady_clock::now();
    io::SurfaceComparison c;
    Eigen::MatrixXd target_points;
    if (reference_) {
      c = io::compare_surfaces(surface, *reference_);
      target_points = reference_->vertices;
    } else {
      target_points = to_original(points_);
      c.a_to_b = io::point_cloud_distance(surface.vertices, target_points);
      const io::ClosestTriangles back = io::closest_triangles(target_points, surface);
      c.b_to_a = back.distance;
      double sum = 0;
      const Eigen::MatrixXd faces = io::triangle_normals(surface);
      for (Eigen::Index p = 0; p < target_points.rows(); ++p)
        sum += std::abs(normals_.row(p).dot(faces.row(back.triangle(p))));
      c.normal_consistency = sum / static_cast<double>(target_points.rows());
    }
    const double diagonal = (target_points.colwise().maxCoeff() - target_points.colwise().minCoeff()).norm();
    metrics.emplace_back("chamfer_surface_to_mesh", c.a_to_b.mean());
    metrics.emplace_back("chamfer_mesh_to_surface", c.b_to_a.mean());
    metrics.emplace_back("chamfer_mean", c.chamfer_mean());
    metrics.emplace_back("chamfer_max", c.chamfer_max());
    metrics.emplace_back("chamfer_mean_per_diagonal", c.chamfer_mean() / diagonal);
    metrics.emplace_back("chamfer_max_per_diagonal", c.chamfer_max() / diagonal);
    metrics.emplace_back("normal_consistency", c.normal_consistency);
    metrics.emplace_back("chamfer_seconds",
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  }

  // How often the sign of u on the grid agrees with inside/outside the reference mesh, over
  // the grid and within 5 % of the mesh's diagonal from it.
  void sign_metrics(const io::Grid& grid, const Eigen::VectorXd& u,
                    std::vector<std::pair<std::string, double>>& metrics) const {
    const Eigen::Index n = u.size();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double band = 0.05 * (reference_->vertices.colwise().maxCoeff() -
                                reference_->vertices.colwise().minCoeff()).norm();
    const auto sign_started = std::chrono::steady_clock::now();
    // The grid in the mesh's coordinates (to_original is a shift and a uniform scale).
    io::Grid original = grid;
    const Eigen::RowVector3d origin = to_original(Eigen::RowVector3d(grid.origin[0], grid.origin[1], grid.origin[2]));
    for (int a = 0; a < 3; ++a) {
      original.origin[a] = origin(a);
      original.spacing[a] = grid.spacing[a] / (normalize_ ? scale_ : 1.0);
    }
    const auto inside = io::inside_closed_mesh(original, *reference_);
    const auto near_surface = io::grid_near_mesh(original, *reference_, band);
    Eigen::Index agree = 0, near = 0, near_agree = 0;
    for (Eigen::Index p = 0; p < n; ++p) {
      const bool same = (u(p) < 0) == inside(p);
      agree += same;
      if (near_surface(p)) {
        ++near;
        near_agree += same;
      }
    }
    metrics.emplace_back("sign_accuracy", static_cast<double>(agree) / static_cast<double>(n));
    metrics.emplace_back("sign_accuracy_band",
                         near > 0 ? static_cast<double>(near_agree) / static_cast<double>(near) : nan);
    metrics.emplace_back("sign_seconds",
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - sign_started).count());
  }

  // 6 faces × 96² points, one per cell of a 96 × 96 grid on each face (jittered, seed fixed).
  void make_box_pool() {
    constexpr int kSide = 96;
    const Eigen::Vector3d lower(domain_.lower().data()), upper(domain_.upper().data());
    box_points_.resize(6 * kSide * kSide, 3);
    Random rng(20261124);
    Eigen::Index row = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side)
        for (int i = 0; i < kSide; ++i)
          for (int j = 0; j < kSide; ++j) {
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            Eigen::RowVector3d p;
            p(axis) = side == 0 ? lower(axis) : upper(axis);
            p(a) = lower(a) + (upper(a) - lower(a)) * (i + uniform01(rng)) / kSide;
            p(b) = lower(b) + (upper(b) - lower(b)) * (j + uniform01(rng)) / kSide;
            box_points_.row(row++) = p;
          }
    box_distances_ = io::point_cloud_distance(box_points_, points_);
    for (Eigen::Index p = 0; p < box_points_.rows(); ++p) box_index_.emplace(key_of(box_points_.row(p).eval().data()), p);
  }

  // Domain coordinates → the cloud's own.
  Eigen::MatrixXd to_original(const Eigen::MatrixXd& x) const {
    if (!normalize_) return x;
    return ((x.rowwise() - domain_center_.transpose()) / scale_).rowwise() + center_.transpose();
  }

  // The normals of cloud points x (by exact coordinates, else the nearest cloud point).
  Eigen::MatrixXd normals_at(const Eigen::MatrixXd& x) const {
    Eigen::MatrixXd n(x.rows(), 3);
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::RowVector3d row = x.row(p);
      const auto it = index_.find(key_of(row.data()));
      Eigen::Index best = 0;
      if (it != index_.end()) {
        best = it->second;
      } else {
        (points_.rowwise() - row).rowwise().squaredNorm().minCoeff(&best);
      }
      n.row(p) = normals_.row(best);
    }
    return n;
  }

  Domain domain_;
  Eigen::MatrixXd points_, normals_;  // in domain coordinates
  std::unordered_map<PointKey, Eigen::Index, PointKeyHash> index_;
  bool normalize_ = true;
  double margin_ = 0.1, scale_ = 1;
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero(), domain_center_ = Eigen::Vector3d::Zero();
  SdfWeights weights_;
  double box_weight_ = 0;
  Eigen::MatrixXd box_points_;  // the face pool, domain coordinates
  Eigen::VectorXd box_distances_;
  std::unordered_map<PointKey, Eigen::Index, PointKeyHash> box_index_;
  std::shared_ptr<io::TriangleMesh> reference_;
};

}  // namespace

std::unique_ptr<Problem> make_sdf(const ProblemContext& context) { return std::make_unique<Sdf>(context); }

}  // namespace nfield::solvers
