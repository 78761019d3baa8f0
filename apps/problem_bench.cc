// SPDX-License-Identifier: MIT
#include "apps/problem_bench.h"

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "apps/gemm_rate.h"
#include "fields/field.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"

namespace nfield::apps {
namespace {

using Clock = std::chrono::steady_clock;

// One side of a row: the config's problem, field and trainer, ready to step.
template <typename Scalar>
struct Side {
  solvers::RunSetup setup;
  std::unique_ptr<fields::Field<Scalar>> field;
  std::unique_ptr<solvers::Trainer<Scalar>> trainer;
  std::vector<Scalar> gradient;
  std::vector<double> ms;

  Side(const std::filesystem::path& config, const std::vector<std::string>& overrides)
      : setup(solvers::load_run(config, overrides)) {
    field = std::make_unique<fields::Field<Scalar>>(setup.field);
    trainer = std::make_unique<solvers::Trainer<Scalar>>(*setup.problem, *field, setup.training);
    gradient.resize(static_cast<size_t>(field->parameter_count()));
  }
  void step(bool timed) {
    const auto start = Clock::now();
    trainer->loss_and_gradient_at(field->parameters().data(), gradient.data());
    if (timed) ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
};

struct Row {
  double builtin_ms, pde_ms;
};

template <typename Scalar>
Row time_pair(const ProblemBenchOptions& options, const std::filesystem::path& builtin_config,
              const std::filesystem::path& pde_config, const std::vector<std::string>& overrides) {
  Side<Scalar> builtin(builtin_config, overrides), pde(pde_config, overrides);
  for (int s = 0; s < options.warmup + options.steps; ++s) {
    builtin.step(s >= options.warmup);
    pde.step(s >= options.warmup);
  }
  return {median(builtin.ms), median(pde.ms)};
}

}  // namespace

void run_problem_bench(const ProblemBenchOptions& options) {
  std::vector<std::string> lines;
  if (!options.json_only)
    std::printf("training step (loss and gradient), built-in problem against its problem: pde restatement\n"
                "%-14s %7s %9s %12s %12s %7s\n", "case", "batch", "precision", "built-in ms", "pde ms", "ratio");
  for (const std::string& name : options.cases)
    for (long batch : options.batches) {
      const std::filesystem::path builtin_config = options.configs / (name + ".yaml");
      const std::filesystem::path pde_config = options.configs / (name + "_pde.yaml");
      std::vector<std::string> overrides{"training.batch.interior=" + std::to_string(batch)};
      if (options.threads > 0) overrides.push_back("training.threads=" + std::to_string(options.threads));
      const std::string precision = solvers::load_run(builtin_config, overrides).training.precision;
      if (solvers::load_run(pde_config, overrides).training.precision != precision)
        throw std::runtime_error(pde_config.string() + " trains in another precision than " + builtin_config.string());
      const Row row = precision == "double"
                          ? time_pair<double>(options, builtin_config, pde_config, overrides)
                          : time_pair<float>(options, builtin_config, pde_config, overrides);
      const double ratio = row.pde_ms / row.builtin_ms;
      int threads = solvers::load_run(builtin_config, overrides).training.threads;
      if (threads == 0) threads = omp_get_max_threads();  // training.threads 0: all cores
      if (!options.json_only) {
        std::printf("%-14s %7ld %9s %12.2f %12.2f %7.3f\n", name.c_str(), batch, precision.c_str(), row.builtin_ms,
                    row.pde_ms, ratio);
        std::fflush(stdout);
      }
      char line[512];
      std::snprintf(line, sizeof line,
                    "{\"case\": \"%s\", \"batch\": %ld, \"precision\": \"%s\", \"builtin_step_ms\": %.3f, "
                    "\"pde_step_ms\": %.3f, \"ratio\": %.4f, \"threads\": %d}",
                    name.c_str(), batch, precision.c_str(), row.builtin_ms, row.pde_ms, ratio, threads);
      lines.push_back(line);
      if (options.json_only) std::puts(line), std::fflush(stdout);
    }
  if (!options.json_only)
    for (const std::string& line : lines) std::puts(line.c_str());
}

}  // namespace nfield::apps
