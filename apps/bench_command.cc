// SPDX-License-Identifier: MIT
#include "apps/bench_command.h"

#include <malloc.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <iostream>
#include <string>
#include <vector>

#include "apps/accuracy_bench.h"
#include "apps/autoint_bench.h"
#include "apps/expression_bench.h"
#include "apps/gemm_rate.h"
#include "apps/nerf_bench.h"
#include "apps/problem_bench.h"
#include "autodiff/small_gemm.h"
#include "fields/field.h"
#include "solvers/training/adam.h"

namespace nfield::apps {
namespace {

using Clock = std::chrono::steady_clock;
using MatrixF = autodiff::Matrix<float>;

struct BenchOptions {
  std::vector<std::string> ops{"laplacian", "wave"};
  std::vector<long> batches{1024, 4096, 16384};
  std::vector<int> hidden{256, 256, 256, 256};
  int steps = 10;
  int warmup = 2;
  int threads = 0;
  long block = 128;
  bool json_only = false;
  // --widths: the table once per width w, every hidden layer w wide (as many as --hidden has).
  std::vector<int> widths;
  // --thread-counts: the table once per thread count (0: all), each with its own FMA peak.
  std::vector<int> thread_counts;
};

// Peak resident memory since the last reset_peak_rss(), in MiB (Linux /proc).
void reset_peak_rss() { std::ofstream("/proc/self/clear_refs") << "5"; }
double peak_rss_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

// The operator a benchmark step trains: which streams, and how the residual reads them.
struct Operator {
  int dims;
  autodiff::StreamSpec spec;
  std::vector<std::pair<int, float>> residual;  // Σ weight · stream, then minus the source
};

Operator make_operator(const std::string& name) {
  if (name == "laplacian") {
    Operator op{2, autodiff::StreamSpec::laplacian(2), {}};
    op.residual = {{3, 1.0f}};
    return op;
  }
  if (name == "wave") {
    Operator op{3, autodiff::StreamSpec::gradient(3), {}};
    op.spec.add_operator(Eigen::Vector3d(-1.0, -1.0, 1.0).asDiagonal().toDenseMatrix());
    op.residual = {{4, 1.0f}};
    return op;
  }
  if (name == "biharmonic") {
    // Δ²u from Taylor series of order 4 along three directions 60° apart (13 streams; the
    // axis-and-diagonal polarization needs 17): Δ²u = (64/3) Σₚ z_{p,4}.
    Operator op{2, autodiff::StreamSpec::values(2), {}};
    op.spec.set_taylor(autodiff::biharmonic_directions_2d(), 4);
    const autodiff::StreamLayout layout(op.spec);
    const float weight = static_cast<float>(autodiff::kBiharmonic2dWeight);
    for (int p = 0; p < 3; ++p) op.residual.push_back({layout.taylor(p, 4), weight});
    return op;
  }
  throw CLI::ValidationError("--op", "unknown operator '" + name +
                                         "' (valid: laplacian, wave, biharmonic)");
}

// Floating-point operations of the matrix products in one step.
double step_flops(const fields::Field<float>& field, long batch, int streams) {
  double flops = 0;
  const auto& modules = field.network().modules();
  for (size_t m = 0; m < modules.size(); ++m) {
    if (modules[m]->parameter_count() == 0) continue;
    const double shape = 2.0 * batch * streams * modules[m]->input_width() * modules[m]->output_width();
    flops += m == 0 ? 2 * shape : 3 * shape;  // forward, W̄, and Ā except for the first layer
  }
  return flops;
}

// The same products at the full batch size with plain Eigen (apps/gemm_rate.h). Returns GFLOP/s.
double gemm_gflops(const fields::Field<float>& field, long batch, int streams, int repeats) {
  std::vector<GemmShape> shapes;
  const auto& modules = field.network().modules();
  for (size_t m = 0; m < modules.size(); ++m)
    if (modules[m]->parameter_count() > 0)
      shapes.push_back({modules[m]->input_width(), modules[m]->output_width(), m != 0});
  return apps::gemm_gflops(shapes, batch * streams, repeats);
}

struct StepResult {
  double median_ms, gflops, gemm_gflops, peak_mb;
};

StepResult bench_step(const BenchOptions& options, const std::string& op_name, long batch) {
  Operator op = make_operator(op_name);
  const autodiff::StreamLayout layout(op.spec);
  fields::FieldOptions field_options;
  field_options.input_dim = op.dims;
  field_options.hidden = options.hidden;
  malloc_trim(0);  // what earlier configurations freed does not count as this one's peak
  reset_peak_rss();
  fields::Field<float> field(field_options, {options.block, options.threads});
  solvers::Adam<float> adam(field.parameter_count(), {1e-5});
  const MatrixF x = MatrixF::Random(batch, op.dims);
  const autodiff::Vector<float> source = autodiff::Vector<float>::Random(batch);
  const float scale = 2.0f / static_cast<float>(batch);
  // mean((L u − f)²): the adjoint is 2 r / N on each stream the residual reads.
  autodiff::LambdaLoss<float> loss([&](Eigen::Index first, const autodiff::StreamLayout&,
                                       const autodiff::Streams<float>& out,
                                       autodiff::Streams<float>& adjoint) {
    autodiff::Vector<float> r = -source.segment(first, out.points);
    for (const auto& [stream, weight] : op.residual) r += weight * out.stream(stream).col(0);
    for (const auto& [stream, weight] : op.residual) adjoint.stream(stream).col(0) = (scale * weight) * r;
    return static_cast<double>(r.squaredNorm()) / batch;
  });
  autodiff::Vector<float> gradient(field.parameter_count());
  auto step = [&] {
    gradient.setZero();
    field.network().value_and_gradient(field.parameters().data(), layout, x, loss, gradient.data());
    adam.step(field.parameters().data(), gradient.data());
  };
  std::vector<double> ms;
  for (int s = 0; s < options.warmup + options.steps; ++s) {
    const auto start = Clock::now();
    step();
    if (s >= options.warmup)
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  StepResult result;
  result.median_ms = median(ms);
  result.peak_mb = peak_rss_mb();
  result.gflops = step_flops(field, batch, layout.count()) / (result.median_ms * 1e-3) * 1e-9;
  result.gemm_gflops = gemm_gflops(field, batch, layout.count(), std::max(3, options.steps / 2));
  return result;
}

// One table: every operator and batch at options.hidden on the threads set now, with its
// share of `peak`, the float FMA peak (apps/gemm_rate.h) measured on those threads.
void run_table(const BenchOptions& options, double peak, std::vector<std::string>& lines) {
  const int threads = omp_get_max_threads();
  std::string widths;
  for (int h : options.hidden) widths += (widths.empty() ? "" : "x") + std::to_string(h);
  if (!options.json_only)
    std::printf("SIREN %s, float (layer products: %s), %d threads, block %ld points, FMA peak %.1f GFLOP/s\n"
                "%-11s %4s %7s %12s %9s %10s %7s %7s %9s\n",
                widths.c_str(), autodiff::small_gemm_kernel_name(), threads, options.block, peak, "op", "dims",
                "batch", "step ms", "GFLOP/s", "GEMM GF/s", "ratio", "peak", "peak MB");
  for (const std::string& op : options.ops)
    for (long batch : options.batches) {
      const StepResult r = bench_step(options, op, batch);
      const int dims = make_operator(op).dims;
      if (!options.json_only) {
        std::printf("%-11s %4d %7ld %12.2f %9.1f %10.1f %6.0f%% %6.0f%% %9.0f\n", op.c_str(), dims, batch,
                    r.median_ms, r.gflops, r.gemm_gflops, 100 * r.gflops / r.gemm_gflops, 100 * r.gflops / peak,
                    r.peak_mb);
        std::fflush(stdout);
      }
      char line[640];
      std::snprintf(line, sizeof line,
                    "{\"impl\": \"nfield\", \"op\": \"%s\", \"dims\": %d, \"batch\": %ld, \"hidden\": \"%s\", "
                    "\"median_step_ms\": %.3f, \"gflops\": %.2f, \"gemm_gflops\": %.2f, "
                    "\"fma_peak_gflops\": %.2f, \"peak_share\": %.4g, \"peak_rss_mb\": %.1f, \"threads\": %d}",
                    op.c_str(), dims, batch, widths.c_str(), r.median_ms, r.gflops, r.gemm_gflops, peak,
                    r.gflops / peak, r.peak_mb, threads);
      lines.push_back(line);
      if (options.json_only) std::puts(line), std::fflush(stdout);
    }
}

void run_bench(const BenchOptions& options) {
  std::vector<std::string> lines;
  const int all = omp_get_max_threads();
  std::vector<int> thread_counts = options.thread_counts;
  if (thread_counts.empty()) thread_counts.push_back(options.threads);
  for (int threads : thread_counts) {
    omp_set_num_threads(threads > 0 ? threads : all);
    const double peak = fma_peak_gflops(omp_get_max_threads(), 5);
    if (options.widths.empty()) {
      run_table(options, peak, lines);
      continue;
    }
    for (int width : options.widths) {
      BenchOptions one = options;
      one.hidden.assign(options.hidden.size(), width);
      run_table(one, peak, lines);
    }
  }
  omp_set_num_threads(all);
  if (!options.json_only)
    for (const std::string& line : lines) std::puts(line.c_str());
}

// Everything the subcommand's options write into, shared with its callback.
struct BenchModes {
  std::shared_ptr<BenchOptions> step = std::make_shared<BenchOptions>();
  std::shared_ptr<AccuracyOptions> accuracy = std::make_shared<AccuracyOptions>();
  std::shared_ptr<NerfBenchOptions> nerf = std::make_shared<NerfBenchOptions>();
  std::shared_ptr<AutointBenchOptions> autoint = std::make_shared<AutointBenchOptions>();
  std::shared_ptr<ProblemBenchOptions> problems = std::make_shared<ProblemBenchOptions>();
  std::shared_ptr<ExpressionBenchOptions> expressions = std::make_shared<ExpressionBenchOptions>();
  std::shared_ptr<std::filesystem::path> autoint_out = std::make_shared<std::filesystem::path>(autoint->out);
  // --accuracy, --no-fail, --nerf, --autoint, --no-grid, --problems, --expressions.
  std::shared_ptr<bool> accuracy_flag = std::make_shared<bool>(false), no_fail = std::make_shared<bool>(false),
                        nerf_flag = std::make_shared<bool>(false), autoint_flag = std::make_shared<bool>(false),
                        no_grid = std::make_shared<bool>(false), problems_flag = std::make_shared<bool>(false),
                        expressions_flag = std::make_shared<bool>(false);
};

// The step timing of the SIREN reference network (the default mode).
void add_step_options(CLI::App* bench, const BenchModes& m) {
  bench->add_option("--op", m.step->ops, "Operators: laplacian (2D), wave (x, y, t), biharmonic (2D)")
      ->check(CLI::IsMember({"laplacian", "wave", "biharmonic"}))
      ->capture_default_str();
  bench->add_option("--batch", m.step->batches, "Batch sizes")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench->add_option("--hidden", m.step->hidden, "Hidden widths")->check(CLI::PositiveNumber)->capture_default_str();
  bench->add_option("--steps", m.step->steps, "Timed steps per configuration (--nerf: 20 unless given)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  bench->add_option("--warmup", m.step->warmup, "Untimed steps first (--nerf: 3 unless given)")->check(CLI::Range(0, 1000))->capture_default_str();
  bench->add_option("--threads", m.step->threads, "Threads (0: all)")->check(CLI::Range(0, 1024))->capture_default_str();
  bench->add_option("--block", m.step->block,
                    "Points per block of the chunked pass (--nerf: replaces the config's training.block)")
      ->check(CLI::Range(1L, 1L << 20))
      ->capture_default_str();
  bench->add_option("--widths", m.step->widths,
                    "The table once per width: every hidden layer this wide (as many layers as --hidden)")
      ->check(CLI::Range(1, 4096));
  bench->add_option("--thread-counts", m.step->thread_counts,
                    "The table once per thread count (0: all), each with the FMA peak of its threads "
                    "(e.g. --thread-counts 1 0); replaces --threads")
      ->check(CLI::Range(0, 1024));
  bench->add_flag("--json", m.step->json_only, "Print only the JSON lines");
}

void add_accuracy_options(CLI::App* bench, const BenchModes& m) {
  bench->add_flag("--accuracy", *m.accuracy_flag,
                  "Run the accuracy table instead (apps/accuracy_bench.cc: the PDE cases' "
                  "configs/accuracy_CASE.yaml and the SIREN experiments' configs): each case's figure "
                  "(rel_l2 after each optimizer stage, PSNR, Chamfer distance), wall time, targets");
  bench->add_option("--cases", m.accuracy->cases, "--accuracy: the cases to run (default: all)");
  bench->add_option("--configs", m.accuracy->configs, "--accuracy: folder of the cases' configs")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
  bench->add_option("--out", m.accuracy->out, "--accuracy: output folder, one subfolder per case")
      ->capture_default_str();
  bench->add_flag("--no-fail", *m.no_fail,
                  "--accuracy: exit 0 even when a case misses its target (default: exit code 4, after a "
                  "line naming the cases that missed)");
  bench->add_option("--set", m.accuracy->overrides,
                    "--accuracy, --nerf, --autoint, --expressions: override a value in every case's config, in the --nerf "
                    "config, or in every --autoint run's config");
}

void add_nerf_options(CLI::App* bench, const BenchModes& m) {
  bench->add_flag("--nerf", *m.nerf_flag,
                  "Time radiance-field training (rays/s: ray sampling, network passes, volume rendering "
                  "and its adjoint, Adam) and the render of a test view instead")
      ->excludes("--accuracy");
  bench->add_option("--config", m.nerf->config, "--nerf: the radiance-field config")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  bench->add_option("--rays", m.nerf->rays, "--nerf: rays per step (0: the config's training.batch.rays)")
      ->check(CLI::Range(0L, 1L << 24))
      ->capture_default_str();
  bench->add_option("--render-stride", m.nerf->render_stride,
                    "--nerf: render every k-th pixel of every k-th row of the test view")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  bench->add_option("--render-repeats", m.nerf->render_repeats, "--nerf: timed renders of the test view")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
}

void add_autoint_options(CLI::App* bench, const BenchModes& m) {
  bench->add_flag("--autoint", *m.autoint_flag,
                  "Train AutoInt volume rendering at K sections per ray and NeRF quadrature for the same "
                  "time each, then compare test PSNR and render time per frame")
      ->excludes("--accuracy")
      ->excludes("--nerf");
  bench->add_option("--seconds", m.autoint->seconds, "--autoint: seconds of training per run")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();
  bench->add_option("--sections", m.autoint->sections, "--autoint: the section counts K to train")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  bench->add_option("--nerf-samples", m.autoint->nerf_samples, "--autoint: samples per ray of the NeRF reference")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  bench->add_option("--train-samples", m.autoint->samples_per_ray,
                    "--autoint: AutoInt training samples per ray, spread over the K sections")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  bench->add_option("--autoint-config", m.autoint->autoint_config, "--autoint: the AutoInt config")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  bench->add_option("--nerf-config", m.autoint->nerf_config, "--autoint: the NeRF reference config (no occupancy grid)")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  bench->add_option("--grid-config", m.autoint->grid_config, "--autoint: the NeRF config with an occupancy grid")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  bench->add_option("--sampler", m.autoint->sampler,
                    "--autoint: AutoInt runs with equal sections (off), with the sampling network (on), or both")
      ->check(CLI::IsMember({"both", "off", "on"}))
      ->capture_default_str();
  bench->add_flag("--no-grid", *m.no_grid, "--autoint: leave out the occupancy-grid NeRF");
  bench->add_option("--autoint-out", *m.autoint_out, "--autoint: output folder, one subfolder per run")
      ->capture_default_str();
}

void add_problem_options(CLI::App* bench, const BenchModes& m) {
  bench->add_flag("--problems", *m.problems_flag,
                  "Time a training step (loss and gradient) of built-in problem configs against their "
                  "`problem: pde` restatements (CASE.yaml, CASE_pde.yaml) in the same run, at each --batch "
                  "interior points (default 4096), and print the ratio")
      ->excludes("--accuracy")
      ->excludes("--nerf")
      ->excludes("--autoint");
  bench->add_option("--pde-cases", m.problems->cases, "--problems: the cases (CASE.yaml and CASE_pde.yaml)")
      ->capture_default_str();
  bench->add_option("--pde-configs", m.problems->configs, "--problems: folder of the cases' configs")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
}

void add_expression_options(CLI::App* bench, const BenchModes& m) {
  bench->add_flag("--expressions", *m.expressions_flag,
                  "Time Adam steps of configs with every config expression through muparser per point against "
                  "the compiled block form, in the same run, and print each one's share of the step "
                  "(--steps per round, default 50; --threads, default 1; --set)")
      ->excludes("--accuracy")
      ->excludes("--nerf")
      ->excludes("--autoint")
      ->excludes("--problems");
  bench->add_option("--expression-cases", m.expressions->cases, "--expressions: the cases (CASE.yaml)")
      ->capture_default_str();
  bench->add_option("--expression-configs", m.expressions->configs, "--expressions: folder of the cases' configs")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
  bench->add_option("--rounds", m.expressions->rounds, "--expressions: rounds of both evaluators (median)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
}

void run_selected(const CLI::App* bench, const BenchModes& m) {
  if (*m.expressions_flag) {
    if (bench->count("--steps") > 0) m.expressions->steps = m.step->steps;
    if (bench->count("--threads") > 0) m.expressions->threads = m.step->threads;
    m.expressions->json_only = m.step->json_only;
    m.expressions->overrides = m.accuracy->overrides;
    return run_expression_bench(*m.expressions);
  }
  if (*m.problems_flag) {
    if (bench->count("--batch") > 0) m.problems->batches = m.step->batches;
    m.problems->steps = m.step->steps;
    m.problems->warmup = m.step->warmup;
    m.problems->threads = m.step->threads;
    m.problems->json_only = m.step->json_only;
    return run_problem_bench(*m.problems);
  }
  if (*m.autoint_flag) {
    m.autoint->with_grid = !*m.no_grid;
    m.autoint->out = *m.autoint_out;
    m.autoint->overrides = m.accuracy->overrides;
    const int code = run_autoint_bench(*m.autoint);
    if (code != 0) throw CLI::RuntimeError(code);
    return;
  }
  if (*m.nerf_flag) {
    // Steps of a radiance field are long and vary with the rays drawn: more of them by default.
    if (bench->count("--steps") > 0) m.nerf->steps = m.step->steps;
    if (bench->count("--warmup") > 0) m.nerf->warmup = m.step->warmup;
    m.nerf->threads = m.step->threads;
    m.nerf->json_only = m.step->json_only;
    m.nerf->overrides = m.accuracy->overrides;
    // After the --set overrides, so that --block wins over a --set training.block.
    if (bench->count("--block") > 0) m.nerf->overrides.push_back("training.block=" + std::to_string(m.step->block));
    return run_nerf_bench(*m.nerf);
  }
  if (!*m.accuracy_flag) return run_bench(*m.step);
  m.accuracy->fail_on_miss = !*m.no_fail;
  const int code = run_accuracy_bench(*m.accuracy);
  if (code != 0) throw CLI::RuntimeError(code);
}

}  // namespace

void add_bench_command(CLI::App& app) {
  CLI::App* bench = app.add_subcommand(
      "bench", "Time full training steps (streams, reverse pass, Adam) of the SIREN reference "
               "network against the matrix-product rate measured in the same run");
  const BenchModes modes;
  add_step_options(bench, modes);
  add_accuracy_options(bench, modes);
  add_nerf_options(bench, modes);
  add_autoint_options(bench, modes);
  add_problem_options(bench, modes);
  add_expression_options(bench, modes);
  bench->callback([bench, modes] { run_selected(bench, modes); });
}

}  // namespace nfield::apps
