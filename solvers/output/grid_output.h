// SPDX-License-Identifier: MIT
//
// A trained field sampled on the output grid: values, gradients, the PDE residual, the exact
// solution and the error, as VTK image files (one per time frame, gathered in a .pvd), a PNG
// preview and the error metrics.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "autodiff/streams.h"
#include "solvers/output/output_options.h"
#include "solvers/problem.h"

namespace nfield::solvers {

// Streams of the trained field at points, in double (any training precision).
using StreamEvaluator = std::function<autodiff::Streams<double>(const autodiff::StreamLayout&,
                                                                const Eigen::MatrixXd&)>;

struct GridMetrics {
  bool has_error = false;
  double rel_l2 = 0;
  double max_abs_err = 0;
  // The same per output channel (problem.output_names() order).
  std::vector<double> output_rel_l2, output_max_abs_err;
  double residual_rms = 0;
  // Time-dependent problems: rel_l2 of each output frame, at frame_times.
  std::vector<double> frame_rel_l2, frame_times;
};

// rel_l2 and max_abs_err on the output grid (and frames) without writing anything; the
// rest of the metrics stay zero. Used after each training stage.
GridMetrics grid_error(const Problem& problem, const StreamEvaluator& evaluate,
                       const OutputOptions& output);

// With `scales` of a multiscale field (OutputContext::scales > 1), each scale's values are
// written beside the output scale's: u_scale0, u_scale1, … for an output named u.
GridMetrics write_grid_outputs(const Problem& problem, const StreamEvaluator& evaluate,
                               const OutputOptions& output, const OutputContext* scales = nullptr);

}  // namespace nfield::solvers
