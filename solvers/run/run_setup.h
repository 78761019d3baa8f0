// SPDX-License-Identifier: MIT
//
// What `nfield run` reads from a config before it trains (solvers/run/run.h, load_run): its own
// header so that the drivers of other kinds of runs (solvers/run/meta_run.h) take it without
// including the run driver.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>

#include "fields/field.h"
#include "io/config.h"
#include "solvers/run/field_init.h"
#include "solvers/output/output_options.h"
#include "solvers/core/problem.h"
#include "solvers/training/training_options.h"

namespace nfield::solvers {

struct RunSetup {
  std::filesystem::path config_path;
  io::ConfigNode root;
  std::unique_ptr<Problem> problem{};
  fields::FieldOptions field{};
  FieldInit init{};  // field.init: the network the run starts from (solvers/run/field_init.h)
  TrainingOptions training{};
  OutputOptions output{};
  YAML::Node resolved{};  // the config with defaults filled in
  std::filesystem::path data_dir{};  // relative data paths resolve here (the config's folder)
  // Progress lines redrawn in place or one per line (ProgressPrinterOptions::terminal); unset:
  // redrawn on a terminal outside mpirun (nfield run --progress).
  std::optional<bool> live_progress{};
};

}  // namespace nfield::solvers
