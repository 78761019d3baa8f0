// SPDX-License-Identifier: MIT
//
// Occupancy fields of closed meshes (Occupancy Networks, Mescheder et al. 2019; ACORN's 3-D
// fits, Martel et al. 2021, Sec. 4.2): the field is fitted to the indicator of a shape's
// inside, from the mesh's own inside test, and its decision surface is the shape's surface.
//
//   problem: occupancy
//   domain: {lower: [-1, -1, -1], upper: [1, 1, 1]}   # optional, this is the default; 3D
//   equation:
//     mesh: ../data/meshes/bunny00.ply   # a closed triangle mesh (.ply, .obj, .stl, .vtp,
//                                        # .off), relative to the config file's folder
//     normalize: true        # move and scale the mesh into the domain (default true)
//     margin: 0.1            # normalize: the fraction of the domain's half-width left free
//     loss: bce              # bce | squares (below)
//     near_surface: 0.5      # the share of each batch drawn near the surface
//     surface_sigma: 0.01    # their spread about the surface, in domain units
//     iou_resolution: 256    # the grid of the IoU after training: n³ points over the domain
//
// Labels: y(x) = 1 inside the mesh, 0 outside, by the parity of the crossings of a ray
// (solvers/geometry/mesh_shape.h, which refuses a mesh with holes or seams, so the labels are
// well defined). Labels are computed for each step's points as drawn: no pool, so a field that
// chooses its own points (ACORN's block sampler, solvers/training/block_allocation.h, which
// replaces the draw by points uniform in its blocks) is labelled alike.
//
// Loss: one term "occupancy" (batch `interior`), points uniform in the domain and, a share
// `near_surface` of them, surface points (uniform by area) moved by N(0, σ²) per coordinate.
//   bce      u is the logit of the occupancy σ(u): the binary cross-entropy
//            −y log σ(u) − (1 − y) log(1 − σ(u)) = softplus(s u), s = 1 − 2y, as the residual
//            r = √softplus(s u) (r² is the per-point loss, so the trainer's mean of ‖r‖² is the
//            mean cross-entropy, and ACORN's block errors are per-block cross-entropies);
//            inside where u > 0.
//   squares  r = u − y (the mean squared error of the indicator); inside where u > 1/2.
// softplus is taken as max(t, 0) + log1p(e^−|t|), which never overflows, and r as a constant
// where softplus underflows to 0 (|u| > 745: sqrt's derivative at 0 is not finite).
// Why bce is the default: an MSE on {0, 1} stops pulling once a point is on the right side
// by a little, so the decision surface drifts within the band where the field is unsure;
// the cross-entropy keeps pushing σ(u) towards 0 and 1 and so sharpens that band.
//
// The progress line adds IoU and acc(uracy) on a fixed set of 2^16 points uniform in the
// domain (labelled once; an estimate of the grid's figures below), refreshed every few seconds.
//
// After training, on an n³ grid over the domain (n = iou_resolution): the field's inside
// against the mesh's (io/inside_mesh.h, parity along the grid's lines: independent of the
// training labels' ray test). metrics.json: iou (|A ∩ B|/|A ∪ B|), occupancy_accuracy (the
// share of grid points that agree), iou_seconds; the decision surface (the level 0 or 1/2 of u
// on that grid) as surface.vtp and surface.ply in the mesh's own coordinates, with
// surface_components, surface_largest_component_area_share, chamfer_mean,
// chamfer_mean_per_diagonal, chamfer_max_per_diagonal and normal_consistency against the mesh
// (io/mesh_distance.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "io/grid.h"
#include "io/inside_mesh.h"
#include "io/isosurface.h"
#include "io/mesh_distance.h"
#include "io/surface_components.h"
#include "io/triangle_mesh.h"
#include "io/vtk_polydata.h"
#include "solvers/core/jet_residual.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/core/slice_progress.h"
#include "solvers/geometry/mesh_shape.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/shape_placement.h"

namespace nfield::solvers {
namespace {

// r = √softplus((1 − 2y) u) (bce) or u − y (squares), reading the value of channel 0.
class OccupancyResidual {
 public:
  struct PointData {
    double label = 0;
  };
  static constexpr int kReads = 1;
  static constexpr int kComponents = 1;

  OccupancyResidual(Eigen::VectorXd labels, bool cross_entropy)
      : labels_(std::move(labels)), cross_entropy_(cross_entropy) {}

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return {StreamRead{layout.value(), 0}};
  }
  PointData point(Eigen::Index index) const { return {labels_(index)}; }

  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    using std::exp;
    using std::log1p;
    using std::sqrt;
    if (!cross_entropy_) {
      r[0] = z[0] - T(data.label);
      return;
    }
    const T t = (1.0 - 2.0 * data.label) * z[0];
    const double value = scalar_of(t);
    const T negative_abs = value > 0 ? T(-t) : t;
    const T softplus = (value > 0 ? t : T(0.0)) + log1p(exp(negative_abs));
    r[0] = scalar_of(softplus) > 0 ? sqrt(softplus) : T(0.0);
  }

 private:
  Eigen::VectorXd labels_;
  bool cross_entropy_;
};

class Occupancy final : public Problem, public ReportsProgress {
 public:
  explicit Occupancy(const ProblemContext& context) : domain_(Domain::box_3d_from_config(context.root, "an occupancy field")) {
    const io::ConfigNode equation = context.root.child("equation");
    const bool normalize = equation.get_or("normalize", true);
    const double margin = equation.get_or("margin", 0.1);
    equation.require("margin", margin >= 0 && margin < 1, "expected a margin in [0, 1)");
    cross_entropy_ = equation.get_choice("loss", {"bce", "squares"}, "bce") == "bce";
    near_surface_ = equation.get_or("near_surface", 0.5);
    equation.require("near_surface", near_surface_ >= 0 && near_surface_ <= 1, "expected a share in [0, 1]");
    if (equation.has("surface_sigma")) sigma_ = equation.get_positive<double>("surface_sigma");
    if (equation.has("iou_resolution")) iou_resolution_ = equation.get_in_range("iou_resolution", 8, 1024);
    read_mesh(equation, context.config_dir / equation.get<std::string>("mesh"), normalize, margin);
    equation.reject_unknown_keys();
    make_progress_set();
  }

  const Domain& domain() const override { return domain_; }
  std::vector<std::string> output_names() const override { return {cross_entropy_ ? "logit" : "occupancy"}; }
  int residual_term() const override { return -1; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm term;
    term.name = "occupancy";
    term.batch_key = "interior";
    term.spec = autodiff::StreamSpec::values(3);
    term.sample = [this](Random& rng, Eigen::Index n) { return TermPoints(draw(rng, n, near_surface_)); };
    term.residual = [this](const TermPoints& points) -> std::unique_ptr<Residual> {
      return make_jet_residual(OccupancyResidual(labels(points.x), cross_entropy_));
    };
    return {term};
  }

  std::vector<std::pair<std::string, double>> progress_metrics(const OutputContext& context,
                                                               const TrainingRate&) const override {
    const Eigen::VectorXd u = context.values(progress_points_).col(0);
    const Agreement a = agreement(u, progress_labels_.array() > 0.5);
    return {{"IoU", a.iou()}, {"acc", a.accuracy()}};
  }

  void write_outputs(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const override {
    const int n = iou_resolution_;
    // iou_seconds counts from here: the grid's points, the field on them and the mesh's test.
    SliceProgress progress("occupancy: the field on the " + std::to_string(n) + "^3 grid");
    const io::Grid grid = io::make_grid(domain_.lower(), domain_.upper(), {n, n, n});
    const Eigen::MatrixXd x = grid.points(3);
    Eigen::VectorXd u(x.rows());
    constexpr Eigen::Index kSlice = 1 << 18;
    for (Eigen::Index first = 0; first < x.rows(); first += kSlice) {
      const Eigen::Index count = std::min(kSlice, x.rows() - first);
      u.segment(first, count) = context.values(x.middleRows(first, count)).col(0);
      progress.advance(first + count, x.rows());
    }
    const Agreement a = agreement(u, io::inside_closed_mesh(grid, shape_->mesh()));
    metrics.emplace_back("iou", a.iou());
    metrics.emplace_back("occupancy_accuracy", a.accuracy());
    metrics.emplace_back("iou_resolution", n);
    metrics.emplace_back("iou_seconds", progress.seconds());
    std::printf("IoU %.5f on %d^3 points (accuracy %.5f)\n", a.iou(), n, a.accuracy());
    write_surface(context, grid, u, metrics);
  }

 private:
  struct Agreement {
    Eigen::Index both = 0, either = 0, agree = 0, total = 0;
    double iou() const { return either > 0 ? static_cast<double>(both) / static_cast<double>(either) : 1.0; }
    double accuracy() const { return total > 0 ? static_cast<double>(agree) / static_cast<double>(total) : 0.0; }
  };
  double threshold() const { return cross_entropy_ ? 0.0 : 0.5; }

  Agreement agreement(const Eigen::VectorXd& u, const Eigen::Array<bool, Eigen::Dynamic, 1>& inside) const {
    Agreement a;
    a.total = u.size();
    for (Eigen::Index p = 0; p < u.size(); ++p) {
      const bool fitted = u(p) > threshold();
      a.both += fitted && inside(p);
      a.either += fitted || inside(p);
      a.agree += fitted == inside(p);
    }
    return a;
  }

  void read_mesh(const io::ConfigNode& equation, const std::filesystem::path& path, bool normalize, double margin) {
    try {
      original_ = io::read_triangle_mesh(path);
    } catch (const std::exception& e) {
      throw equation.error("mesh", e.what());
    }
    equation.require("mesh", original_.triangles.rows() > 0, path.filename().string() + ": expected a mesh with triangles");
    io::TriangleMesh mesh = original_;  // in domain coordinates
    const Eigen::Vector3d lower(domain_.lower().data()), upper(domain_.upper().data());
    if (normalize) {
      placement_ = ShapePlacement::fit(mesh.vertices, lower, upper, margin);
      mesh.vertices = placement_.to_domain(mesh.vertices);
    } else {
      equation.require("mesh", ShapePlacement::within(mesh.vertices, lower, upper),
                       path.filename().string() + ": the mesh leaves the domain: set normalize: true or widen the domain");
    }
    try {
      shape_ = std::make_shared<geometry::MeshShape>(std::move(mesh));
    } catch (const std::exception& e) {
      throw equation.error("mesh", path.filename().string() + ": " + e.what());
    }
  }

  // n points: uniform in the domain, and a share `near_share` about the surface.
  Eigen::MatrixXd draw(Random& rng, Eigen::Index n, double near_share) const {
    const Eigen::Index near = static_cast<Eigen::Index>(std::llround(near_share * static_cast<double>(n)));
    Eigen::MatrixXd x(n, 3);
    for (Eigen::Index p = 0; p < n; ++p) {
      if (p < near) {
        const double u[3] = {uniform01(rng), uniform01(rng), uniform01(rng)};
        const geometry::Vec3 s = shape_->boundary_point(u).point;
        for (int a = 0; a < 3; ++a) x(p, a) = s(a) + sigma_ * standard_normal(rng);
      } else {
        for (int a = 0; a < 3; ++a)
          x(p, a) = domain_.lower()[a] + (domain_.upper()[a] - domain_.lower()[a]) * uniform01(rng);
      }
    }
    return x;
  }

  Eigen::VectorXd labels(const Eigen::MatrixXd& x) const {
    Eigen::VectorXd y(x.rows());
    for (Eigen::Index p = 0; p < x.rows(); ++p) y(p) = shape_->contains(geometry::Vec3(x(p, 0), x(p, 1), x(p, 2))) ? 1.0 : 0.0;
    return y;
  }

  void make_progress_set() {
    Random rng(20261127);
    progress_points_ = draw(rng, 1 << 16, 0.0);
    progress_labels_ = labels(progress_points_);
  }

  // The decision surface on `grid`, in the mesh's coordinates, and its comparison with the mesh.
  void write_surface(const OutputContext& context, const io::Grid& grid, const Eigen::VectorXd& u,
                     std::vector<std::pair<std::string, double>>& metrics) const {
    io::TriangleMesh surface = io::extract_isosurface(grid, u, threshold(), true);
    surface.vertices = placement_.to_original(surface.vertices);
    io::write_vtp_mesh(context.dir / "surface.vtp", surface);
    io::write_ply(context.dir / "surface.ply", surface);
    const io::SurfaceComponents pieces = io::surface_components(surface);
    metrics.emplace_back("surface_components", pieces.count);
    metrics.emplace_back("surface_largest_component_area_share", pieces.largest_area_share);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double diagonal = (original_.vertices.colwise().maxCoeff() - original_.vertices.colwise().minCoeff()).norm();
    const bool some = surface.triangles.rows() > 0;
    const io::SurfaceComparison c = some ? io::compare_surfaces(surface, original_) : io::SurfaceComparison{};
    metrics.emplace_back("chamfer_mean", some ? c.chamfer_mean() : nan);
    metrics.emplace_back("chamfer_mean_per_diagonal", some ? c.chamfer_mean() / diagonal : nan);
    metrics.emplace_back("chamfer_max_per_diagonal", some ? c.chamfer_max() / diagonal : nan);
    metrics.emplace_back("normal_consistency", some ? c.normal_consistency : nan);
  }

  Domain domain_;
  bool cross_entropy_ = true;
  double near_surface_ = 0.5, sigma_ = 0.01;
  int iou_resolution_ = 256;
  io::TriangleMesh original_;  // as read
  ShapePlacement placement_;  // the mesh's own coordinates → the domain's
  std::shared_ptr<const geometry::MeshShape> shape_;
  Eigen::MatrixXd progress_points_;
  Eigen::VectorXd progress_labels_;
};

}  // namespace

std::unique_ptr<Problem> make_occupancy(const ProblemContext& context) { return std::make_unique<Occupancy>(context); }

}  // namespace nfield::solvers
