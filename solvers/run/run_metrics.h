// SPDX-License-Identifier: MIT
//
// metrics.json of a finished, interrupted or diverged run (docs/config.md, "metrics.json"):
// how it stopped, steps, wall time, losses per term, each stage's end, loss, error and time,
// the grid's errors (per output, per frame, per held-out parameter), the domain's measure,
// MPI volume, and the strategies' and the problem's own figures (`extra`).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fields/field.h"
#include "solvers/output/grid_output.h"
#include "solvers/run/run_setup.h"
#include "solvers/training/communicator.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {

template <typename Scalar>
nlohmann::ordered_json run_metrics(const RunSetup& setup, Trainer<Scalar>& trainer, const fields::Field<Scalar>& field,
                                   bool finished, double wall, const GridMetrics& grid,
                                   const std::vector<std::pair<std::string, double>>& extra, long first_step,
                                   Communicator& communicator);

// metrics.json of `nfield eval`: the grid's errors and the problem's own figures (`extra`:
// a reference.file's per-output errors), under the keys run_metrics gives them, so that the
// two files compare key by key.
nlohmann::ordered_json eval_metrics(const RunSetup& setup, const GridMetrics& grid,
                                    const std::vector<std::pair<std::string, double>>& extra);

// dir/metrics.json, indented, written atomically (a reader never sees half a file).
void write_metrics_json(const std::filesystem::path& dir, const nlohmann::ordered_json& metrics);

}  // namespace nfield::solvers
