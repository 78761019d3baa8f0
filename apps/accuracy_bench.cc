// SPDX-License-Identifier: MIT
#include "apps/accuracy_bench.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "solvers/run.h"

namespace nfield::apps {

const std::vector<AccuracyCase>& accuracy_cases() {
  static const std::vector<AccuracyCase> cases{
      {"poisson_2d", 1e-6, 120},   {"helmholtz_2d", 1e-5, 300},    {"wave_1d", 1e-3, 600},
      {"poisson_3d", 1e-5, 300},   {"eikonal_layered", 1e-3, 300},
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

}  // namespace

int run_accuracy_bench(const AccuracyOptions& options) {
  std::vector<AccuracyCase> selected;
  for (const AccuracyCase& c : accuracy_cases())
    if (options.cases.empty() ||
        std::find(options.cases.begin(), options.cases.end(), c.name) != options.cases.end())
      selected.push_back(c);
  for (const std::string& name : options.cases)
    if (std::none_of(selected.begin(), selected.end(), [&](const AccuracyCase& c) { return c.name == name; })) {
      std::string valid;
      for (const AccuracyCase& c : accuracy_cases()) valid += (valid.empty() ? "" : ", ") + c.name;
      throw CLI::ValidationError("--cases", "unknown case '" + name + "' (valid: " + valid + ")");
    }
  // Read and check every config before training any, so a bad one fails at once.
  std::vector<solvers::RunSetup> setups;
  for (const AccuracyCase& c : selected)
    setups.push_back(solvers::load_run(options.configs / ("accuracy_" + c.name + ".yaml"),
                                       options.overrides, options.out / c.name));

  std::vector<Row> rows;
  for (size_t k = 0; k < selected.size(); ++k) {
    std::printf("== %s (%s)\n", selected[k].name.c_str(), setups[k].config_path.string().c_str());
    std::fflush(stdout);
    const int code = solvers::execute_run(setups[k]);
    std::ifstream file(setups[k].output.dir / "metrics.json");
    rows.push_back({selected[k], nlohmann::json::parse(file)});
    if (code != 0) return code;
  }

  std::printf("\n%-16s %10s %10s %12s %8s %8s  %s\n", "case", "target", "rel_l2", "after adam", "wall s",
              "met", "rel_l2 after each stage");
  std::vector<std::string> lines;
  for (const Row& row : rows) {
    const nlohmann::json& m = row.metrics;
    const double rel_l2 = m.contains("rel_l2") ? m["rel_l2"].get<double>() : std::nan("");
    const double wall = m["wall_s"].get<double>();
    const double after_adam = rel_l2_after_adam(m["stages"]);
    const bool met = rel_l2 <= row.target.target_rel_l2 && wall <= row.target.target_wall_s;
    std::printf("%-16s %10.1e %10.2e %12.2e %8.1f %8s  %s\n", row.target.name.c_str(),
                row.target.target_rel_l2, rel_l2, after_adam, wall,
                met ? "yes" : (rel_l2 <= row.target.target_rel_l2 ? "slow" : "no"),
                stage_summary(m["stages"]).c_str());
    nlohmann::ordered_json line;
    line["case"] = row.target.name;
    line["rel_l2"] = json_number(rel_l2);
    line["rel_l2_after_adam"] = json_number(after_adam);
    line["wall_s"] = wall;
    line["target_rel_l2"] = row.target.target_rel_l2;
    line["target_wall_s"] = row.target.target_wall_s;
    line["stages"] = m["stages"];
    lines.push_back(line.dump());
  }
  for (const std::string& line : lines) std::puts(line.c_str());
  return 0;
}

}  // namespace nfield::apps
