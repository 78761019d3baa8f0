// SPDX-License-Identifier: MIT
//
// `nfield bench --accuracy`: runs the accuracy table, one ready config per case, and prints
// for each its figure against the target (rel_l2 for the PDE cases, with the error after
// every optimizer stage so the gain of each stage shows; PSNR, Chamfer distance or the
// worst frame's error for the others), the wall time, and whether the case met all its
// targets. Ends with one JSON line per case, then a line naming the cases that missed:
//   {"case", "metric", "value", "target", "met", "criteria", "rel_l2", "rel_l2_after_adam",
//    ["sign_accuracy", "sign_accuracy_band",] "wall_s", "target_wall_s", "stages"}
// (the sign shares where metrics.json has them: an SDF case with a reference mesh).
// Each run writes its usual outputs under OUT/CASE.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

// One figure of metrics.json against its target.
struct AccuracyCriterion {
  std::string metric;     // a key of metrics.json
  double target = 0;
  bool at_least = false;  // true: metric >= target (PSNR, shares); false: metric <= target
};

struct AccuracyCase {
  std::string name;                        // --cases NAME
  std::string config;                      // CONFIG.yaml in the configs folder
  std::vector<AccuracyCriterion> criteria;  // all must hold; the first is the case's figure
  double target_wall_s = 0;                // on the 2-core reference machine
};

// The table, in order.
const std::vector<AccuracyCase>& accuracy_cases();

struct AccuracyOptions {
  std::vector<std::string> cases;          // empty: all
  std::filesystem::path configs = "configs";  // the folder of the cases' configs
  std::filesystem::path out = "out/accuracy";
  std::vector<std::string> overrides;      // --set applied to every case
  bool fail_on_miss = true;                // false: --no-fail, exit 0 whatever the figures
};

// The exit code when a case misses a target (its figure, its wall time, or it did not finish).
inline constexpr int kExitTargetsMissed = 4;

// Runs the cases; returns 0 when every case met its targets, kExitTargetsMissed when one
// missed (after a summary line naming them), or 130 when interrupted.
int run_accuracy_bench(const AccuracyOptions& options);

}  // namespace nfield::apps
