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
//     distance_weight: 0       # > 0: the "distance" term below (training.batch.distance)
//     distance_sigma: 0.02     # its near-surface points' spread, in domain units
//
//     loss: siren              # siren | squares (below)
//
// A family of shapes (issue 28: DeepSDF's auto-decoder, field.latent; solvers/run/latent_run.h)
// replaces `points` and `reference_mesh` with
//
//     family:
//       meshes: ../data/meshes/family    # a folder (its *.ply, *.obj, *.vtp, *.off in name
//                                        #   order) or a list of files; at least two
//       held_out: [elephant.ply]         # the last n, or a list of file names
//       surface_points: 50000            # points drawn on each mesh (≥ 1000)
//
// Each mesh is both an instance's oriented points (surface_points drawn on its triangles in
// proportion to their areas, each with its face's normal; seeded per mesh) and its reference
// mesh; each is normalized into the domain on its own, so every shape fills it
// alike. The settings above are shared. The family problem itself stands for its first
// training shape.
//
// Loss terms (each a mean over its points; w_* the weights above, ĝ = ∇u/|∇u|):
//   "surface"   batch `surface`: points drawn uniformly (with replacement) from the cloud,
//               ‖r‖² = w_sdf |u| + w_normal (1 − cos(∇u, n)) + w_eikonal ||∇u| − 1|,
//               r = [√w_sdf ρ(u),  √(w_normal/2) (ĝ − n),  √w_eikonal ρ(|∇u| − 1)];
//   "interior"  batch `interior`: uniform points in the domain,
//               ‖r‖² = w_eikonal ||∇u| − 1| + w_off exp(−α|u|),
//               r = [√w_eikonal ρ(|∇u| − 1),  √w_off exp(−α|u|/2)],
//   "box"       (only with box_weight > 0) batch `box`: points on the domain's faces,
//               r = √w_box (u − d(x)), d the distance to the nearest cloud point;
//   "distance"  (only with distance_weight > 0) batch `distance`: r = √w_distance (u − s(x)),
//               s = ± the distance to the nearest cloud point p, + where (x − p)·n_p ≥ 0
//               (outside: the normals point out), on a pool of 2^17 points made once, half
//               uniform in the domain and half cloud points moved by N(0, σ²) per coordinate
//               (σ = distance_sigma). BACON's SDF fits (Lindell et al. 2022)
//               supervises values this way, near the surface and across the box.
// with ρ(x) = sign(x) √|x|, so that these are exactly the per-point losses of SIREN's
// reference code (its means of |u| weighted 3e3, of 1 − cos 1e2, of ||∇u| − 1| 5e1, of
// exp(−α|u|) 1e2 with α = 100; (ĝ − n)²/2 = 1 − cos). `loss: squares` takes ρ(x) = x
// instead (u² and (|∇u| − 1)², least squares proper); on a sphere it places the surface
// about 4 times less accurately with these weights, as small errors then cost little.
// The term weights themselves are 1 (the w_* are inside the residuals). ∂|g|/∂g and ∂ĝ/∂g
// are taken as 0 where |g| = 0, ∂|u|/∂u as 0 at u = 0, and ρ'(0) as 0.
//
// Why the distance term: a field that is a sum of products of sines (BACON, fields/bacon.h)
// fitted by SIREN's loss alone fills the box with extra zero crossings, as only |∇u| = 1 and
// |u| away from 0 constrain it there; values set across the box remove them. The sign by the
// nearest point's normal is wrong only where the nearest point is on the far side of a part
// thinner than the distance to it, so the near-surface points are where it is trusted most.
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
#include <functional>
#include <limits>
#include <mutex>
#include <numbers>
#include <string>
#include <unordered_map>

#include <Eigen/Geometry>


#include "io/grid.h"
#include "io/inside_mesh.h"
#include "io/isosurface.h"
#include "io/mesh_distance.h"
#include "io/surface_components.h"
#include "io/text.h"
#include "io/point_cloud.h"
#include "io/triangle_mesh.h"
#include "io/vtk_polydata.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/problems/image_family.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/sdf_residual.h"
#include "solvers/problems/shape_placement.h"

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


// The loss settings every shape of a run shares (a family's instances too).
struct SdfSettings {
  bool normalize = true;
  double margin = 0.1;
  SdfWeights weights;
  double box_weight = 0;
  double distance_weight = 0;
  double distance_sigma = 0.02;
};

// One shape: its oriented points in domain coordinates, how they map back to the cloud's own,
// its reference mesh, and the face pool of the box term.
struct SdfShape {
  Eigen::MatrixXd points, normals;  // in domain coordinates
  std::unordered_map<PointKey, Eigen::Index, PointKeyHash> index;
  ShapePlacement placement;  // the cloud's own coordinates → the domain's (normalize)
  std::shared_ptr<io::TriangleMesh> reference;

  // Points with target values (the box term's face pool, the distance term's pool): points
  // in domain coordinates, their target distances, and the lookup by coordinates; made at the
  // first draw (loading a config, as `nfield validate` and the config tests do, never needs it).
  struct ValuePool {
    Eigen::MatrixXd points;
    Eigen::VectorXd distances;
    std::unordered_map<PointKey, Eigen::Index, PointKeyHash> index;
  };
  const ValuePool& box_pool(const Domain& domain) const;
  const ValuePool& distance_pool(const Domain& domain, double sigma) const;
  // ± the distance from x to the nearest cloud point p, + where (x − p)·n_p ≥ 0.
  Eigen::VectorXd signed_cloud_distance(const Eigen::MatrixXd& x) const;

 private:
  mutable std::once_flag box_once_, distance_once_;
  mutable ValuePool box_, distance_;
};

// Reads `key` of `node` (a cloud or a mesh file, relative to config_dir) into a shape; errors
// are located at that key.
io::OrientedPoints read_cloud(const io::ConfigNode& node, const std::string& key, const std::filesystem::path& path) {
  try {
    return io::read_oriented_points(path);
  } catch (const std::exception& e) {
    throw node.error(key, e.what());
  }
}

// n points on the mesh's triangles with their face normals: a triangle with probability ∝ its
// area (binary search in the cumulative areas), a point in it by (1 − √u₁) a + √u₁ (1 − u₂) b
// + √u₁ u₂ c. A mesh's vertices alone can be too few to pin its surface down (sphere.ply has
// 162), and they crowd where the mesh is fine rather than where the surface is.
io::OrientedPoints surface_samples(const io::TriangleMesh& mesh, Eigen::Index n, std::uint64_t seed) {
  const Eigen::Index m = mesh.triangles.rows();
  Eigen::MatrixXd normals(m, 3);
  std::vector<double> cumulative(static_cast<std::size_t>(m));
  double total = 0;
  for (Eigen::Index t = 0; t < m; ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)), b = mesh.vertices.row(mesh.triangles(t, 1)),
                          c = mesh.vertices.row(mesh.triangles(t, 2));
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double twice_area = cross.norm();
    normals.row(t) = twice_area > 0 ? Eigen::RowVector3d(cross.transpose() / twice_area) : Eigen::RowVector3d::Zero();
    total += 0.5 * twice_area;
    cumulative[static_cast<std::size_t>(t)] = total;
  }
  Random rng(seed);
  io::OrientedPoints out;
  out.points.resize(n, 3);
  out.normals.resize(n, 3);
  for (Eigen::Index p = 0; p < n; ++p) {
    const double pick = uniform01(rng) * total;
    const auto t = static_cast<Eigen::Index>(
        std::min<std::ptrdiff_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(), m - 1));
    const double r = std::sqrt(uniform01(rng)), v = uniform01(rng);
    out.points.row(p) = (1 - r) * mesh.vertices.row(mesh.triangles(t, 0)) +
                        r * (1 - v) * mesh.vertices.row(mesh.triangles(t, 1)) + r * v * mesh.vertices.row(mesh.triangles(t, 2));
    out.normals.row(p) = normals.row(t);
  }
  return out;
}

std::shared_ptr<SdfShape> make_shape(const io::ConfigNode& node, const std::string& key, const std::string& name,
                                     io::OrientedPoints cloud, const SdfSettings& settings, const Domain& domain) {
  const std::filesystem::path path = name;
  auto shape = std::make_shared<SdfShape>();
  // Drop points without a normal.
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < cloud.points.rows(); ++i)
    if (cloud.normals.row(i).squaredNorm() > 0.5 && cloud.points.row(i).allFinite()) keep.push_back(i);
  node.require(key, !keep.empty(), path.filename().string() + ": the point cloud has no points with normals");
  if (keep.size() < static_cast<size_t>(cloud.points.rows()))
    std::printf("sdf: %s: dropped %ld of %ld points without a normal\n", path.filename().string().c_str(),
                static_cast<long>(cloud.points.rows() - static_cast<Eigen::Index>(keep.size())),
                static_cast<long>(cloud.points.rows()));
  shape->points.resize(static_cast<Eigen::Index>(keep.size()), 3);
  shape->normals.resize(shape->points.rows(), 3);
  for (size_t k = 0; k < keep.size(); ++k) {
    shape->points.row(static_cast<Eigen::Index>(k)) = cloud.points.row(keep[k]);
    shape->normals.row(static_cast<Eigen::Index>(k)) = cloud.normals.row(keep[k]);
  }
  const Eigen::Vector3d lower(domain.lower().data()), upper(domain.upper().data());
  Eigen::MatrixXd& points = shape->points;
  if (settings.normalize) {
    shape->placement = ShapePlacement::fit(points, lower, upper, settings.margin);
    points = shape->placement.to_domain(points);
  } else {
    node.require(key, ShapePlacement::within(points, lower, upper),
                 path.filename().string() + ": the points leave the domain: set normalize: true or widen the domain");
  }
  for (Eigen::Index i = 0; i < points.rows(); ++i) shape->index.emplace(key_of(points.row(i).eval().data()), i);
  return shape;
}

std::shared_ptr<io::TriangleMesh> read_reference(const io::ConfigNode& node, const std::string& key,
                                                 const std::filesystem::path& path) {
  std::shared_ptr<io::TriangleMesh> mesh;
  try {
    mesh = std::make_shared<io::TriangleMesh>(io::read_triangle_mesh(path));
  } catch (const std::exception& e) {
    throw node.error(key, e.what());
  }
  node.require(key, mesh->triangles.rows() > 0, path.filename().string() + ": expected a mesh with triangles");
  return mesh;
}

// 6 faces × 96² points, one per cell of a 96 × 96 grid on each face (jittered, seed fixed),
// and their distances to the shape's points.
const SdfShape::ValuePool& SdfShape::box_pool(const Domain& domain) const {
  std::call_once(box_once_, [&] {
    constexpr int kSide = 96;
    const Eigen::Vector3d lower(domain.lower().data()), upper(domain.upper().data());
    box_.points.resize(6 * kSide * kSide, 3);
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
            box_.points.row(row++) = p;
          }
    box_.distances = io::point_cloud_distance(box_.points, points);
    for (Eigen::Index p = 0; p < box_.points.rows(); ++p) box_.index.emplace(key_of(box_.points.row(p).eval().data()), p);
  });
  return box_;
}

Eigen::VectorXd SdfShape::signed_cloud_distance(const Eigen::MatrixXd& x) const {
  const auto nearest = io::nearest_cloud_points(x, points);
  Eigen::VectorXd d(x.rows());
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    const Eigen::RowVector3d offset = x.row(p) - points.row(nearest(p));
    d(p) = offset.dot(normals.row(nearest(p))) >= 0 ? offset.norm() : -offset.norm();
  }
  return d;
}

// 2^17 points (seed fixed): half uniform in the domain, half cloud points moved by N(0, σ²) in
// each coordinate (Box–Muller on the engine's own uniforms) and clamped into the domain; and
// their signed distances to the cloud.
const SdfShape::ValuePool& SdfShape::distance_pool(const Domain& domain, double sigma) const {
  std::call_once(distance_once_, [&] {
    constexpr Eigen::Index kCount = Eigen::Index{1} << 17;
    const Eigen::Vector3d lower(domain.lower().data()), upper(domain.upper().data());
    distance_.points.resize(kCount, 3);
    Random rng(20261127);
    const auto gauss = [&rng] {
      return std::sqrt(-2 * std::log1p(-uniform01(rng))) * std::cos(2 * std::numbers::pi * uniform01(rng));
    };
    for (Eigen::Index p = 0; p < kCount; ++p) {
      if (p % 2 == 0) {
        for (int a = 0; a < 3; ++a) distance_.points(p, a) = lower(a) + (upper(a) - lower(a)) * uniform01(rng);
        continue;
      }
      const auto k = std::min(points.rows() - 1, static_cast<Eigen::Index>(uniform01(rng) * static_cast<double>(points.rows())));
      for (int a = 0; a < 3; ++a) distance_.points(p, a) = std::clamp(points(k, a) + sigma * gauss(), lower(a), upper(a));
    }
    distance_.distances = signed_cloud_distance(distance_.points);
    for (Eigen::Index p = 0; p < kCount; ++p) distance_.index.emplace(key_of(distance_.points.row(p).eval().data()), p);
  });
  return distance_;
}

// The meshes of equation.family (a folder's *.ply, *.obj, *.vtp and *.off in name order, or a
// list of files), and which are held out (the last n, or a list of file names).
struct MeshFamily {
  std::vector<std::filesystem::path> paths;
  std::vector<std::string> names;
  std::size_t training = 0;
};

MeshFamily read_mesh_family(const io::ConfigNode& family, const std::filesystem::path& config_dir) {
  namespace fs = std::filesystem;
  MeshFamily out;
  if (family.has_list("meshes")) {
    for (const std::string& file : family.get<std::vector<std::string>>("meshes")) out.paths.push_back(config_dir / file);
  } else {
    const fs::path folder = config_dir / family.get<std::string>("meshes");
    family.require("meshes", fs::is_directory(folder), folder.string() + ": no such folder (or a list of mesh files)");
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string ext = io::to_lower(entry.path().extension().string());
      if (entry.is_regular_file() && (ext == ".ply" || ext == ".obj" || ext == ".vtp" || ext == ".off"))
        out.paths.push_back(entry.path());
    }
    std::sort(out.paths.begin(), out.paths.end());
  }
  family.require("meshes", out.paths.size() >= 2, "expected at least two meshes in a family");
  (void)family.has("surface_points");  // read by the caller
  for (const auto& p : out.paths) out.names.push_back(p.filename().string());
  std::size_t training = 0;
  const std::vector<std::size_t> order = held_out_last(family, out.paths, training, "meshes");
  MeshFamily ordered;
  for (std::size_t k : order) {
    ordered.paths.push_back(out.paths[k]);
    ordered.names.push_back(out.names[k]);
  }
  ordered.training = training;
  family.reject_unknown_keys();
  return ordered;
}

class Sdf final : public Problem, public HasInstances {
 public:
  explicit Sdf(const ProblemContext& context) : domain_(Domain::box_3d_from_config(context.root, "a signed distance field")) {
    const io::ConfigNode equation = context.root.child("equation");
    settings_.normalize = equation.get_or("normalize", true);
    settings_.margin = equation.get_or("margin", 0.1);
    equation.require("margin", settings_.margin >= 0 && settings_.margin < 1, "expected a margin in [0, 1)");
    SdfWeights& weights = settings_.weights;
    weights.sdf = equation.get_or("sdf_weight", weights.sdf);
    weights.normal = equation.get_or("normal_weight", weights.normal);
    weights.eikonal = equation.get_or("eikonal_weight", weights.eikonal);
    weights.off_surface = equation.get_or("off_surface_weight", weights.off_surface);
    weights.alpha = equation.get_or("off_surface_alpha", weights.alpha);
    weights.absolute = equation.get_choice("loss", {"siren", "squares"}, "siren") == "siren";
    for (const char* key : {"sdf_weight", "normal_weight", "eikonal_weight", "off_surface_weight",
                            "off_surface_alpha"})
      if (equation.has(key)) {
        const double w = equation.get<double>(key);
        equation.require(key, w >= 0 && std::isfinite(w), "expected a number >= 0");
      }
    settings_.box_weight = equation.has("box_weight") ? equation.get_nonnegative<double>("box_weight") : 0.0;
    if (settings_.box_weight > 0)
      equation.require("box_weight", !settings_.normalize || settings_.margin > 0,
                       "the box term needs the cloud strictly inside the domain: margin > 0");
    if (equation.has("distance_weight")) settings_.distance_weight = equation.get_nonnegative<double>("distance_weight");
    if (equation.has("distance_sigma")) {
      settings_.distance_sigma = equation.get_positive<double>("distance_sigma");
      equation.require("distance_sigma", settings_.distance_weight > 0,
                       "the distance term's spread needs the term: distance_weight > 0");
    }
    if (equation.has("family")) {
      for (const char* key : {"points", "reference_mesh"})
        equation.require(key, !equation.has(key), "a family names its meshes itself (equation.family.meshes): drop " +
                                                      std::string(key));
      const io::ConfigNode family = equation.child("family");
      const MeshFamily meshes = read_mesh_family(family, context.config_dir);
      const Eigen::Index samples = family.has("surface_points") ? family.get_in_range("surface_points", 1000, 1 << 24) : 50000;
      for (std::size_t k = 0; k < meshes.paths.size(); ++k) {
        auto reference = read_reference(family, "meshes", meshes.paths[k]);
        auto shape = make_shape(family, "meshes", meshes.names[k], surface_samples(*reference, samples, 20261127 + k),
                                settings_, domain_);
        shape->reference = std::move(reference);
        family_.push_back(std::move(shape));
      }
      family_names_ = meshes.names;
      training_count_ = meshes.training;
      shape_ = family_.front();
    } else {
      const std::filesystem::path points = context.config_dir / equation.get<std::string>("points");
      auto shape = make_shape(equation, "points", points.filename().string(), read_cloud(equation, "points", points),
                              settings_, domain_);
      if (equation.has("reference_mesh"))
        shape->reference =
            read_reference(equation, "reference_mesh", context.config_dir / equation.get<std::string>("reference_mesh"));
      shape_ = std::move(shape);
    }
    equation.reject_unknown_keys();
  }

  // One shape of a family: the settings, domain and shape of an instance.
  Sdf(const Domain& domain, const SdfSettings& settings, std::shared_ptr<const SdfShape> shape)
      : domain_(domain), settings_(settings), shape_(std::move(shape)) {}

  std::vector<ProblemInstance> instances(bool held_out) const override {
    std::vector<ProblemInstance> out;
    const std::size_t first = held_out ? training_count_ : 0, end = held_out ? family_.size() : training_count_;
    for (std::size_t k = first; k < end; ++k)
      out.push_back({family_names_[k], std::make_unique<Sdf>(domain_, settings_, family_[k])});
    return out;
  }

  const Domain& domain() const override { return domain_; }
  // The interior term (eikonal and off-surface parts) is written on the output grid.
  int residual_term() const override { return 1; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm surface;
    surface.name = "surface";
    surface.batch_key = "surface";
    surface.spec = autodiff::StreamSpec::gradient(3);
    surface.sample = [this](Random& rng, Eigen::Index n) { return draw_rows(shape_->points, rng, n); };
    surface.residual = [this](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
      return make_sdf_residual(normals_at(x), true, settings_.weights);
    };
    LossTerm interior;
    interior.name = "interior";
    interior.batch_key = "interior";
    interior.spec = autodiff::StreamSpec::gradient(3);
    interior.sample = [this](Random& rng, Eigen::Index n) { return domain_.sample_interior(rng, n); };
    interior.residual = [this](const Eigen::MatrixXd&) -> std::unique_ptr<Residual> {
      return make_sdf_residual(Eigen::MatrixXd(), false, settings_.weights);
    };
    std::vector<LossTerm> terms{surface, interior};
    if (settings_.box_weight > 0)
      terms.push_back(value_term("box", settings_.box_weight, [this]() -> const SdfShape::ValuePool& {
        return shape_->box_pool(domain_);
      }, [this](const Eigen::MatrixXd& x) { return io::point_cloud_distance(x, shape_->points); }));
    if (settings_.distance_weight > 0)
      terms.push_back(value_term("distance", settings_.distance_weight, [this]() -> const SdfShape::ValuePool& {
        return shape_->distance_pool(domain_, settings_.distance_sigma);
      }, [this](const Eigen::MatrixXd& x) { return shape_->signed_cloud_distance(x); }));
    return terms;
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    const io::Grid grid = io::make_grid(domain_.lower(), domain_.upper(), context.grid);
    const Eigen::MatrixXd x = grid.points(3);
    // Each surface's metrics take seconds to a minute (Chamfer both ways, signs on the grid):
    // a line before and after each, so that a multiscale field's outputs do not look hung.
    const auto timed_surface = [&](const std::string& label, const auto& values) {
      const auto started = std::chrono::steady_clock::now();
      std::printf("sdf: %s: zero level set on the output grid and its metrics\n", label.c_str());
      std::fflush(stdout);
      Surface surface = surface_of(grid, on_grid(x, values));
      std::printf("sdf: %s: %ld triangles (%.1f s)\n", label.c_str(), static_cast<long>(surface.mesh.triangles.rows()),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
      std::fflush(stdout);
      return surface;
    };
    const Surface output = timed_surface("surface", context.values);
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
        write_surface(context.dir, timed_surface("surface" + suffix, values), suffix, metrics);
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
      if (shape_->reference) sign_metrics(grid, u, metrics);
    } else {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (const char* key : {"chamfer_surface_to_mesh", "chamfer_mesh_to_surface", "chamfer_mean", "chamfer_max",
                              "chamfer_mean_per_diagonal", "chamfer_max_per_diagonal", "normal_consistency"})
        metrics.emplace_back(key, nan);
      if (shape_->reference) {
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
    if (shape_->reference) {
      c = io::compare_surfaces(surface, *shape_->reference);
      target_points = shape_->reference->vertices;
    } else {
      target_points = to_original(shape_->points);
      c.a_to_b = io::point_cloud_distance(surface.vertices, target_points);
      const io::ClosestTriangles back = io::closest_triangles(target_points, surface);
      c.b_to_a = back.distance;
      double sum = 0;
      const Eigen::MatrixXd faces = io::triangle_normals(surface);
      for (Eigen::Index p = 0; p < target_points.rows(); ++p)
        sum += std::abs(shape_->normals.row(p).dot(faces.row(back.triangle(p))));
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
    const double band = 0.05 * (shape_->reference->vertices.colwise().maxCoeff() -
                                shape_->reference->vertices.colwise().minCoeff()).norm();
    const auto sign_started = std::chrono::steady_clock::now();
    // The grid in the mesh's coordinates (to_original is a shift and a uniform scale).
    io::Grid original = grid;
    const Eigen::RowVector3d origin = to_original(Eigen::RowVector3d(grid.origin[0], grid.origin[1], grid.origin[2]));
    for (int a = 0; a < 3; ++a) {
      original.origin[a] = origin(a);
      original.spacing[a] = grid.spacing[a] / (settings_.normalize ? shape_->placement.scale : 1.0);
    }
    const auto inside = io::inside_closed_mesh(original, *shape_->reference);
    const auto near_surface = io::grid_near_mesh(original, *shape_->reference, band);
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

  // Domain coordinates → the cloud's own.
  Eigen::MatrixXd to_original(const Eigen::MatrixXd& x) const {
    if (!settings_.normalize) return x;
    return shape_->placement.to_original(x);
  }

  // A term of residuals √w (u − d) on the points of a pool (batch key = name); a point not in
  // the pool (a checkpoint of another pool) gets its target from `compute`.
  static LossTerm value_term(const std::string& name, double weight,
                             std::function<const SdfShape::ValuePool&()> pool,
                             std::function<Eigen::VectorXd(const Eigen::MatrixXd&)> compute) {
    LossTerm term;
    term.name = name;
    term.batch_key = name;
    term.spec = autodiff::StreamSpec::values(3);
    term.sample = [pool](Random& rng, Eigen::Index n) { return draw_rows(pool().points, rng, n); };
    term.residual = [pool, compute, root = std::sqrt(weight)](const Eigen::MatrixXd& x) -> std::unique_ptr<Residual> {
      Eigen::MatrixXd target(x.rows(), 1);
      const SdfShape::ValuePool& values = pool();
      for (Eigen::Index p = 0; p < x.rows(); ++p) {
        const Eigen::RowVector3d row = x.row(p);
        const auto it = values.index.find(key_of(row.data()));
        target(p, 0) = root * (it != values.index.end() ? values.distances(it->second) : compute(row)(0));
      }
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{
              {0, autodiff::StreamLayout::value(), 0, Eigen::VectorXd::Constant(1, root)}},
          target);
    };
    return term;
  }

  // The normals of cloud points x (by exact coordinates, else the nearest cloud point).
  Eigen::MatrixXd normals_at(const Eigen::MatrixXd& x) const {
    Eigen::MatrixXd n(x.rows(), 3);
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const Eigen::RowVector3d row = x.row(p);
      const auto it = shape_->index.find(key_of(row.data()));
      Eigen::Index best = 0;
      if (it != shape_->index.end()) {
        best = it->second;
      } else {
        (shape_->points.rowwise() - row).rowwise().squaredNorm().minCoeff(&best);
      }
      n.row(p) = shape_->normals.row(best);
    }
    return n;
  }

  Domain domain_;
  SdfSettings settings_;
  std::shared_ptr<const SdfShape> shape_;  // this problem's shape (a family's first training one)
  std::vector<std::shared_ptr<const SdfShape>> family_;  // equation.family: training shapes, then held-out
  std::vector<std::string> family_names_;
  std::size_t training_count_ = 0;
};

}  // namespace

std::unique_ptr<Problem> make_sdf(const ProblemContext& context) { return std::make_unique<Sdf>(context); }

}  // namespace nfield::solvers
