// SPDX-License-Identifier: MIT
//
// `nfield bench --problems`: one training step (the loss over every term and its gradient,
// Trainer::loss_and_gradient_at) of a built-in problem's config and of its `problem: pde`
// restatement (CONFIG_pde.yaml beside it), at the same interior batch, measured in the same
// run, and the ratio pde / built-in (issue 24 item 8: at most 1.25 at batch 4096).
//
// Both trainers are built first; then the steps alternate (built-in, pde, built-in, …) so
// that a busy machine slows both alike, and each side reports its median. The step is what
// every optimizer repeats: the streams' forward pass, the residuals and their adjoints, the
// reverse pass; the optimizer's update is the same for both and left out. Each config keeps
// its own precision, field and other batch kinds (boundary, initial); the interior batch is
// --batch.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

struct ProblemBenchOptions {
  std::vector<std::string> cases{"poisson_2d", "helmholtz_2d", "wave_1d"};  // CASE.yaml, CASE_pde.yaml
  std::filesystem::path configs = "configs";
  std::vector<long> batches{4096};  // interior points
  int steps = 10;
  int warmup = 2;
  int threads = 0;                  // 0: the configs' training.threads
  bool json_only = false;
};

// Prints a table (case, batch, built-in ms, pde ms, ratio), then one JSON line per row:
//   {"case", "batch", "precision", "builtin_step_ms", "pde_step_ms", "ratio", "threads"}
void run_problem_bench(const ProblemBenchOptions& options);

}  // namespace nfield::apps
