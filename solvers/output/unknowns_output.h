// SPDX-License-Identifier: MIT
//
// What a run reports of its unknown constants (solvers/core/unknowns.h):
//
//   metrics.json   unknowns: {nu: {value, initial, true, rel_error, trajectory: [[step, value], …]}}
//                  (true and rel_error = |value − true| / |true| where the config gives the
//                  truth; the trajectory every K steps, K = total steps / 500 or 1, and the
//                  first step)
//   unknowns.png   one panel per unknown: its trajectory over the steps (blue) and, with a
//                  truth, the truth as a flat line (orange); no text (io/line_plot.h), so the
//                  docs name the colours.
#pragma once

#include <filesystem>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "solvers/core/unknowns.h"

namespace nfield::solvers {

// A trajectory: the steps sampled and the values then (steps × unknowns).
struct UnknownTrajectory {
  std::vector<long> steps;
  Eigen::MatrixXd values;
};

nlohmann::ordered_json unknowns_metrics(const UnknownConstants& unknowns, const UnknownTrajectory& trajectory);
// Writes the plot (nothing with fewer than two samples).
void write_unknowns_plot(const std::filesystem::path& path, const UnknownConstants& unknowns,
                         const UnknownTrajectory& trajectory);
// One line for the terminal: "unknowns: nu 0.003185 (true 0.003183, 0.06 %)".
std::string unknowns_line(const UnknownConstants& unknowns);

}  // namespace nfield::solvers
