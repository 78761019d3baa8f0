// SPDX-License-Identifier: MIT
//
// The `output:` section of a config (read by load_run, solvers/run/run.h; used by the grid
// outputs, solvers/output/grid_output.h):
//
//   output:
//     dir: out/NAME        # default: out/ + the config file's stem
//     grid: [128, 128]     # points per space axis (default 256 in 1D, 128 in 2D, 48 in 3D)
//     frames: 11           # time-dependent problems: frames over [t0, t1]
//     png: true
#pragma once

#include <filesystem>
#include <vector>

namespace nfield::solvers {

struct OutputOptions {
  std::filesystem::path dir;
  std::vector<int> grid;
  int frames = 11;
  bool png = true;
};

}  // namespace nfield::solvers
