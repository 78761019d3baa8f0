// SPDX-License-Identifier: MIT
//
// One run of a config: read and check everything first (so a bad config writes nothing),
// then train, then write the outputs into output.dir:
//
//   config.yaml      the config as resolved, every default filled in
//   checkpoint.h5    field (see fields/field_io.h), trainer state, config text
//   solution.vti     u, grad_u, residual, exact, error on output.grid (time-dependent
//                    problems: solution.pvd over frames frame_KKKK.vti)
//   solution.png     preview of u (2D, or the middle slice of 3D / the first frame)
//   metrics.json     problem, steps, wall_s, step_ms_median, losses, rel_l2, max_abs_err, …
//                    stages: [{optimizer, steps, iterations, ended, termination, message,
//                    loss, rel_l2, wall_s}] after each stage; finished, stopped, divergence
//
// The `output:` section: solvers/output_options.h.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <nlohmann/json.hpp>

#include "fields/field.h"
#include "io/hdf5_file.h"
#include "solvers/run/run_setup.h"

namespace nfield::solvers {

// Reads and checks a config (and `--set` overrides). Throws io::ConfigError. Relative data
// paths resolve against `data_dir` (default: the config's folder).
RunSetup load_run(const std::filesystem::path& config, const std::vector<std::string>& overrides,
                  const std::filesystem::path& out_dir_override = {},
                  const std::filesystem::path& data_dir = {});

// The run a checkpoint was trained by, from the config stored in it (relative data paths
// resolve where that run read them): its problem, field options and the rest. Writes
// nothing; messages name the config as CHECKPOINT:config.
RunSetup load_checkpoint_run(const io::H5Reader& file);

// The exit code of a run whose loss, gradient or update went non-finite (training.on_divergence):
// its checkpoint and outputs hold the last parameters whose loss was finite, and metrics.json
// says where it stopped ("finished": false, "stopped", "divergence").
inline constexpr int kExitDiverged = 3;

// Trains and writes the outputs. Returns 0 when finished, 130 when interrupted by a signal,
// kExitDiverged when a step went non-finite (outputs and checkpoint of the last finite state
// reached are still written).
int execute_run(RunSetup& setup, const std::filesystem::path& resume = {});

// Samples a checkpoint's field onto a grid and writes VTK (nfield eval), and metrics.json
// with the grid's errors and the problem's own figures (a pde's reference.file errors at
// its points, the same keys and values as the run's metrics.json). The problem is rebuilt
// from the stored config: relative data paths resolve against the folder of the config the
// run read (the checkpoint's config_dir), and a data file gone from there is the located
// config error it would be for `nfield run`, naming the stored config's copy in out_dir.
// Returns what it writes to metrics.json.
nlohmann::ordered_json evaluate_checkpoint(const std::filesystem::path& checkpoint, int grid_points,
                                           const std::filesystem::path& out_dir);

// The appearance a checkpoint with latent codes (/latent/codes: data.appearance) renders
// with: `from`, and with `to` the code (1 − t)·z_from + t·z_to. Each names a training image by
// its name (with or without its extension: r_3.png, r_3) or its row in /latent/codes. Both
// empty: the code 0, the prior's mean.
struct RenderCode {
  std::string from, to;
  double t = 0.5;
};

// Renders views of a radiance-field checkpoint into out_dir (nfield render): the cameras of
// `request.poses`, or a turntable. Throws for a checkpoint whose problem renders no images,
// and std::invalid_argument naming --code or --to for a code the checkpoint does not hold.
void render_checkpoint(const std::filesystem::path& checkpoint, const RenderRequest& request,
                       const std::filesystem::path& out_dir, const RenderCode& code = {});

}  // namespace nfield::solvers
