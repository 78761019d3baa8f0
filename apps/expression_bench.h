// SPDX-License-Identifier: MIT
//
// `nfield bench --expressions`: the share of an Adam step spent evaluating config
// expressions (condition values and the hard-condition ansatz's A with its finite-difference
// stencil, sources, soft targets), with every expression through muparser point by point
// against the compiled block form where a text allows it (io/expression.h), in the same run.
//
// Each case's config trains one Adam stage of --steps steps (new points every step, as the
// configs' Adam stages do; the config's other stages dropped) from the same initial field,
// once per evaluator, alternating the two for --rounds rounds so that a busy machine slows
// both alike; each side reports its median over the rounds. The step is the whole step the
// trainer times (drawing points, building the residuals, loss and gradient, the update);
// the expression time is the wall time inside io::Expression::evaluate during those steps
// (io::ExpressionTiming). Outputs are not written.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

struct ExpressionBenchOptions {
  // CASE.yaml under `configs`: hard conditions in 2-D and 1-D, a soft time-varying
  // Dirichlet value with a hard initial value, a Gaussian source, soft initial conditions.
  std::vector<std::string> cases{"accuracy_wave_2d", "accuracy_wave_1d", "heat_disk", "helmholtz_pml", "wave_1d"};
  std::filesystem::path configs = "configs";
  int steps = 50;    // Adam steps per round and evaluator
  int rounds = 3;
  int threads = 1;   // training.threads of every run (0: the configs' own)
  std::vector<std::string> overrides;  // --set, after the bench's own
  bool json_only = false;
};

// Prints a table (case, ms/step and expression share with muparser, the same compiled, the
// step ratio), then one JSON line per case:
//   {"case", "steps", "rounds", "threads", "muparser_step_ms", "muparser_expression_share",
//    "compiled_step_ms", "compiled_expression_share", "step_ratio"}
void run_expression_bench(const ExpressionBenchOptions& options);

}  // namespace nfield::apps
