// SPDX-License-Identifier: MIT
#include "apps/nerf_bench.h"

#include <omp.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "apps/gemm_rate.h"
#include "fields/field.h"
#include "integrators/cone_frustums.h"
#include "integrators/multiview_dataset.h"
#include "integrators/radiance_activations.h"
#include "integrators/ray_batch.h"
#include "integrators/ray_sampling.h"
#include "integrators/scene_box.h"
#include "integrators/volume_rendering.h"
#include "solvers/training/adam.h"
#include "solvers/training/optimizers.h"
#include "solvers/run.h"
#include "solvers/training/sampler.h"

namespace nfield::apps {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The trainer's loss, with the time spent in it added up: for a ray residual that is the
// volume rendering, its adjoint and the output activations. The pass calls it from every
// thread at once.
class TimedLoss final : public autodiff::StreamLoss<float> {
 public:
  TimedLoss(const autodiff::StreamLoss<float>& inner, std::atomic<double>& seconds)
      : inner_(inner), seconds_(seconds) {}
  double evaluate(Eigen::Index first, const autodiff::StreamLayout& layout,
                  const autodiff::Streams<float>& out, autodiff::Streams<float>& adjoint) const override {
    const auto start = Clock::now();
    const double loss = inner_.evaluate(first, layout, out, adjoint);
    seconds_.fetch_add(seconds_since(start), std::memory_order_relaxed);
    return loss;
  }

 private:
  const autodiff::StreamLoss<float>& inner_;
  std::atomic<double>& seconds_;
};

// The products of the dense layers. The first reads the encoding, which has no parameters,
// so a training step needs no input adjoint there; it is not counted even though the
// reverse pass forms it, so that the rate is that of the products the step needs.
std::vector<GemmShape> dense_shapes(const fields::Field<float>& field) {
  std::vector<GemmShape> shapes;
  for (const auto& module : field.network().modules()) {
    if (module->parameter_count() == 0) continue;
    const autodiff::Module<float>& dense = fields::parameter_owner(*module);
    shapes.push_back({dense.input_width(), dense.output_width(), !shapes.empty()});
  }
  return shapes;
}

struct FrameTiming {
  double median_ms = 0;
  Eigen::Index pixels = 0, samples = 0;
};

// Renders the first test view (or training view, for a config without test views) the way
// the run renders its test views without an occupancy grid: stratified midpoints, the
// field's values in its own precision, compositing in double.
FrameTiming time_frame(const solvers::RunSetup& setup, const fields::Field<float>& field,
                       const NerfBenchOptions& options) {
  const io::ConfigNode data = setup.root.child("data");
  integrators::DatasetOptions dataset;
  if (data.get_or("background", "white") == "black") dataset.background.setZero();
  const auto views = integrators::read_transforms(
      setup.data_dir / data.get<std::string>(data.has("test") ? "test" : "train"), dataset);
  const integrators::SceneBox box{Eigen::Vector3d(setup.problem->domain().lower().data()),
                                  Eigen::Vector3d(setup.problem->domain().upper().data())};
  const double near = setup.root.child("scene").get_or("near", 0.0);
  const io::ConfigNode render = setup.root.child_or_empty("render");
  const int samples_per_ray = render.get_or("samples", 64);
  const integrators::DensityActivation density{render.get_or("density", "softplus") == "trunc_exp"};
  const int width = views.intrinsics.width, stride = options.render_stride;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index p = 0; p < views.pixels_per_image(); ++p)
    if ((p / width) % stride == 0 && (p % width) % stride == 0) kept.push_back(p);

  FrameTiming timing;
  std::vector<double> ms;
  // No untimed render first: the training steps before have warmed the passes up.
  for (int r = 0; r < options.render_repeats; ++r) {
    const auto start = Clock::now();
    integrators::PixelBatch<double> all = integrators::frame_pixels<double>(views, 0);
    integrators::Rays<double> rays = all.rays;
    if (stride > 1)
      rays = all.rays.subset(kept);
    integrators::clip_to_box(rays, box, near);
    std::mt19937_64 unused(0);
    const auto samples = integrators::stratified_samples(rays, {samples_per_ray, false}, unused);
    // [x, d], or [mean, d, σ²] of the samples' frustums for an encoding that reads variances.
    Eigen::MatrixXd x(samples.size(), setup.field.input_dim);
    if (setup.field.input_dim == 6) {
      x << integrators::sample_points(rays, samples), integrators::sample_directions(rays, samples);
    } else {
      const integrators::SampleGaussians<double> gaussians = integrators::sample_gaussians(rays, samples);
      x << gaussians.mean, integrators::sample_directions(rays, samples), gaussians.variance;
    }
    const Eigen::MatrixXd out = field.values(x.cast<float>()).cast<double>();
    const Eigen::VectorXd sigma = out.col(0).unaryExpr([density](double s) { return density.value(s); });
    const Eigen::MatrixXd rgb = out.rightCols(3).unaryExpr(&integrators::colour_activation);
    const auto image = integrators::render<double>(samples, sigma, rgb, views.background.transpose());
    ms.push_back(1e3 * seconds_since(start));
    timing.pixels = image.color.rows();
    timing.samples = samples.size();
  }
  timing.median_ms = median(ms);
  return timing;
}

}  // namespace

void run_nerf_bench(const NerfBenchOptions& options) {
  solvers::RunSetup setup = solvers::load_run(options.config, options.overrides);
  if (setup.field.type != "nerf")
    throw CLI::ValidationError("--config", options.config.string() + " trains a '" + setup.field.type +
                                               "' field; --nerf needs a radiance field (field.type: nerf)");
  const int threads = options.threads > 0 ? options.threads : setup.training.threads;
  if (threads > 0) omp_set_num_threads(threads);
  const int used_threads = omp_get_max_threads();
  fields::Field<float> field(setup.field, {setup.training.block, used_threads});
  const std::vector<GemmShape> shapes = dense_shapes(field);

  // The trainer's loss terms and batch sizes (solvers/training/trainer.cc: resample, term_loss).
  const std::vector<solvers::LossTerm> terms = setup.problem->loss_terms();
  for (const solvers::LossTerm& term : terms)
    if (term.spec.tangents.cols() > 0)
      throw CLI::ValidationError("--config", options.config.string() + " trains derivative streams (loss term '" +
                                                 term.name + "'); --nerf times NeRF's quadrature (for problem: "
                                                 "autoint_nerf use --autoint)");
  std::vector<autodiff::StreamLayout> layouts;
  std::vector<Eigen::Index> batch;
  long rays = 0;
  for (const solvers::LossTerm& term : terms) {
    layouts.emplace_back(term.spec);
    batch.push_back(options.rays > 0 ? options.rays : setup.training.batch.at(term.batch_key));
    if (term.batch_key == "rays") rays += batch.back();
  }
  const solvers::StageOptions& stage = setup.training.stages.front();
  const auto& schedule = stage.options<solvers::AdamStageOptions>();
  solvers::Adam<float> adam(field.parameter_count(), {schedule.lr});
  solvers::Random rng(setup.training.seed);
  std::vector<solvers::TermPoints> points(terms.size());
  std::vector<autodiff::Matrix<float>> x(terms.size());
  std::vector<std::unique_ptr<solvers::Residual>> residuals(terms.size());
  autodiff::Vector<float> gradient(field.parameter_count());
  std::atomic<double> loss_seconds{0};

  if (!options.json_only) {
    std::printf("radiance field of %s: %ld parameters, float, %d threads, block %ld points, %ld rays a step\n",
                options.config.string().c_str(), static_cast<long>(field.parameter_count()), used_threads,
                setup.training.block, rays);
    std::fflush(stdout);
  }
  struct Step {
    double total, sampling, passes, rendering, adam, flops;
    Eigen::Index samples;
  };
  std::vector<Step> timed;
  for (int s = 0; s < options.warmup + options.steps; ++s) {
    const auto start = Clock::now();
    Eigen::Index samples = 0;
    for (size_t k = 0; k < terms.size(); ++k) {
      points[k] = terms[k].sample(rng, batch[k]);
      x[k] = points[k].x.cast<float>();
      residuals[k] = terms[k].residual(points[k]);
      samples += points[k].x.rows();
    }
    const auto drawn = Clock::now();
    gradient.setZero();
    loss_seconds = 0;
    for (size_t k = 0; k < terms.size(); ++k) {
      const solvers::ResidualLoss<float> loss(*residuals[k], terms[k].weight, points[k].residual_rows());
      const TimedLoss timed_loss(loss, loss_seconds);
      field.value_and_gradient(field.parameters().data(), layouts[k],
                               autodiff::Batch<float>{x[k], nullptr, points[k].groups}, timed_loss,
                               gradient.data());
    }
    const auto passed = Clock::now();
    adam.step(field.parameters().data(), gradient.data(), schedule.learning_rate(s, stage.steps));
    const auto end = Clock::now();
    if (s < options.warmup) continue;
    const auto between = [](Clock::time_point a, Clock::time_point b) {
      return std::chrono::duration<double>(b - a).count();
    };
    timed.push_back({between(start, end), between(start, drawn), between(drawn, passed),
                     loss_seconds.load() / used_threads, between(passed, end), gemm_flops(shapes, samples),
                     samples});
  }

  Step sum{};
  std::vector<double> step_ms;
  for (const Step& t : timed) {
    sum.total += t.total, sum.sampling += t.sampling, sum.passes += t.passes;
    sum.rendering += t.rendering, sum.adam += t.adam, sum.flops += t.flops, sum.samples += t.samples;
    step_ms.push_back(1e3 * t.total);
  }
  const double n = static_cast<double>(timed.size());
  const double median_ms = median(step_ms);
  const double network = sum.passes - sum.rendering;
  const double mlp_gflops = sum.flops / network * 1e-9;
  const auto mean_samples = static_cast<Eigen::Index>(std::llround(static_cast<double>(sum.samples) / n));
  const double gemm = gemm_gflops(shapes, std::max<Eigen::Index>(mean_samples, 1), std::max(3, options.steps / 2));
  const double peak = fma_peak_gflops(used_threads, 5);
  const double step_gflop = gemm_flops(shapes, mean_samples) * 1e-9;
  const FrameTiming frame = time_frame(setup, field, options);

  char line[1536];
  std::snprintf(
      line, sizeof line,
      "{\"impl\": \"nfield\", \"bench\": \"nerf\", \"config\": \"%s\", \"rays_per_step\": %ld, "
      "\"samples_per_step\": %ld, \"steps\": %d, \"warmup\": %d, \"threads\": %d, \"block\": %ld, "
      "\"params\": %ld, \"rays_per_s\": %.1f, \"median_step_ms\": %.3f, \"sampling_ms\": %.3f, "
      "\"network_ms\": %.3f, \"rendering_ms\": %.3f, \"adam_ms\": %.3f, \"share_sampling\": %.4f, "
      "\"share_network\": %.4f, \"share_rendering\": %.4f, \"share_adam\": %.4f, \"mlp_gflops\": %.2f, "
      "\"step_gflops\": %.2f, \"gemm_gflops\": %.2f, \"mlp_gemm_ratio\": %.4f, \"fma_peak_gflops\": %.2f, "
      "\"mlp_peak_ratio\": %.4f, \"step_gflop\": %.4f, \"frame_ms\": %.2f, "
      "\"frame_pixels\": %ld, \"frame_samples\": %ld}",
      options.config.string().c_str(), rays, static_cast<long>(mean_samples), options.steps, options.warmup,
      used_threads, setup.training.block, static_cast<long>(field.parameter_count()),
      static_cast<double>(rays) / (median_ms * 1e-3), median_ms, 1e3 * sum.sampling / n, 1e3 * network / n,
      1e3 * sum.rendering / n, 1e3 * sum.adam / n, sum.sampling / sum.total, network / sum.total,
      sum.rendering / sum.total, sum.adam / sum.total, mlp_gflops, sum.flops / sum.total * 1e-9, gemm,
      mlp_gflops / gemm, peak, mlp_gflops / peak, step_gflop, frame.median_ms, static_cast<long>(frame.pixels), static_cast<long>(frame.samples));
  if (!options.json_only) {
    std::printf("%d steps after %d: %.0f rays/s, median step %.2f ms (%ld samples)\n", options.steps,
                options.warmup, static_cast<double>(rays) / (median_ms * 1e-3), median_ms,
                static_cast<long>(mean_samples));
    std::printf("  drawing rays %4.1f %%   network passes %4.1f %%   rendering loss %4.1f %%   Adam %4.1f %%\n",
                100 * sum.sampling / sum.total, 100 * network / sum.total, 100 * sum.rendering / sum.total,
                100 * sum.adam / sum.total);
    std::printf("  dense products: %.1f GFLOP/s in the network passes, %.1f over the whole step;\n"
                "  plain Eigen products of the same shapes: %.1f GFLOP/s (%.0f %%)\n",
                mlp_gflops, sum.flops / sum.total * 1e-9, gemm, 100 * mlp_gflops / gemm);
    std::printf("  the machine's float FMA peak on %d threads: %.1f GFLOP/s; the network passes use %.0f %% of it\n"
                "  (%.2f GFLOP of products a step: no implementation of this step runs faster than %.1f ms)\n",
                used_threads, peak, 100 * mlp_gflops / peak, step_gflop, 1e3 * step_gflop / peak);
    std::printf("render of a %ld-pixel view, %ld samples: %.1f ms (median of %d)\n",
                static_cast<long>(frame.pixels), static_cast<long>(frame.samples), frame.median_ms,
                options.render_repeats);
  }
  std::puts(line);
  std::fflush(stdout);
}

}  // namespace nfield::apps
