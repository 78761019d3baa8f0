// SPDX-License-Identifier: MIT
//
// `nfield bench --accuracy`: runs the accuracy table, one ready config per case
// (configs/accuracy_CASE.yaml), and prints for each the relative L2 error after every
// optimizer stage, so the gain of each stage shows, the wall time, and whether the case met
// its error and time targets. Ends with one JSON line per case:
//   {"case", "rel_l2", "rel_l2_after_adam", "wall_s", "target_rel_l2", "target_wall_s", "stages"}
// Each run writes its usual outputs under OUT/CASE.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

struct AccuracyCase {
  std::string name;       // config file: accuracy_NAME.yaml
  double target_rel_l2;   // the figure to reach
  double target_wall_s;   // on the 2-core reference machine
};

// The table, in order.
const std::vector<AccuracyCase>& accuracy_cases();

struct AccuracyOptions {
  std::vector<std::string> cases;          // empty: all
  std::filesystem::path configs = "configs";
  std::filesystem::path out = "out/accuracy";
  std::vector<std::string> overrides;      // --set applied to every case
};

// Runs the cases; returns 0, or 130 when interrupted.
int run_accuracy_bench(const AccuracyOptions& options);

}  // namespace nfield::apps
