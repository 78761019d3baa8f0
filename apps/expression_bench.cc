// SPDX-License-Identifier: MIT
#include "apps/expression_bench.h"

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/gemm_rate.h"
#include "fields/field.h"
#include "io/expression.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"

namespace nfield::apps {
namespace {

using Clock = std::chrono::steady_clock;

struct Timing {
  double step_ms = 0, expression_ms = 0;  // per step
};

// One Adam stage from the config's initial field, every expression through muparser
// (interpreted) or, where its text allows, the compiled form.
template <typename Scalar>
Timing train_once(const solvers::RunSetup& setup, int steps, bool interpreted) {
  fields::Field<Scalar> field(setup.field);
  solvers::Trainer<Scalar> trainer(*setup.problem, field, setup.training);
  const io::ExpressionTiming timing(interpreted);
  const auto start = Clock::now();
  trainer.run({});
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  const double expression_ms = 1e3 * timing.seconds();
  return {ms / steps, expression_ms / steps};
}

struct Row {
  Timing muparser, compiled;
};

template <typename Scalar>
Row time_case(const ExpressionBenchOptions& options, const solvers::RunSetup& setup) {
  std::vector<double> mu_step, mu_expr, c_step, c_expr;
  for (int r = 0; r < options.rounds; ++r) {
    const Timing mu = train_once<Scalar>(setup, options.steps, true);
    const Timing c = train_once<Scalar>(setup, options.steps, false);
    mu_step.push_back(mu.step_ms), mu_expr.push_back(mu.expression_ms);
    c_step.push_back(c.step_ms), c_expr.push_back(c.expression_ms);
  }
  return {{median(mu_step), median(mu_expr)}, {median(c_step), median(c_expr)}};
}

}  // namespace

void run_expression_bench(const ExpressionBenchOptions& options) {
  std::vector<std::string> lines;
  if (!options.json_only)
    std::printf("Adam step (new points each step), expressions through muparser per point against the compiled "
                "block form\n%-18s %12s %9s %12s %9s %7s\n",
                "case", "muparser ms", "share", "compiled ms", "share", "ratio");
  for (const std::string& name : options.cases) {
    std::vector<std::string> overrides{
        "training.stages=[{optimizer: adam, steps: " + std::to_string(options.steps) + ", lr: 1.0e-3}]"};
    if (options.threads > 0) overrides.push_back("training.threads=" + std::to_string(options.threads));
    overrides.insert(overrides.end(), options.overrides.begin(), options.overrides.end());
    const solvers::RunSetup setup = solvers::load_run(options.configs / (name + ".yaml"), overrides);
    const Row row = setup.training.precision == "double" ? time_case<double>(options, setup)
                                                         : time_case<float>(options, setup);
    const double mu_share = row.muparser.expression_ms / row.muparser.step_ms;
    const double c_share = row.compiled.expression_ms / row.compiled.step_ms;
    const double ratio = row.muparser.step_ms / row.compiled.step_ms;
    int threads = setup.training.threads;
    if (threads == 0) threads = omp_get_max_threads();  // training.threads 0: all cores
    if (!options.json_only) {
      std::printf("%-18s %12.3f %8.1f%% %12.3f %8.1f%% %7.3f\n", name.c_str(), row.muparser.step_ms, 100 * mu_share,
                  row.compiled.step_ms, 100 * c_share, ratio);
      std::fflush(stdout);
    }
    char line[640];
    std::snprintf(line, sizeof line,
                  "{\"case\": \"%s\", \"steps\": %d, \"rounds\": %d, \"threads\": %d, \"muparser_step_ms\": %.4f, "
                  "\"muparser_expression_share\": %.4f, \"compiled_step_ms\": %.4f, "
                  "\"compiled_expression_share\": %.4f, \"step_ratio\": %.4f}",
                  name.c_str(), options.steps, options.rounds, threads, row.muparser.step_ms, mu_share,
                  row.compiled.step_ms, c_share, ratio);
    lines.push_back(line);
    if (options.json_only) std::puts(line), std::fflush(stdout);
  }
  if (!options.json_only)
    for (const std::string& line : lines) std::puts(line.c_str());
}

}  // namespace nfield::apps
