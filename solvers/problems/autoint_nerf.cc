// SPDX-License-Identifier: MIT
//
// Volume rendering by automatic integration (AutoInt, Lindell, Martel and Wetzstein, CVPR
// 2021): the field is the antiderivative Φ(x, d) = [Φ_σ, Φ_r, Φ_g, Φ_b] of raw density and
// colour along rays, so a section's integral is a difference of two values, not a sum of
// many samples.
//
//   problem: autoint_nerf
//   data, scene: as for `problem: nerf` (solvers/problems/radiance_scene.h)
//   render:
//     sections: 16              # K equal sections of each ray's [near, far] in the box
//     samples_per_section: 4    # m stratified samples per section in training
//     density: softplus         # softplus | trunc_exp, on a section's mean raw density
//     density_scale: 10         # s̄_σ = this × the mean rate of Φ_σ (default 1)
//     sampler:                  # optional: sections placed by a sampling network
//       hidden: [64, 64]        #   (solvers/problems/section_sampler.h); `true`: these
//       frequencies: 4          #   defaults; absent or `false`: equal sections
//       lr: 1.0e-3
//       min_share: 0.25         #   each section ≥ min_share/K of the ray
//       every: 1                #   steps between the network's updates
//       rays: 256               #   rays of the batch each update reads
//   field: {type: nerf, activation: tanh, encoding: {type: positional, normalize: true}}
//   training:
//     batch: {rays: 1024}
//
// Along a ray x(t) = o + t·d the "grad network" of the paper is ∂Φ/∂t = ∇ₓΦ · d: one tangent
// stream of Φ with the per-point tangent (d, 0) (TermPoints::tangents), computed with its
// reverse pass by the derivative streams, not a second network.
//
// Training. Each ray (clipped to the scene box and the near plane) is cut into K equal
// sections; m stratified samples per section give the section means
//   s̄ᵢ = (1/m) Σⱼ ∂Φ/∂t(tᵢⱼ)   (4 channels),
// estimates of (Φ(tᵢ₊₁) − Φ(tᵢ))/Δ. As in the paper's code, the output nonlinearities act on
// these means, after the integral: σᵢ = density(λ s̄ᵢ,σ), cᵢ = sigmoid(s̄ᵢ,rgb) (the paper
// uses ReLU for the density; softplus keeps a gradient for sections whose mean is negative,
// which ReLU would leave dead). λ = `density_scale` lets densities of tens to hundreds (an
// opaque surface within a section) come from rates of order one: Adam moves the weights by
// about the learning rate a step, so without it the density head would take many steps to
// grow that large (docs/experiments.md). The sections are composited as NeRF's piecewise-constant quadrature
// (integrators/volume_rendering.h: one "sample" per section, δ = Δ); its adjoint reaches each
// sample's tangent stream through the activations' derivatives and 1/m. The loss is the mean
// over rays of ‖C − C_pixel‖², one group of K·m samples per ray.
//
// Rendering. s̄ᵢ = (Φ(o + tᵢ₊₁d, d) − Φ(o + tᵢd, d))/Δᵢ exactly, from the values at the K + 1
// section ends (no tangent streams), composited the same way: a ray costs K + 1 field
// evaluations.
//
// Sampling network (`render.sampler`). The sections are those a small network places per
// ray (section_sampler.h) instead of equal ones, in training and rendering alike. Before
// each batch's step of the field (before_step), the network takes one Adam step on the
// rendering loss of `sampler.rays` rays of their own, drawn like the batch's, at its own
// sections, with Φ fixed; the field's step then trains at the
// stratified samples of the sections it now places. Its weights and Adam state are saved in
// the checkpoint (group `sampler`), so resume and `nfield render` use the same sections. A
// ray then costs one evaluation of the sampling network besides the K + 1 of Φ.
//
// Encodings: the positional encoding's octave l should be scaled by 2⁻ˡ
// (`encoding.normalize: true`, as the paper's normalize_pe), so that ∂Φ/∂t, which the
// training sees, does not amplify the high octaves by 2ˡ. The network should be smooth
// (tanh, softplus, sine; the paper: Swish or sine): ∂Φ/∂t of a ReLU network is piecewise
// constant and the tangent stream's reverse pass reads the activation's second derivative,
// which ReLU lacks. Tanh trained better than softplus here (docs/experiments.md) and costs
// less per evaluation.
//
// Outputs: every test view rendered beside its ground truth, error, depth and opacity in
// test_views/, PSNR and SSIM per view and their means and the time to render a view in
// metrics.json (as `problem: nerf`; no density grid: σ is a derivative of the field). The
// progress line shows rays per second and the PSNR of the first test view at every 4th pixel.
#include <cmath>
#include <random>

#include "autodiff/sequential.h"
#include "integrators/ray_sampling.h"
#include "integrators/volume_rendering.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/problems/problems.h"
#include "solvers/problems/radiance_scene.h"
#include "solvers/problems/section_sampler.h"

namespace nfield::solvers {
namespace {

using integrators::RaySamples;

// A drawn batch: the rays' sections, the m samples per section behind them, and the pixels.
struct SectionBatch {
  RaySamples<double> sections;  // one entry per section: t its midpoint, δ its length
  int samples_per_section = 1;
  std::vector<Eigen::Index> groups;  // the samples' offsets: sections.offsets × m
  Eigen::MatrixXd target;      // R × 3
  Eigen::MatrixXd background;  // 1 × 3, or R × 3
};

// Per ray: the rendered colour of its sections minus the pixel's, the section means read
// from the tangent stream ∂Φ/∂t of the samples (m consecutive samples per section).
class SectionColourResidual final : public Residual {
 public:
  SectionColourResidual(std::shared_ptr<const SectionBatch> batch, DensityActivation density, double density_scale)
      : batch_(std::move(batch)), density_(density), density_scale_(density_scale) {}

  int components() const override { return 3; }

  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    const Block b = block(first, layout, out);
    const auto result = integrators::render<double>(b.sections, b.shading.sigma, b.shading.rgb, b.background);
    r = result.color - batch_->target.middleRows(b.k0, b.k1 - b.k0);
  }

  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    const Block b = block(first, layout, out);
    integrators::RenderAdjoint<double> bar;
    bar.color = r_bar;
    const Eigen::Index n = b.sections.size();
    Eigen::VectorXd sigma_bar(n);
    Eigen::MatrixXd rgb_bar(n, 3);
    integrators::render_backward<double>(b.sections, b.shading.sigma, b.shading.rgb, b.background, bar,
                                         sigma_bar, rgb_bar);
    const int m = batch_->samples_per_section;
    auto tangent_bar = adjoint.stream(layout.tangent(0));
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector4d mean_bar;
      mean_bar(0) = sigma_bar(i) * density_.derivative(b.means(i, 0)) * density_scale_;
      for (int c = 0; c < 3; ++c) {
        const double rgb = b.shading.rgb(i, c);
        mean_bar(1 + c) = rgb_bar(i, c) * rgb * (1 - rgb);
      }
      for (int j = 0; j < m; ++j) tangent_bar.row(b.samples_begin + i * m + j) += mean_bar.transpose() / m;
    }
  }

 private:
  struct Block {
    size_t k0 = 0, k1 = 0;
    Eigen::Index samples_begin = 0;  // row of the block's first sample in `out`
    RaySamples<double> sections;
    Eigen::MatrixXd means;  // sections × 4: s̄, the density column times λ
    Shading shading;
    Eigen::MatrixXd background;
  };

  Block block(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out) const {
    const SectionBatch& all = *batch_;
    const int m = all.samples_per_section;
    const std::vector<Eigen::Index>& groups = all.groups;
    Block b;
    std::tie(b.k0, b.k1) = autodiff::groups_in_block(groups, first, out.points);
    b.sections = integrators::ray_range(all.sections, static_cast<Eigen::Index>(b.k0), static_cast<Eigen::Index>(b.k1));
    b.samples_begin = groups[b.k0] - first;
    const Eigen::Index n = b.sections.size();
    const auto tangent = out.stream(layout.tangent(0));
    b.means.setZero(n, 4);
    for (Eigen::Index i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j) b.means.row(i) += tangent.row(b.samples_begin + i * m + j);
    b.means /= m;
    b.means.col(0) *= density_scale_;
    b.shading = shade(b.means, density_);
    b.background = all.background.rows() == 1 ? all.background
                                              : Eigen::MatrixXd(all.background.middleRows(b.k0, b.k1 - b.k0));
    return b;
  }

  std::shared_ptr<const SectionBatch> batch_;
  DensityActivation density_;
  double density_scale_;
};

class AutointNerf final : public Problem,
                          public SamplesWithSolution,
                          public KeepsState,
                          public ReportsProgress,
                          public RendersViews {
 public:
  explicit AutointNerf(const ProblemContext& context) : scene_(context) {
    const io::ConfigNode render = context.root.child_or_empty("render");
    sections_ = render.has("sections") ? render.get_in_range("sections", 1, 4096) : sections_;
    samples_per_section_ =
        render.has("samples_per_section") ? render.get_in_range("samples_per_section", 1, 1024) : samples_per_section_;
    density_.truncated_exp = render.get_choice("density", {"softplus", "trunc_exp"}, "softplus") == "trunc_exp";
    density_scale_ = render.get_or("density_scale", density_scale_);
    render.require("density_scale", density_scale_ > 0 && std::isfinite(density_scale_), "expected a number > 0");
    if (render.has("sampler")) {
      const YAML::Node node = render.yaml()["sampler"];
      if (node.IsMap())
        sampler_ = std::make_unique<SectionSampler>(sections_, SectionSamplerOptions::from_config(render.child("sampler")));
      else if (node.IsScalar() && render.get<bool>("sampler"))
        sampler_ = std::make_unique<SectionSampler>(sections_, SectionSamplerOptions{});
      else
        render.require("sampler", node.IsScalar(), "expected true, false or a mapping of the network's options");
    }
    render.reject_unknown_keys();
  }

  // The sampling network's update: every `sampler.every` steps, on rays of its own.
  void before_step(long step, const Solution& solution, Random& rng) override {
    if (!sampler_ || step % sampler_->options().every != 0) return;
    std::mt19937_64 engine(rng());
    PixelTargets drawn = scene_.draw_pixels(sampler_->options().rays, engine);
    scene_.draw_targets(drawn, engine);
    last_update_ = sampler_->update(drawn.pixels.rays, drawn.target, drawn.background, solution.streams, density_,
                                    density_scale_);
  }
  void save_state(io::H5Writer& file) const override {
    if (sampler_) sampler_->save(file, "sampler");
  }
  void load_state(const io::H5Reader& file) override {
    if (sampler_) sampler_->load(file, "sampler");
  }

  const Domain& domain() const override { return scene_.domain(); }
  int field_input_dim() const override { return 6; }
  int output_dim() const override { return 4; }
  std::vector<std::string> output_names() const override {
    return {"density_integral", "red_integral", "green_integral", "blue_integral"};
  }
  int residual_term() const override { return -1; }
  bool writes_grid_outputs() const override { return false; }

  std::vector<std::pair<std::string, double>> progress_metrics(const OutputContext& context,
                                                               const TrainingRate& rate) const override {
    const double rays = rate.groups.empty() ? 0.0 : static_cast<double>(rate.groups[0]);
    std::vector<std::pair<std::string, double>> figures{{"rays/s", rate.steps_per_second * rays}};
    if (sampler_) {
      figures.emplace_back("sampler_loss", last_update_.loss);
      figures.emplace_back("max_section", last_update_.max_section_share);
    }
    for (auto& figure : scene_.progress_psnr(renderer(context.values))) figures.push_back(std::move(figure));
    return figures;
  }

  void render_views(const OutputContext& context, const RenderRequest& request) const override {
    scene_.render_views(context, request, renderer(context.values));
  }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm rgb;
    rgb.name = "rgb";
    rgb.batch_key = "rays";
    // One tangent stream; its direction is each sample's own (d, 0), given per point.
    rgb.spec = autodiff::StreamSpec::values(6);
    rgb.spec.tangents = Eigen::MatrixXd::Zero(6, 1);
    rgb.spec.tangents(0, 0) = 1;
    rgb.sample = [this](Random& rng, Eigen::Index rays) { return draw(rng, rays); };
    const DensityActivation density = density_;
    const double density_scale = density_scale_;
    rgb.residual = [density, density_scale](const TermPoints& points) -> std::unique_ptr<Residual> {
      auto batch = std::static_pointer_cast<const SectionBatch>(points.context);
      if (!batch) throw std::logic_error("autoint_nerf: a ray residual needs the batch it was drawn with");
      return std::make_unique<SectionColourResidual>(std::move(batch), density, density_scale);
    };
    return {rgb};
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    scene_.write_test_views(context, renderer(context.values), metrics);
    metrics.emplace_back("field_evaluations_per_ray", sections_ + 1);
    metrics.emplace_back("sampling_network", sampler_ ? 1 : 0);
    if (sampler_) {
      metrics.emplace_back("sampler_parameters", static_cast<double>(sampler_->parameter_count()));
      metrics.emplace_back("sampler_loss", last_update_.loss);
      metrics.emplace_back("sampler_max_section_share", last_update_.max_section_share);
    }
  }

 private:
  TermPoints draw(Random& rng, Eigen::Index rays) const {
    std::mt19937_64 engine(rng());
    PixelTargets drawn = scene_.draw_pixels(rays, engine);
    const integrators::Rays<double>& pixel_rays = drawn.pixels.rays;
    auto batch = std::make_shared<SectionBatch>();
    batch->samples_per_section = samples_per_section_;
    RaySamples<double> samples;
    if (sampler_) {
      scene_.draw_targets(drawn, engine);
      batch->sections = sampler_->sections(pixel_rays);
      samples = stratified_in_sections(batch->sections, samples_per_section_, engine);
    } else {
      batch->sections = integrators::equal_sections(pixel_rays, sections_);
      // K·m equal bins, one jittered sample each: bins [i·m, (i+1)·m) are section i's.
      samples = integrators::stratified_samples(pixel_rays, {sections_ * samples_per_section_, true}, engine);
      scene_.draw_targets(drawn, engine);
    }
    batch->target = std::move(drawn.target);
    batch->background = std::move(drawn.background);

    TermPoints points;
    const Eigen::MatrixXd directions = integrators::sample_directions(pixel_rays, samples);
    points.x.resize(samples.size(), 6);
    points.x << integrators::sample_points(pixel_rays, samples), directions;
    points.tangents = Eigen::MatrixXd::Zero(samples.size(), 6);
    points.tangents.leftCols(3) = directions;
    points.groups = samples.offsets;
    batch->groups = samples.offsets;
    points.context = std::move(batch);
    return points;
  }

  // m samples per section, one in each of its m equal parts at a uniform place.
  static RaySamples<double> stratified_in_sections(const RaySamples<double>& sections, int m,
                                                   std::mt19937_64& engine) {
    RaySamples<double> out;
    out.offsets.resize(sections.offsets.size());
    for (size_t r = 0; r < sections.offsets.size(); ++r) out.offsets[r] = sections.offsets[r] * m;
    out.t.resize(sections.size() * m);
    out.delta.resize(sections.size() * m);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (Eigen::Index i = 0; i < sections.size(); ++i) {
      const double part = sections.delta(i) / m, begin = sections.t(i) - 0.5 * sections.delta(i);
      for (int j = 0; j < m; ++j) {
        out.t(i * m + j) = begin + (j + uniform(engine)) * part;
        out.delta(i * m + j) = part;
      }
    }
    return out;
  }

  // Section means from Φ at the K + 1 section ends of every ray, composited.
  RenderRays renderer(const Solution::Values& values) const {
    return [this, values](const integrators::Rays<double>& rays, const Eigen::Vector3d& background) {
      const RaySamples<double> sections =
          sampler_ ? sampler_->sections(rays) : integrators::equal_sections(rays, sections_);
      const Eigen::Index hit = static_cast<Eigen::Index>(sections.size() / sections_);
      const Eigen::Index ends = sections_ + 1;
      Eigen::MatrixXd x(hit * ends, 6);
      Eigen::Index row = 0;
      for (Eigen::Index r = 0; r < rays.size(); ++r) {
        if (sections.count(r) == 0) continue;
        double t = rays.near(r);
        for (Eigen::Index e = 0; e < ends; ++e, ++row) {
          x.row(row).head(3) = rays.origins.row(r) + t * rays.directions.row(r);
          x.row(row).tail(3) = rays.directions.row(r);
          t = e + 1 < sections_ ? t + sections.delta(sections.begin(r) + e) : rays.far(r);
        }
      }
      const Eigen::MatrixXd phi = values(x);
      Eigen::MatrixXd means(sections.size(), 4);
      for (Eigen::Index k = 0; k < hit; ++k)
        for (Eigen::Index i = 0; i < sections_; ++i)
          means.row(k * sections_ + i) =
              (phi.row(k * ends + i + 1) - phi.row(k * ends + i)) / sections.delta(k * sections_ + i);
      means.col(0) *= density_scale_;
      return composite(sections, shade(means, density_), background);
    };
  }

  RadianceScene scene_;
  int sections_ = 16;
  int samples_per_section_ = 4;
  DensityActivation density_;
  double density_scale_ = 1;
  std::unique_ptr<SectionSampler> sampler_;  // null: equal sections
  SamplerUpdate last_update_;                // of before_step's last update
};

}  // namespace

std::unique_ptr<Problem> make_autoint_nerf(const ProblemContext& context) {
  return std::make_unique<AutointNerf>(context);
}

}  // namespace nfield::solvers
