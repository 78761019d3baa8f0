// SPDX-License-Identifier: MIT
//
// A trained field sampled on the output grid: values, gradients, the PDE residual, the exact
// solution and the error, as VTK image files (one per time frame, gathered in a .pvd), a PNG
// preview and the error metrics.
//
// A parametric field (solvers/core/domain.h, parameters) is written at each of the problem's
// held-out parameter values (Problem::held_out_parameters), each into its own folder of the
// output directory (held_out_nu_0.01/solution.pvd, …), each with its errors against its own
// reference; the GridMetrics then report the worst of them (rel_l2, max_abs_err, per output)
// and each in held_out. Frames of one held-out value are not listed at the top.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "autodiff/streams.h"
#include "solvers/output/output_options.h"
#include "solvers/core/problem.h"

namespace nfield::solvers {

// Streams of the trained field at points, in double (any training precision).
using StreamEvaluator = std::function<autodiff::Streams<double>(const autodiff::StreamLayout&,
                                                                const Eigen::MatrixXd&)>;

// One held-out parameter value's figures.
struct HeldOutMetrics {
  std::vector<std::pair<std::string, double>> parameters;  // name → value
  std::string dir;                                          // its folder in the output directory
  double rel_l2 = 0, max_abs_err = 0, max_frame_rel_l2 = 0;
};

struct GridMetrics {
  bool has_error = false;
  double rel_l2 = 0;
  double max_abs_err = 0;
  // The same per output channel (problem.output_names() order).
  std::vector<double> output_rel_l2, output_max_abs_err;
  double residual_rms = 0;
  // Time-dependent problems: rel_l2 of each output frame, at frame_times.
  std::vector<double> frame_rel_l2, frame_times;
  // A parametric field: each held-out value's figures (empty otherwise).
  std::vector<HeldOutMetrics> held_out;
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
