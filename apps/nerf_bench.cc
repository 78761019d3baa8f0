// SPDX-License-Identifier: MIT
#include "apps/nerf_bench.h"

#include <omp.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

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
#include "solvers/training/trainer.h"
#include "solvers/run/run.h"
#include "solvers/sampling/random.h"

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

// One timed training step: where its time went, and the products it did.
struct StepTiming {
  double total, sampling, passes, rendering, adam, flops;
  Eigen::Index samples;
};

// The trainer's loss terms of a radiance-field config, refused when they train derivative
// streams, with their layouts and batch sizes (solvers/training/trainer.cc: resample, term_loss).
struct NerfTerms {
  std::vector<solvers::LossTerm> terms;
  std::vector<autodiff::StreamLayout> layouts;
  std::vector<Eigen::Index> batch;
  long rays = 0;
};

NerfTerms nerf_terms(const solvers::RunSetup& setup, const NerfBenchOptions& options) {
  NerfTerms t{setup.problem->loss_terms(), {}, {}, 0};
  for (const solvers::LossTerm& term : t.terms) {
    if (term.spec.tangents.cols() > 0)
      throw CLI::ValidationError("--config", options.config.string() + " trains derivative streams (loss term '" +
                                                 term.name + "'); --nerf times NeRF's quadrature (for problem: "
                                                 "autoint_nerf use --autoint)");
    t.layouts.emplace_back(term.spec);
    t.batch.push_back(options.rays > 0 ? options.rays : setup.training.batch.at(term.batch_key));
    if (term.batch_key == "rays") t.rays += t.batch.back();
  }
  return t;
}

// Adam steps of the first stage on `field`, the first `options.warmup` untimed.
std::vector<StepTiming> timed_steps(const solvers::RunSetup& setup, const NerfTerms& t, fields::Field<float>& field,
                                    const NerfBenchOptions& options, int threads) {
  const std::vector<GemmShape> shapes = dense_shapes(field);
  const solvers::StageOptions& stage = setup.training.stages.front();
  const auto& schedule = stage.options<solvers::AdamStageOptions>();
  solvers::Adam<float> adam(field.parameter_count(), {schedule.lr});
  solvers::Random rng(setup.training.seed);
  const std::size_t n_terms = t.terms.size();
  std::vector<solvers::TermPoints> points(n_terms);
  std::vector<autodiff::Matrix<float>> x(n_terms);
  std::vector<std::unique_ptr<solvers::Residual>> residuals(n_terms);
  autodiff::Vector<float> gradient(field.parameter_count());
  std::atomic<double> loss_seconds{0};
  std::vector<StepTiming> timed;
  for (int s = 0; s < options.warmup + options.steps; ++s) {
    const auto start = Clock::now();
    Eigen::Index samples = 0;
    for (size_t k = 0; k < n_terms; ++k) {
      points[k] = t.terms[k].sample(rng, t.batch[k]);
      x[k] = points[k].x.cast<float>();
      residuals[k] = t.terms[k].residual(points[k]);
      samples += points[k].x.rows();
    }
    const auto drawn = Clock::now();
    gradient.setZero();
    loss_seconds = 0;
    for (size_t k = 0; k < n_terms; ++k) {
      const solvers::ResidualLoss<float> loss(*residuals[k], t.terms[k].weight, points[k].residual_rows());
      const TimedLoss timed_loss(loss, loss_seconds);
      field.value_and_gradient(field.parameters().data(), t.layouts[k],
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
                     loss_seconds.load() / threads, between(passed, end), gemm_flops(shapes, samples), samples});
  }
  return timed;
}

// The library's own training step: solvers::Trainer on the setup's problem and a field of its
// own (the same initialization), one Adam stage of warmup + steps steps, no callbacks (so
// nothing updates an occupancy grid: every step samples as timed_steps does). Returns the
// step times after the warmup, in milliseconds.
std::vector<double> trainer_step_ms(const solvers::RunSetup& setup, const NerfTerms& t,
                                    const NerfBenchOptions& options, int threads) {
  solvers::TrainingOptions training = setup.training;
  training.stages.resize(1);
  training.stages.front().steps = options.warmup + options.steps;
  training.checkpoint_every = 0;
  for (std::size_t k = 0; k < t.terms.size(); ++k) training.batch[t.terms[k].batch_key] = t.batch[k];
  fields::Field<float> field(setup.field, {setup.training.block, threads});
  solvers::Trainer<float> trainer(*setup.problem, field, training);
  trainer.run({});
  const std::vector<double>& ms = trainer.step_milliseconds();
  return {ms.begin() + std::min<std::ptrdiff_t>(options.warmup, std::ssize(ms)), ms.end()};
}

// The steps' sums and the rates that put them in proportion: the plain Eigen products of the
// same shapes and the machine's FMA peak, both measured now.
struct NerfReport {
  StepTiming sum{};
  double steps = 0, median_ms = 0, network = 0, mlp_gflops = 0, gemm = 0, peak = 0, step_gflop = 0;
  double trainer_median_ms = 0;  // the library's Trainer taking the same steps
  Eigen::Index mean_samples = 0;
};

NerfReport summarise(const std::vector<StepTiming>& timed, const std::vector<GemmShape>& shapes, int threads,
                     int steps) {
  NerfReport r;
  std::vector<double> step_ms;
  for (const StepTiming& t : timed) {
    r.sum.total += t.total, r.sum.sampling += t.sampling, r.sum.passes += t.passes;
    r.sum.rendering += t.rendering, r.sum.adam += t.adam, r.sum.flops += t.flops, r.sum.samples += t.samples;
    step_ms.push_back(1e3 * t.total);
  }
  r.steps = static_cast<double>(timed.size());
  r.median_ms = median(step_ms);
  r.network = r.sum.passes - r.sum.rendering;
  r.mlp_gflops = r.sum.flops / r.network * 1e-9;
  r.mean_samples = static_cast<Eigen::Index>(std::llround(static_cast<double>(r.sum.samples) / r.steps));
  r.gemm = gemm_gflops(shapes, std::max<Eigen::Index>(r.mean_samples, 1), std::max(3, steps / 2));
  r.peak = fma_peak_gflops(threads, 5);
  r.step_gflop = gemm_flops(shapes, r.mean_samples) * 1e-9;
  return r;
}

void print_report(const NerfReport& r, const FrameTiming& frame, const NerfBenchOptions& options, long rays) {
  const StepTiming& sum = r.sum;
  std::printf("%d steps of the trainer after %d: %.0f rays/s, median step %.2f ms (%ld samples)\n", options.steps,
              options.warmup, static_cast<double>(rays) / (r.trainer_median_ms * 1e-3), r.trainer_median_ms,
              static_cast<long>(r.mean_samples));
  std::printf("the same steps' calls timed apart (median step %.2f ms):\n", r.median_ms);
  std::printf("  drawing rays %4.1f %%   network passes %4.1f %%   rendering loss %4.1f %%   Adam %4.1f %%\n",
              100 * sum.sampling / sum.total, 100 * r.network / sum.total, 100 * sum.rendering / sum.total,
              100 * sum.adam / sum.total);
  std::printf("  dense products: %.1f GFLOP/s in the network passes, %.1f over the whole step;\n"
              "  plain Eigen products of the same shapes: %.1f GFLOP/s (%.0f %%)\n",
              r.mlp_gflops, sum.flops / sum.total * 1e-9, r.gemm, 100 * r.mlp_gflops / r.gemm);
  std::printf("  the machine's float FMA peak on %d threads: %.1f GFLOP/s; the network passes use %.0f %% of it\n"
              "  (%.2f GFLOP of products a step: no implementation of this step runs faster than %.1f ms)\n",
              omp_get_max_threads(), r.peak, 100 * r.mlp_gflops / r.peak, r.step_gflop,
              1e3 * r.step_gflop / r.peak);
  std::printf("render of a %ld-pixel view, %ld samples: %.1f ms (median of %d)\n", static_cast<long>(frame.pixels),
              static_cast<long>(frame.samples), frame.median_ms, options.render_repeats);
}

std::string json_line(const NerfReport& r, const FrameTiming& frame, const NerfBenchOptions& options, long rays,
                      const solvers::RunSetup& setup, Eigen::Index parameters) {
  const StepTiming& sum = r.sum;
  const double n = r.steps;
  char line[1536];
  std::snprintf(
      line, sizeof line,
      "{\"impl\": \"nfield\", \"bench\": \"nerf\", \"config\": \"%s\", \"rays_per_step\": %ld, "
      "\"samples_per_step\": %ld, \"steps\": %d, \"warmup\": %d, \"threads\": %d, \"block\": %ld, "
      "\"params\": %ld, \"rays_per_s\": %.1f, \"median_step_ms\": %.3f, \"anatomy_median_step_ms\": %.3f, "
      "\"sampling_ms\": %.3f, "
      "\"network_ms\": %.3f, \"rendering_ms\": %.3f, \"adam_ms\": %.3f, \"share_sampling\": %.4f, "
      "\"share_network\": %.4f, \"share_rendering\": %.4f, \"share_adam\": %.4f, \"mlp_gflops\": %.2f, "
      "\"step_gflops\": %.2f, \"gemm_gflops\": %.2f, \"mlp_gemm_ratio\": %.4f, \"fma_peak_gflops\": %.2f, "
      "\"mlp_peak_ratio\": %.4f, \"step_gflop\": %.4f, \"frame_ms\": %.2f, "
      "\"frame_pixels\": %ld, \"frame_samples\": %ld}",
      options.config.string().c_str(), rays, static_cast<long>(r.mean_samples), options.steps, options.warmup,
      omp_get_max_threads(), setup.training.block, static_cast<long>(parameters),
      static_cast<double>(rays) / (r.trainer_median_ms * 1e-3), r.trainer_median_ms, r.median_ms, 1e3 * sum.sampling / n, 1e3 * r.network / n,
      1e3 * sum.rendering / n, 1e3 * sum.adam / n, sum.sampling / sum.total, r.network / sum.total,
      sum.rendering / sum.total, sum.adam / sum.total, r.mlp_gflops, sum.flops / sum.total * 1e-9, r.gemm,
      r.mlp_gflops / r.gemm, r.peak, r.mlp_gflops / r.peak, r.step_gflop, frame.median_ms,
      static_cast<long>(frame.pixels), static_cast<long>(frame.samples));
  return line;
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
  const NerfTerms terms = nerf_terms(setup, options);
  if (!options.json_only) {
    std::printf("radiance field of %s: %ld parameters, float, %d threads, block %ld points, %ld rays a step\n",
                options.config.string().c_str(), static_cast<long>(field.parameter_count()), used_threads,
                setup.training.block, terms.rays);
    std::fflush(stdout);
  }
  const std::vector<StepTiming> timed = timed_steps(setup, terms, field, options, used_threads);
  NerfReport report = summarise(timed, dense_shapes(field), used_threads, options.steps);
  report.trainer_median_ms = median(trainer_step_ms(setup, terms, options, used_threads));
  const FrameTiming frame = time_frame(setup, field, options);
  if (!options.json_only) print_report(report, frame, options, terms.rays);
  std::puts(json_line(report, frame, options, terms.rays, setup, field.parameter_count()).c_str());
  std::fflush(stdout);
}

}  // namespace nfield::apps
