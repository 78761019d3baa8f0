// SPDX-License-Identifier: MIT
//
// What one instance of a family (equation.family, Problem::instances) reports and writes with
// a field's current parameters: the drivers of family runs (solvers/run/meta_run.h,
// solvers/run/latent_run.h) ask it after adapting or fitting the field to the instance. A
// family's instances have no hard conditions: the solution is the network itself.
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

namespace nfield::solvers {

// The folder name of an instance's outputs: its name without the extension (camera_5.png →
// camera_5).
inline std::string instance_stem(const std::string& name) { return std::filesystem::path(name).stem().string(); }

template <typename Scalar>
class InstanceOutputs {
 public:
  using Metrics = std::vector<std::pair<std::string, double>>;

  // `grid`: output.grid of the run; the field is read at each call (not copied).
  InstanceOutputs(std::vector<int> grid, const fields::Field<Scalar>& field) : grid_(std::move(grid)), field_(field) {}

  // The instance's first progress figure (fit: "PSNR") and its value; nullopt for problems
  // without progress figures (sdf: its figures are its outputs' metrics).
  std::optional<std::pair<std::string, double>> figure(const Problem& problem) const {
    const auto* reports = capability<ReportsProgress>(problem);
    if (!reports) return std::nullopt;
    const auto figures = reports->progress_metrics(context({}), {});
    if (figures.empty()) return std::nullopt;
    return figures.front();
  }

  // Writes the instance's outputs into `dir` (made if missing); returns its metrics.
  Metrics write(const Problem& problem, const std::filesystem::path& dir) const {
    std::filesystem::create_directories(dir);
    Metrics metrics;
    problem.write_outputs(context(dir), metrics);
    return metrics;
  }

 private:
  OutputContext context(const std::filesystem::path& dir) const {
    const Solution solution = make_solution(field_, nullptr);
    OutputContext context;
    context.dir = dir;
    context.values = solution.values;
    context.streams = solution.streams;
    context.grid = grid_;
    context.epsilon = std::numeric_limits<Scalar>::epsilon();
    return context;
  }

  std::vector<int> grid_;
  const fields::Field<Scalar>& field_;
};

}  // namespace nfield::solvers
