// SPDX-License-Identifier: MIT
//
// Radiance fields as one more equation (NeRF, Mildenhall et al. 2020): the "residual" of a
// ray is its rendered colour minus its pixel's colour, and it reads every sample of the ray.
//
//   problem: nerf
//   data:
//     train: data/multiview/bunny_blender/transforms_train.json   # NeRF-synthetic layout
//     test: data/multiview/bunny_blender/transforms_test.json     # optional: test views
//     background: white          # white | black | random (training rays only; tests: white)
//     recolour: {scale: [0.8, 1.2], shift: [-0.2, 0.2], seed: 0}   # optional: per image c·s + b
//     appearance: false          # true: an appearance code per training image (below)
//   scene:
//     lower: [-0.6, -0.6, -0.6]  # the box rays are clipped to, where the field lives
//     upper: [0.6, 0.6, 0.6]
//     near: 0.1                  # optional: no sample closer to the camera than this
//   render:
//     samples: 64                # stratified samples per ray (jittered in training)
//     importance: 0              # more samples per ray drawn from the first ones' weights
//     density: softplus          # softplus | trunc_exp: σ from the raw density output s
//     surface: 10                # density of the isosurface written after training
//     occupancy:                 # optional: skip empty space (integrators/occupancy_grid.h)
//       resolution: 64           #   cells per axis
//       every: 16                #   training steps between updates from the field's density
//       decay: 0.95              #   of the cells' density estimates per update
//       threshold: 0.01          #   opacity of one march step above which a cell is occupied
//       steps_per_diagonal: 256  #   march step = box diagonal / this (replaces `samples`)
//   field: {type: nerf, ...}     # input [x, d], output [s, r, g, b] (fields/field.h)
//                                # encoding integrated_positional: input [x, d, σ²]
//   training:
//     batch: {rays: 1024}        # rays per step
//
// One loss term, "rgb", draws `rays` random training pixels, their rays clipped to the
// scene box and stratified samples along them; its points are the samples [x, d], one
// group per ray (autodiff::Batch), and its residual per ray is C(ray) − C_pixel (3 values),
// with C from integrators/volume_rendering.h and σ = density(s), c = sigmoid(r, g, b). The
// reverse pass runs the rendering adjoint and the output activations' derivatives back to
// the samples' output streams. Training loss: mean over rays of ‖C − C_pixel‖².
//
// With `importance: k` (hierarchical sampling, NeRF Sec. 5.2, with one network): the
// stratified samples are first rendered with the current field, without gradients, and k
// more per ray are drawn from their weights (integrators::importance_samples); the field is
// trained and rendered on both sets merged. Not with an occupancy grid, which places the
// samples itself.
//
// With an occupancy grid, rays are marched at a fixed step through occupied cells only, in
// training (each sample jittered inside its interval) and in rendering (midpoints); the grid
// is updated from the field's density every `every` steps (before_step) and is
// rebuilt, not saved, on resume: every cell counts as occupied until the first update.
//
// With an encoding that reads variances (integrated_positional, mip-NeRF), each sample is the
// Gaussian of its conical frustum (integrators/cone_frustums.h: the ray's cone of its pixel,
// the stretch of length δ centred on the sample): the field's input is [mean, d, diagonal
// variance]. Density queries at bare points (the occupancy grid's updates, density.vti and
// the surface) give every point the isotropic variance of a typical sample: the frustum of
// one step (the march step, or the box diagonal over `samples`) at the training cameras'
// mean distance from the box centre with the central pixel's cone, its three axis variances
// averaged. A field trained on Gaussians has no meaning at σ² = 0 in its damped octaves
// (fields/integrated_positional.h).
//
// Appearance codes (data.appearance, NeRF in the Wild's NeRF-A, Martin-Brualla et al. 2021):
// the problem is a family (HasInstances) whose instances are the training images, each a
// problem that draws its own image's rays, trained with field.latent (the code joins the
// colour layers, fields/radiance_network.h) by the auto-decoder (solvers/run/latent_run.h).
// The test images are the held-out instances: each draws the rays of its left half only
// (integrators/dataset_views.h), so the code fitted to it has never seen the right half,
// where its figure (PSNR) and psnr_right_half_mean score it, as in the paper's synthetic
// experiments. An instance writes its own view (view/) with that code; the first training
// instance also writes the density and surface, which no code changes. Needs data.test;
// refuses an occupancy grid and importance samples (an instance's passes update no grid and
// hold no field to refine with).
//
// Outputs: the density σ on output.grid over the scene box as density.vti, its isosurface
// σ = render.surface as surface.vtp and surface.ply (VTK flying edges); every test view rendered (midpoint samples), beside its ground truth, the error,
// depth and opacity, as PNGs in test_views/; PSNR and SSIM per view and their means in
// metrics.json, with the mean time to render a view. With an occupancy grid the views are
// also rendered without it (the same march through every cell): render_ms_dense_mean and
// psnr_dense_mean show what skipping empty space gains and costs. The progress line shows
// rays per second and the PSNR of the first test view at a quarter of its resolution.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>

#include "autodiff/sequential.h"
#include "integrators/cone_frustums.h"
#include "integrators/dataset_views.h"
#include "integrators/multiview_dataset.h"
#include "integrators/occupancy_grid.h"
#include "integrators/ray_batch.h"
#include "integrators/ray_sampling.h"
#include "integrators/scene_box.h"
#include "integrators/volume_rendering.h"
#include "io/image_metrics.h"
#include "io/isosurface.h"
#include "io/vtk_image.h"
#include "io/vtk_polydata.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/radiance_scene.h"

namespace nfield::solvers {
namespace {

using integrators::RaySamples;

// The network's inputs [x, d] at every sample of every ray; with `variances`, [mean, d,
// variance] of each sample's frustum Gaussian.
Eigen::MatrixXd sample_inputs(const integrators::Rays<double>& rays, const RaySamples<double>& samples,
                              bool variances) {
  if (!variances) {
    Eigen::MatrixXd x(samples.size(), 6);
    x << integrators::sample_points(rays, samples), integrators::sample_directions(rays, samples);
    return x;
  }
  const integrators::SampleGaussians<double> gaussians = integrators::sample_gaussians(rays, samples);
  Eigen::MatrixXd x(samples.size(), 9);
  x << gaussians.mean, integrators::sample_directions(rays, samples), gaussians.variance;
  return x;
}

// What a drawn ray batch needs besides the sample positions: the samples' spacing, each
// ray's pixel colour and background.
struct RayBatch {
  RaySamples<double> samples;
  Eigen::MatrixXd target;      // R × 3
  Eigen::MatrixXd background;  // 1 × 3, or R × 3
};

class RayColourResidual final : public Residual {
 public:
  RayColourResidual(std::shared_ptr<const RayBatch> batch, DensityActivation density)
      : batch_(std::move(batch)), density_(density) {}

  int components() const override { return 3; }

  void evaluate(Eigen::Index first, const StreamLayout&, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    const Block b = block(first, out);
    const auto result = integrators::render<double>(b.samples, b.sigma, b.rgb, b.background);
    r = result.color - batch_->target.middleRows(b.k0, b.k1 - b.k0);
  }

  void backward(Eigen::Index first, const StreamLayout&, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    const Block b = block(first, out);
    integrators::RenderAdjoint<double> bar;
    bar.color = r_bar;
    Eigen::VectorXd sigma_bar(b.sigma.size());
    Eigen::MatrixXd rgb_bar(b.rgb.rows(), 3);
    integrators::render_backward<double>(b.samples, b.sigma, b.rgb, b.background, bar, sigma_bar,
                                         rgb_bar);
    const Eigen::Index offset = b.samples_begin;
    auto value = out.stream(StreamLayout::value());
    auto value_bar = adjoint.stream(StreamLayout::value());
    for (Eigen::Index i = 0; i < b.sigma.size(); ++i) {
      value_bar(offset + i, 0) += sigma_bar(i) * density_.derivative(value(offset + i, 0));
      for (int c = 0; c < 3; ++c) {
        const double rgb = b.rgb(i, c);
        value_bar(offset + i, 1 + c) += rgb_bar(i, c) * rgb * (1 - rgb);
      }
    }
  }

 private:
  struct Block {
    size_t k0 = 0, k1 = 0;
    Eigen::Index samples_begin = 0;  // row of the block's first sample in `out`
    RaySamples<double> samples;
    Eigen::VectorXd sigma;
    Eigen::MatrixXd rgb, background;
  };

  Block block(Eigen::Index first, const Streams<double>& out) const {
    const RaySamples<double>& all = batch_->samples;
    Block b;
    std::tie(b.k0, b.k1) = autodiff::groups_in_block(all.offsets, first, out.points);
    b.samples = integrators::ray_range(all, static_cast<Eigen::Index>(b.k0), static_cast<Eigen::Index>(b.k1));
    b.samples_begin = all.offsets[b.k0] - first;
    const Eigen::Index n = b.samples.size();
    const auto value = out.stream(StreamLayout::value()).middleRows(b.samples_begin, n);
    Shading shading = shade(value, density_);
    b.sigma = std::move(shading.sigma);
    b.rgb = std::move(shading.rgb);
    b.background = batch_->background.rows() == 1
                       ? batch_->background
                       : Eigen::MatrixXd(batch_->background.middleRows(b.k0, b.k1 - b.k0));
    return b;
  }

  std::shared_ptr<const RayBatch> batch_;
  DensityActivation density_;
};

class Nerf final : public Problem,
                   public TakesInputVariances,
                   public SamplesWithSolution,
                   public ReportsProgress,
                   public RendersViews,
                   public HasInstances {
 public:
  explicit Nerf(const ProblemContext& context) : scene_(context), box_(scene_.box()) {
    const io::ConfigNode render = context.root.child_or_empty("render");
    samples_ = render.has("samples") ? render.get_in_range("samples", 1, 4096) : 64;
    importance_ = render.has("importance") ? render.get_in_range("importance", 0, 4096) : 0;
    render.require("importance", importance_ == 0 || !render.has("occupancy"),
                   "expected 0 with an occupancy grid (the grid places the samples)");
    density_.truncated_exp = render.get_choice("density", {"softplus", "trunc_exp"}, "softplus") == "trunc_exp";
    surface_ = render.get_or("surface", surface_);
    render.require("surface", surface_ > 0 && std::isfinite(surface_), "expected a density > 0");
    if (render.has("occupancy")) read_occupancy(render.child("occupancy"));
    render.reject_unknown_keys();
    if (scene_.appearance()) check_appearance(context.root, render);
  }

  // data.appearance: every training image an instance; the test images held out, each
  // fitted on its left half and scored on its right half. A training instance's outputs are
  // its own view (the first one's also the density and surface, which no code changes).
  std::vector<ProblemInstance> instances(bool held_out) const override {
    std::vector<ProblemInstance> list;
    if (!scene_.appearance() || instance_) return list;
    const integrators::MultiviewDataset& views = held_out ? *scene_.test() : scene_.train();
    const int width = views.intrinsics.width;
    for (int k = 0; k < static_cast<int>(views.frames.size()); ++k) {
      auto view = std::make_shared<const integrators::MultiviewDataset>(integrators::single_frame(views, k));
      auto drawn = held_out ? std::make_shared<const integrators::MultiviewDataset>(
                                  integrators::frame_columns(views, k, 0, width / 2))
                            : view;
      auto instance = std::unique_ptr<Nerf>(new Nerf(*this, scene_.with_views(drawn, view, "view")));
      instance->scored_from_column_ = held_out ? width / 2 : 0;
      instance->writes_density_ = !held_out && k == 0;
      list.push_back({views.frames[static_cast<std::size_t>(k)].path.filename().string(), std::move(instance)});
    }
    return list;
  }

  const Domain& domain() const override { return scene_.domain(); }
  int field_input_dim() const override { return variances_ ? 9 : 6; }
  void give_input_variances() override {
    variances_ = true;
    // The frustum of one step at the cameras' mean distance, through the central pixel.
    const Eigen::Vector3d centre = 0.5 * (box_.lower + box_.upper);
    double distance = 0;
    const auto& frames = scene_.train().frames;
    for (const auto& frame : frames) distance += (frame.camera.centre() - centre).norm();
    distance /= static_cast<double>(frames.size());
    const double step = box_.size().norm() / (grid_ ? occupancy_.march.steps_per_diagonal : samples_);
    const integrators::Intrinsics& camera = scene_.train().intrinsics;
    const double radius = 2.0 / std::sqrt(12.0) / std::sqrt(camera.fx * camera.fy);
    const integrators::FrustumMoments f =
        integrators::frustum_moments(std::max(distance - step / 2, 0.0), distance + step / 2, radius);
    point_variance_ = (f.along + 2 * f.across) / 3;
  }
  int output_dim() const override { return 4; }
  std::vector<std::string> output_names() const override { return {"density", "red", "green", "blue"}; }
  int residual_term() const override { return -1; }
  bool writes_grid_outputs() const override { return false; }
  // The grid is updated at the first draw (a resumed run's too: the grid is not saved) and
  // every `every` steps after.
  void before_step(long step, const Solution& solution, Random&) override {
    solution_ = &solution;
    if (grid_ && (!grid_updated_ || step % occupancy_.every == 0)) {
      grid_->update([this](const Eigen::MatrixXd& p) { return density_with(solution_->values, p); }, occupancy_.decay);
      grid_updated_ = true;
    }
  }

  std::vector<std::pair<std::string, double>> progress_metrics(
      const OutputContext& context, const TrainingRate& rate) const override {
    // An instance's figure: the PSNR of its view where it is scored.
    if (instance_) return {{"PSNR", scene_.columns_psnr(renderer(context, nullptr), scored_from_column_)}};
    const double rays = rate.groups.empty() ? 0.0 : static_cast<double>(rate.groups[0]);
    const double samples = rate.points.empty() ? 0.0 : static_cast<double>(rate.points[0]);
    std::vector<std::pair<std::string, double>> figures{{"rays/s", rate.steps_per_second * rays},
                                                        {"samples/ray", samples / std::max(rays, 1.0)}};
    for (auto& figure : scene_.progress_psnr(renderer(context, grid_.get()))) figures.push_back(std::move(figure));
    return figures;
  }

  void render_views(const OutputContext& context, const RenderRequest& request) const override {
    if (grid_) {
      // The grid of the loaded field: one update at decay 0 holds just its densities.
      grid_->update([&](const Eigen::MatrixXd& p) { return density_with(context.values, p); }, 0.0);
    }
    scene_.render_views(context, request, renderer(context, grid_.get()));
  }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm rgb;
    rgb.name = "rgb";
    rgb.batch_key = "rays";
    rgb.spec = autodiff::StreamSpec::values(field_input_dim());
    rgb.sample = [this](Random& rng, Eigen::Index rays) { return draw(rng, rays); };
    const DensityActivation density = density_;
    rgb.residual = [density](const TermPoints& points) -> std::unique_ptr<Residual> {
      auto batch = std::static_pointer_cast<const RayBatch>(points.context);
      if (!batch) throw std::logic_error("nerf: a ray residual needs the batch it was drawn with");
      return std::make_unique<RayColourResidual>(std::move(batch), density);
    };
    return {rgb};
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    if (writes_density_) write_density(context, metrics);
    if (!scene_.test()) return;
    double dense_seconds = 0, dense_psnr_sum = 0;
    std::function<void(int)> dense_view;
    if (grid_) {
      // The same march through every cell: a grid before its first update.
      dense_view = [&](int f) {
        const integrators::OccupancyGrid everywhere(box_, grid_->options());
        const auto started = std::chrono::steady_clock::now();
        const View dense = scene_.render_view(*scene_.test(), f, renderer(context, &everywhere));
        dense_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        dense_psnr_sum += io::psnr(dense.rgb, dense.truth);
      };
    }
    const double seconds = scene_.write_test_views(context, renderer(context, grid_.get()), metrics, dense_view);
    if (grid_) {
      const auto n = static_cast<double>(scene_.test()->frames.size());
      metrics.emplace_back("psnr_dense_mean", dense_psnr_sum / n);
      metrics.emplace_back("render_ms_dense_mean", 1e3 * dense_seconds / n);
      metrics.emplace_back("occupied_cells", static_cast<double>(grid_->occupied_cells()));
      std::printf("without the occupancy grid: mean PSNR %.2f dB, %.0f ms a view (%.1fx slower)\n",
                  dense_psnr_sum / n, 1e3 * dense_seconds / n, dense_seconds / n / std::max(seconds, 1e-9));
    }
  }

 private:
  // An instance of the family `family` (data.appearance) that draws and renders `scene`.
  Nerf(const Nerf& family, RadianceScene scene)
      : scene_(std::move(scene)),
        box_(family.box_),
        samples_(family.samples_),
        importance_(family.importance_),
        variances_(family.variances_),
        point_variance_(family.point_variance_),
        surface_(family.surface_),
        density_(family.density_),
        instance_(true) {}

  // Appearance codes are trained by the auto-decoder, whose passes draw and render with no
  // grid updates and no field in hand (before_step is not called for an instance).
  static void check_appearance(const io::ConfigNode& root, const io::ConfigNode& render) {
    const io::ConfigNode data = root.child("data");
    if (!root.child_or_empty("field").has("latent"))
      throw data.error("appearance", "expected field.latent: {size: N} too: the appearance code of each image");
    if (render.has("occupancy"))
      throw render.error("occupancy", "not with data.appearance: each image's instance draws stratified samples");
    if (render.has("importance") && render.get<int>("importance") > 0)
      throw render.error("importance", "expected 0 with data.appearance: each image's instance draws stratified "
                                       "samples");
  }

  struct OccupancySettings {
    integrators::OccupancyGridOptions grid;
    integrators::MarchOptions march;
    int every = 16;
    double decay = 0.95;
  };

  void read_occupancy(const io::ConfigNode& node) {
    OccupancySettings o;
    o.grid.resolution = node.has("resolution") ? node.get_in_range("resolution", 4, 512) : 64;
    o.every = node.has("every") ? node.get_in_range("every", 1, 1 << 20) : o.every;
    o.decay = node.get_or("decay", o.decay);
    node.require("decay", o.decay >= 0 && o.decay <= 1, "expected a number in [0, 1]");
    const double opacity = node.get_or("threshold", 0.01);
    node.require("threshold", opacity > 0 && opacity < 1, "expected an opacity in (0, 1)");
    o.march.steps_per_diagonal =
        node.has("steps_per_diagonal") ? node.get_in_range("steps_per_diagonal", 4, 1 << 16) : 256;
    // A cell is occupied where one march step through it would be more opaque than
    // `threshold`: σ > −ln(1 − threshold) / step (Instant NGP: 0.01 · 1024/√3 for its step).
    const double step = box_.size().norm() / o.march.steps_per_diagonal;
    o.grid.threshold = -std::log1p(-opacity) / step;
    node.reject_unknown_keys();
    occupancy_ = o;
    grid_ = std::make_unique<integrators::OccupancyGrid>(box_, o.grid);
  }

  // σ at points (N × 3): the density does not depend on the direction, any will do; with
  // variances, a typical sample's (give_input_variances).
  Eigen::VectorXd density_with(const Solution::Values& values, const Eigen::MatrixXd& points) const {
    Eigen::MatrixXd x(points.rows(), field_input_dim());
    x.leftCols(3) = points;
    x.middleCols(3, 3).setZero();
    x.col(5).setOnes();
    if (variances_) x.rightCols(3).setConstant(point_variance_);
    return values(x).col(0).unaryExpr([this](double s) { return density_.value(s); });
  }

  TermPoints draw(Random& rng, Eigen::Index rays) const {
    std::mt19937_64 engine(rng());
    PixelTargets drawn = scene_.draw_pixels(rays, engine);
    const integrators::Rays<double>& pixel_rays = drawn.pixels.rays;
    auto batch = std::make_shared<RayBatch>();
    if (grid_ && grid_updated_) {
      batch->samples = grid_->march(pixel_rays, occupancy_.march);
      // Each sample anywhere in its interval, so that training sees all of it.
      for (Eigen::Index i = 0; i < batch->samples.size(); ++i)
        batch->samples.t(i) += (static_cast<double>(engine() >> 11) * 0x1.0p-53 - 0.5) * batch->samples.delta(i);
    } else {
      batch->samples = integrators::stratified_samples(pixel_rays, {samples_, true}, engine);
      if (importance_ > 0 && solution_)
        batch->samples = refined(solution_->values, pixel_rays, batch->samples, drawn.pixels.background, false, engine);
    }
    scene_.draw_targets(drawn, engine);
    batch->target = std::move(drawn.target);
    batch->background = std::move(drawn.background);
    TermPoints points;
    points.x = sample_inputs(pixel_rays, batch->samples, variances_);
    points.groups = batch->samples.offsets;
    points.context = std::move(batch);
    return points;
  }

  // The coarse samples and `importance_` more per ray drawn from their rendering weights with
  // the field `values` (deterministic: at the inverse CDF's midpoints), merged in order.
  RaySamples<double> refined(const Solution::Values& values, const integrators::Rays<double>& rays,
                             const RaySamples<double>& coarse, const Eigen::Vector3d& background,
                             bool deterministic, std::mt19937_64& engine) const {
    const Shading coarse_shading = shade(values(sample_inputs(rays, coarse, variances_)), density_);
    const auto weights = integrators::render<double>(coarse, coarse_shading.sigma, coarse_shading.rgb,
                                                     background.transpose()).weights;
    integrators::ImportanceOptions options;
    options.samples_per_ray = importance_;
    options.deterministic = deterministic;
    options.include_coarse = true;
    return integrators::importance_samples(rays, coarse, weights, options, engine);
  }

  // Rays marched through `grid` or sampled at the stratified midpoints (refined by
  // importance), with the field context.values.
  RenderRays renderer(const OutputContext& context, const integrators::OccupancyGrid* grid) const {
    return [this, &context, grid](const integrators::Rays<double>& rays, const Eigen::Vector3d& background) {
      std::mt19937_64 unused(0);
      RaySamples<double> samples = grid ? grid->march(rays, occupancy_.march)
                                        : integrators::stratified_samples(rays, {samples_, false}, unused);
      if (!grid && importance_ > 0) samples = refined(context.values, rays, samples, background, true, unused);
      return composite(samples, shade(context.values(sample_inputs(rays, samples, variances_)), density_), background);
    };
  }

  void write_density(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const {
    const io::Grid grid = io::make_grid(scene_.domain().lower(), scene_.domain().upper(), context.grid);
    const Eigen::MatrixXd points = grid.points(3);
    Eigen::VectorXd sigma(points.rows());
    constexpr Eigen::Index kChunk = 1 << 16;
    for (Eigen::Index start = 0; start < points.rows(); start += kChunk) {
      const Eigen::Index count = std::min(kChunk, points.rows() - start);
      sigma.segment(start, count) = density_with(context.values, points.middleRows(start, count));
    }
    io::write_vti(context.dir / "density.vti", grid, {{"density", sigma}}, io::Precision::kFloat32);
    const io::TriangleMesh surface = io::extract_isosurface(grid, sigma, surface_, true);
    io::write_vtp_mesh(context.dir / "surface.vtp", surface);
    io::write_ply(context.dir / "surface.ply", surface);
    metrics.emplace_back("surface_vertices", static_cast<double>(surface.vertices.rows()));
    metrics.emplace_back("surface_triangles", static_cast<double>(surface.triangles.rows()));
  }

  RadianceScene scene_;
  integrators::SceneBox box_;
  int samples_ = 64;
  int importance_ = 0;
  bool variances_ = false;      // the field reads [mean, d, variance] (give_input_variances)
  double point_variance_ = 0;   // the variance per axis of a density query at a point
  double surface_ = 10;
  DensityActivation density_;
  OccupancySettings occupancy_;
  std::unique_ptr<integrators::OccupancyGrid> grid_;  // null: stratified samples
  const Solution* solution_ = nullptr;                // the field in training (before_step)
  bool grid_updated_ = false;                         // since this problem was built
  bool instance_ = false;                             // one image of an appearance family
  int scored_from_column_ = 0;                        // an instance's figure: its view's columns from here
  bool writes_density_ = true;                        // density.vti and the surface in write_outputs
};

}  // namespace

std::unique_ptr<Problem> make_nerf(const ProblemContext& context) {
  return std::make_unique<Nerf>(context);
}

}  // namespace nfield::solvers
