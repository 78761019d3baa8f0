// SPDX-License-Identifier: MIT
//
// What one instance of a family (equation.family, Problem::instances) reports and writes with
// a field's current parameters: the drivers of family runs (solvers/run/meta_run.h,
// solvers/run/latent_run.h) ask it after adapting or fitting the field to the instance. A
// family's instances have no hard conditions: the solution is the network itself.
//
// An instance's figure is its first progress figure (fit: PSNR, higher is better), or for a
// problem with none whose field is written on the output grid against an exact or reference
// solution (a drawn family of PDE instances, solvers/problems/drawn_family.h) the grid's
// rel_l2 (lower is better). Its outputs are the problem's own, and for the latter also the
// grid files (solution.vti, …) with rel_l2 and max_abs_err among its metrics.
#pragma once

#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fields/field.h"
#include "solvers/core/problem.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/core/solution.h"
#include "solvers/output/grid_output.h"
#include "solvers/output/output_options.h"

namespace nfield::solvers {

// The folder name of an instance's outputs: its name without the extension (camera_5.png →
// camera_5).
inline std::string instance_stem(const std::string& name) { return std::filesystem::path(name).stem().string(); }

// An instance's figure: its name, value and sense.
struct InstanceFigure {
  std::string name;
  double value = 0;
  bool lower_is_better = false;
  // Whether `a` is as good as `b` or better in this figure's sense.
  bool as_good(double a, double b) const { return lower_is_better ? a <= b : a >= b; }
};

// Whether an instance's field is scored on the output grid (see above).
inline bool scored_on_grid(const Problem& problem) {
  return !capability<ReportsProgress>(problem) && problem.writes_grid_outputs() && problem.has_exact();
}

template <typename Scalar>
class InstanceOutputs {
 public:
  using Metrics = std::vector<std::pair<std::string, double>>;

  // `output`: the run's output options (grid, VTK precision); the field is read at each call
  // (not copied).
  InstanceOutputs(OutputOptions output, const fields::Field<Scalar>& field) : output_(std::move(output)), field_(field) {}

  // The instance's figure (above); nullopt for problems without one (sdf: its figures are its
  // outputs' metrics).
  std::optional<InstanceFigure> figure(const Problem& problem) const {
    if (scored_on_grid(problem)) {
      const Solution solution = make_solution(field_, nullptr);
      return InstanceFigure{"rel_l2", grid_error(problem, solution.streams, output_).rel_l2, true};
    }
    const auto* reports = capability<ReportsProgress>(problem);
    if (!reports) return std::nullopt;
    const auto figures = reports->progress_metrics(context({}), {});
    if (figures.empty()) return std::nullopt;
    return InstanceFigure{figures.front().first, figures.front().second, false};
  }

  // Writes the instance's outputs into `dir` (made if missing); returns its metrics.
  Metrics write(const Problem& problem, const std::filesystem::path& dir) const {
    std::filesystem::create_directories(dir);
    Metrics metrics;
    const OutputContext c = context(dir);
    if (scored_on_grid(problem)) {
      OutputOptions output = output_;
      output.dir = dir;
      const GridMetrics grid = write_grid_outputs(problem, c.streams, output, &c);
      metrics.emplace_back("rel_l2", grid.rel_l2);
      metrics.emplace_back("max_abs_err", grid.max_abs_err);
    }
    problem.write_outputs(c, metrics);
    return metrics;
  }

 private:
  OutputContext context(const std::filesystem::path& dir) const {
    const Solution solution = make_solution(field_, nullptr);
    OutputContext context;
    context.dir = dir;
    context.values = solution.values;
    context.streams = solution.streams;
    context.grid = output_.grid;
    context.epsilon = std::numeric_limits<Scalar>::epsilon();
    return context;
  }

  OutputOptions output_;
  const fields::Field<Scalar>& field_;
};

}  // namespace nfield::solvers
