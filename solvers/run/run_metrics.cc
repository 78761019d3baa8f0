// SPDX-License-Identifier: MIT
#include "solvers/run/run_metrics.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "io/atomic_write.h"
#include "solvers/geometry/geometry.h"

namespace nfield::solvers {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// Per finished stage: optimizer, steps configured and taken and why it ended, final loss,
// rel_l2 (the problem's reported error, else the grid's), wall seconds.
template <typename Scalar>
nlohmann::ordered_json stage_metrics(const RunSetup& setup, const Trainer<Scalar>& trainer) {
  nlohmann::ordered_json stages = nlohmann::ordered_json::array();
  for (size_t k = 0; k < trainer.stage_losses().size(); ++k) {
    nlohmann::ordered_json stage;
    stage["optimizer"] = setup.training.stages[k].optimizer;
    stage["steps"] = setup.training.stages[k].steps;
    if (k < trainer.stage_ends().size()) {
      const StageEnd& end = trainer.stage_ends()[k];
      stage["iterations"] = end.iterations;
      stage["ended"] = end.ended;
      if (!end.termination.empty()) stage["termination"] = end.termination;
      if (!end.message.empty()) stage["message"] = end.message;
    }
    stage["loss"] = trainer.stage_losses()[k];
    if (k < trainer.stage_errors().size() && std::isfinite(trainer.stage_errors()[k]))
      stage["rel_l2"] = trainer.stage_errors()[k];
    if (k < trainer.stage_seconds().size() && std::isfinite(trainer.stage_seconds()[k]))
      stage["wall_s"] = trainer.stage_seconds()[k];
    stages.push_back(stage);
  }
  return stages;
}

// The errors on the output grid: overall, per output, per frame and per held-out parameter.
void add_grid_metrics(const RunSetup& setup, const GridMetrics& grid, nlohmann::ordered_json& metrics) {
  if (!grid.has_error) return;
  metrics["rel_l2"] = grid.rel_l2;
  metrics["max_abs_err"] = grid.max_abs_err;
  const std::vector<std::string> names = setup.problem->output_names();
  for (size_t c = 0; names.size() > 1 && c < names.size() && c < grid.output_rel_l2.size(); ++c) {
    metrics["rel_l2_" + names[c]] = grid.output_rel_l2[c];
    metrics["max_abs_err_" + names[c]] = grid.output_max_abs_err[c];
  }
  if (!grid.frame_rel_l2.empty()) {
    metrics["max_frame_rel_l2"] = *std::max_element(grid.frame_rel_l2.begin(), grid.frame_rel_l2.end());
    metrics["frame_rel_l2"] = grid.frame_rel_l2;
    metrics["frame_times"] = grid.frame_times;
  }
  // A parametric field: rel_l2 above is the worst held-out value's; each value's figures.
  for (const HeldOutMetrics& h : grid.held_out) {
    nlohmann::ordered_json item;
    for (const auto& [name, value] : h.parameters) item[name] = value;
    item["rel_l2"] = h.rel_l2;
    item["max_abs_err"] = h.max_abs_err;
    if (setup.problem->domain().has_time()) item["max_frame_rel_l2"] = h.max_frame_rel_l2;
    item["dir"] = h.dir;
    metrics["held_out"].push_back(item);
  }
}

}  // namespace

template <typename Scalar>
nlohmann::ordered_json run_metrics(const RunSetup& setup, Trainer<Scalar>& trainer, const fields::Field<Scalar>& field,
                                   bool finished, double wall, const GridMetrics& grid,
                                   const std::vector<std::pair<std::string, double>>& extra, long first_step,
                                   Communicator& communicator) {
  nlohmann::ordered_json metrics;
  metrics["problem"] = setup.root.get<std::string>("problem");
  metrics["finished"] = finished;
  if (const auto& d = trainer.divergence()) {
    metrics["stopped"] = "diverged: " + d->describe();
    metrics["divergence"] = {{"step", d->step},
                             {"stage", d->stage},
                             {"optimizer", d->optimizer},
                             {"what", d->what},
                             {"last_finite_step", d->last_finite_step},
                             {"last_finite_loss", d->last_finite_loss}};
  } else if (!finished) {
    metrics["stopped"] = "interrupted";
  }
  metrics["steps"] = trainer.step();
  metrics["wall_s"] = wall;
  metrics["step_ms_median"] = median(trainer.step_milliseconds());
  metrics["precision"] = setup.training.precision;
  metrics["parameters"] = field.parameter_count();
  double loss = 0;
  for (size_t k = 0; k < trainer.term_names().size(); ++k) {
    metrics["losses"][trainer.term_names()[k]] = trainer.term_losses()[k];
    loss += trainer.term_losses()[k];
  }
  metrics["loss"] = loss;
  metrics["stage_losses"] = trainer.stage_losses();
  metrics["stages"] = stage_metrics(setup, trainer);
  add_grid_metrics(setup, grid, metrics);
  if (setup.problem->writes_grid_outputs()) metrics["residual_rms"] = grid.residual_rms;
  if (setup.problem->domain().geometry()) {
    // The measure of a shaped domain: exact for one primitive, else a Monte Carlo estimate.
    const geometry::Measure m = setup.problem->domain().space_measure();
    metrics["domain_measure"] = m.value;
    metrics["domain_measure_std_error"] = m.std_error;
    metrics["domain_measure_exact"] = m.exact;
  }
  if (communicator.size() > 1) {
    metrics["mpi_ranks"] = communicator.size();
    // Sent by this rank into the step's sums (and stop flags, clock): the volume per step.
    const long steps = trainer.step() - first_step;
    if (steps > 0)
      metrics["mpi_bytes_per_step"] =
          static_cast<double>(communicator.bytes_communicated()) / static_cast<double>(steps);
  }
  for (const auto& [key, value] : trainer.extra_metrics()) metrics[key] = value;
  for (const auto& [key, value] : extra) metrics[key] = value;
  return metrics;
}

nlohmann::ordered_json eval_metrics(const RunSetup& setup, const GridMetrics& grid,
                                    const std::vector<std::pair<std::string, double>>& extra) {
  nlohmann::ordered_json metrics;
  metrics["problem"] = setup.root.get<std::string>("problem");
  add_grid_metrics(setup, grid, metrics);
  if (setup.problem->writes_grid_outputs()) metrics["residual_rms"] = grid.residual_rms;
  for (const auto& [key, value] : extra) metrics[key] = value;
  return metrics;
}

template nlohmann::ordered_json run_metrics(const RunSetup&, Trainer<float>&, const fields::Field<float>&, bool, double,
                                           const GridMetrics&, const std::vector<std::pair<std::string, double>>&,
                                           long, Communicator&);
template nlohmann::ordered_json run_metrics(const RunSetup&, Trainer<double>&, const fields::Field<double>&, bool, double,
                                            const GridMetrics&, const std::vector<std::pair<std::string, double>>&,
                                            long, Communicator&);

void write_metrics_json(const std::filesystem::path& dir, const nlohmann::ordered_json& metrics) {
  io::write_atomically(dir / "metrics.json", [&](const std::filesystem::path& p) {
    std::ofstream(p) << metrics.dump(2) << "\n";
  });
}

}  // namespace nfield::solvers
