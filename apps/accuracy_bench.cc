// SPDX-License-Identifier: MIT
#include "apps/accuracy_bench.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "solvers/run/run.h"

namespace nfield::apps {

const std::vector<AccuracyCase>& accuracy_cases() {
  const auto rel_l2 = [](double target) { return std::vector<AccuracyCriterion>{{"rel_l2", target, false}}; };
  static const std::vector<AccuracyCase> cases{
      {"poisson_2d", "accuracy_poisson_2d", rel_l2(1e-6), 120},
      {"helmholtz_2d", "accuracy_helmholtz_2d", rel_l2(1e-5), 300},
      {"wave_1d", "accuracy_wave_1d", rel_l2(1e-3), 600},
      {"poisson_3d", "accuracy_poisson_3d", rel_l2(1e-5), 300},
      {"eikonal_layered", "accuracy_eikonal_layered", rel_l2(1e-3), 300},
      // The SIREN experiments (issue 14's table).
      {"wave_2d", "accuracy_wave_2d", {{"max_frame_rel_l2", 1e-2, false}}, 600},
      {"helmholtz_pml", "helmholtz_pml", rel_l2(5e-3), 600},
      {"sdf_bunny", "sdf_bunny",
       {{"chamfer_mean_per_diagonal", 3e-3, false},
        {"chamfer_max", 3e-2, false},
        {"sign_accuracy", 0.998, true},
        {"surface_components", 1, false}},
       600},
      {"sdf_kitten", "sdf_kitten",
       {{"chamfer_mean_per_diagonal", 5e-3, false}, {"surface_components", 1, false}},
       600},
      {"poisson_image", "poisson_image", {{"psnr_db", 40, true}}, 600},
      {"poisson_image_laplacian", "poisson_image_laplacian", {{"psnr_db", 32, true}}, 600},
      {"fit_image", "fit_image", {{"psnr_db", 50, true}}, 60},
      {"fit_audio", "fit_audio", {{"snr_db", 40, true}}, 120},
      {"fit_video", "fit_video", {{"psnr_mean", 30, true}}, 600},
  };
  return cases;
}

namespace {

struct Row {
  AccuracyCase target;
  nlohmann::json metrics;
};

// The error after the last Adam stage that precedes the first other optimizer (NaN: none).
double rel_l2_after_adam(const nlohmann::json& stages) {
  double after = std::nan("");
  for (const auto& stage : stages) {
    if (stage.value("optimizer", "") != "adam") break;
    if (stage.contains("rel_l2")) after = stage["rel_l2"].get<double>();
  }
  return after;
}

std::string stage_summary(const nlohmann::json& stages) {
  std::string text;
  for (const auto& stage : stages) {
    char part[96];
    std::snprintf(part, sizeof part, "%s%s %.2e", text.empty() ? "" : " -> ",
                  stage.value("optimizer", "?").c_str(),
                  stage.contains("rel_l2") ? stage["rel_l2"].get<double>() : std::nan(""));
    text += part;
  }
  return text;
}

nlohmann::json json_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

double metric(const nlohmann::json& metrics, const std::string& key) {
  return metrics.contains(key) && metrics[key].is_number() ? metrics[key].get<double>() : std::nan("");
}

bool holds(const AccuracyCriterion& c, double value) {
  return c.at_least ? value >= c.target : value <= c.target;  // false for NaN
}

// The cases that --cases names (all of them when it names none); an unknown name is refused
// with the valid ones listed.
std::vector<AccuracyCase> selected_cases(const std::vector<std::string>& names) {
  std::vector<AccuracyCase> selected;
  for (const AccuracyCase& c : accuracy_cases())
    if (names.empty() || std::find(names.begin(), names.end(), c.name) != names.end()) selected.push_back(c);
  for (const std::string& name : names)
    if (std::none_of(selected.begin(), selected.end(), [&](const AccuracyCase& c) { return c.name == name; })) {
      std::string valid;
      for (const AccuracyCase& c : accuracy_cases()) valid += (valid.empty() ? "" : ", ") + c.name;
      throw CLI::ValidationError("--cases", "unknown case '" + name + "' (valid: " + valid + ")");
    }
  return selected;
}

// Prints the row's lines of the table and returns its JSON line; `met` tells whether the case
// finished, reached every criterion and kept to its wall time.
nlohmann::ordered_json report_row(const Row& row, bool& met) {
  const nlohmann::json& m = row.metrics;
  const double wall = m["wall_s"].get<double>();
  bool accurate = true;
  nlohmann::json criteria = nlohmann::json::array();
  for (const AccuracyCriterion& c : row.target.criteria) {
    const double value = metric(m, c.metric);
    accurate = accurate && holds(c, value);
    criteria.push_back({{"metric", c.metric},
                        {"value", json_number(value)},
                        {"target", c.target},
                        {"at_least", c.at_least},
                        {"met", holds(c, value)}});
  }
  const AccuracyCriterion& first = row.target.criteria.front();
  const double value = metric(m, first.metric);
  const bool finished = m.value("finished", false);
  met = finished && accurate && wall <= row.target.target_wall_s;
  std::printf("%-16s %-26s %10.3g %10.3g %8.1f %8s  %s\n", row.target.name.c_str(),
              (first.metric + (first.at_least ? " >=" : " <=")).c_str(), first.target, value, wall,
              met ? "yes" : !finished ? "stopped" : (accurate ? "slow" : "no"), stage_summary(m["stages"]).c_str());
  for (size_t k = 1; k < row.target.criteria.size(); ++k) {
    const AccuracyCriterion& c = row.target.criteria[k];
    const double v = metric(m, c.metric);
    std::printf("%-16s %-26s %10.3g %10.3g %8s %8s\n", "", (c.metric + (c.at_least ? " >=" : " <=")).c_str(),
                c.target, v, "", holds(c, v) ? "yes" : "no");
  }
  if (m.contains("sign_accuracy_band"))
    std::printf("%-16s %-26s %10s %10.3g\n", "", "sign_accuracy_band", "-", metric(m, "sign_accuracy_band"));
  nlohmann::ordered_json line;
  line["case"] = row.target.name;
  line["metric"] = first.metric;
  line["value"] = json_number(value);
  line["target"] = first.target;
  line["met"] = met;
  line["criteria"] = criteria;
  line["rel_l2"] = json_number(metric(m, "rel_l2"));
  line["rel_l2_after_adam"] = json_number(rel_l2_after_adam(m["stages"]));
  // The sign shares of an SDF case side by side: the whole grid's is mostly far from the
  // surface, where the sign is easy; the 5 % band's is where a surface goes wrong.
  for (const char* key : {"sign_accuracy", "sign_accuracy_band"})
    if (m.contains(key)) line[key] = json_number(metric(m, key));
  line["wall_s"] = wall;
  line["target_wall_s"] = row.target.target_wall_s;
  line["stages"] = m["stages"];
  return line;
}

}  // namespace

int run_accuracy_bench(const AccuracyOptions& options) {
  const std::vector<AccuracyCase> selected = selected_cases(options.cases);
  // Read and check every config before training any, so a bad one fails at once.
  std::vector<solvers::RunSetup> setups;
  for (const AccuracyCase& c : selected)
    setups.push_back(solvers::load_run(options.configs / (c.config + ".yaml"), options.overrides,
                                       options.out / c.name));

  std::vector<Row> rows;
  for (size_t k = 0; k < selected.size(); ++k) {
    std::printf("== %s (%s)\n", selected[k].name.c_str(), setups[k].config_path.string().c_str());
    std::fflush(stdout);
    const int code = solvers::execute_run(setups[k]);
    std::ifstream file(setups[k].output.dir / "metrics.json");
    rows.push_back({selected[k], nlohmann::json::parse(file)});
    // A case that diverged misses its target (below); an interrupt ends the table.
    if (code != 0 && code != solvers::kExitDiverged) return code;
  }

  std::printf("\n%-16s %-26s %10s %10s %8s %8s  %s\n", "case", "figure", "target", "value", "wall s", "met",
              "rel_l2 after each stage");
  std::vector<std::string> lines, missed;
  for (const Row& row : rows) {
    bool met = false;
    const nlohmann::ordered_json line = report_row(row, met);
    lines.push_back(line.dump());
    if (met) continue;
    const nlohmann::json& m = row.metrics;
    const bool finished = m.value("finished", false);
    const bool accurate = std::all_of(line["criteria"].begin(), line["criteria"].end(),
                                      [](const auto& c) { return c["met"].template get<bool>(); });
    missed.push_back(row.target.name + (!finished ? " (" + m.value("stopped", std::string("not finished")) + ")"
                                        : accurate ? " (slow)" : ""));
  }
  for (const std::string& line : lines) std::puts(line.c_str());
  if (missed.empty()) {
    std::printf("all %zu cases met their targets\n", rows.size());
    return 0;
  }
  std::string names;
  for (const std::string& name : missed) names += (names.empty() ? "" : ", ") + name;
  std::printf("%zu of %zu cases missed their targets: %s\n", missed.size(), rows.size(), names.c_str());
  return options.fail_on_miss ? kExitTargetsMissed : 0;
}

}  // namespace nfield::apps
