// SPDX-License-Identifier: MIT
#include "apps/autoint_bench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/atomic_write.h"
#include "io/config.h"
#include "solvers/run/run.h"

namespace nfield::apps {
namespace {

struct Run {
  std::string name;
  int sections = 0;          // 0: a NeRF
  int evaluations_per_ray = 0;
  bool sampler = false;      // sections placed by the sampling network
  solvers::RunSetup setup;
  nlohmann::json metrics;
};

// The targets for AutoInt at K sections: render speed-up over the reference at
// least, PSNR lost against it at most (NaN: none for this K).
std::pair<double, double> target(int sections) {
  switch (sections) {
    case 8: return {8, 4};
    case 16: return {5, 2.5};
    case 32: return {3, 1.5};
    default: return {std::nan(""), std::nan("")};
  }
}

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// Every config is read and checked before any training, so a bad one fails at once.
std::vector<Run> plan_runs(const AutointBenchOptions& options) {
  std::vector<std::string> common = options.overrides;
  common.push_back("training.stages[0].seconds=" + std::to_string(options.seconds));
  auto with = [&common](std::vector<std::string> extra) {
    extra.insert(extra.begin(), common.begin(), common.end());
    return extra;
  };
  std::vector<Run> runs;
  runs.push_back({"nerf_quadrature", 0, options.nerf_samples, false,
                  solvers::load_run(options.nerf_config, with({"render.samples=" + std::to_string(options.nerf_samples)}),
                                    options.out / "nerf_quadrature"),
                  {}});
  if (options.with_grid)
    runs.push_back({"nerf_grid", 0, 0, false, solvers::load_run(options.grid_config, with({}), options.out / "nerf_grid"), {}});
  std::vector<bool> samplers;
  if (options.sampler != "on") samplers.push_back(false);
  if (options.sampler != "off") samplers.push_back(true);
  // Whether the config itself places sections by the network (`sampler:` a mapping or true):
  // runs that differ get `render.sampler=true|false`, the others keep the config's section.
  const io::ConfigNode render = io::load_config(options.autoint_config, common).child_or_empty("render");
  const bool configured =
      render.has("sampler") && !(render.yaml()["sampler"].IsScalar() && !render.get<bool>("sampler"));
  for (bool sampler : samplers)
    for (int k : options.sections) {
      const long per_section = std::max(1L, std::lround(static_cast<double>(options.samples_per_ray) / k));
      std::vector<std::string> set{"render.sections=" + std::to_string(k),
                                   "render.samples_per_section=" + std::to_string(per_section)};
      if (sampler != configured) set.push_back(std::string("render.sampler=") + (sampler ? "true" : "false"));
      const std::string name = "autoint_" + std::to_string(k) + (sampler ? "_sampler" : "");
      solvers::RunSetup setup = solvers::load_run(options.autoint_config, with(set), options.out / name);
      runs.push_back({name, k, k + 1, sampler, std::move(setup), {}});
    }
  return runs;
}

struct Row {
  std::string run;
  int sections, evaluations;
  bool sampler;
  double steps, train_s, psnr, ssim, ms;
};

// A row per run, and one more for the occupancy-grid NeRF marched through every cell: what the
// grid's skipping gains.
std::vector<Row> table_rows(const std::vector<Run>& runs) {
  std::vector<Row> rows;
  for (const Run& run : runs) {
    const nlohmann::json& m = run.metrics;
    Row row{run.name, run.sections, run.evaluations_per_ray, run.sampler, m["steps"].get<double>(), m["wall_s"].get<double>(),
            m["psnr_mean"].get<double>(), m["ssim_mean"].get<double>(), m["render_ms_mean"].get<double>()};
    rows.push_back(row);
    if (run.name == "nerf_grid" && m.contains("render_ms_dense_mean")) {
      row.run = "nerf_grid_dense";
      row.psnr = m["psnr_dense_mean"].get<double>();
      row.ssim = std::nan("");
      row.ms = m["render_ms_dense_mean"].get<double>();
      rows.push_back(row);
    }
  }
  return rows;
}

// Prints the row against the reference and returns it as a JSON line.
nlohmann::ordered_json print_row(const Row& row, double reference_ms, double reference_psnr) {
  const double speedup = reference_ms / row.ms, loss = reference_psnr - row.psnr;
  const auto [target_speedup, target_loss] = target(row.sections);
  const bool has_target = std::isfinite(target_speedup);
  const bool met = has_target && speedup >= target_speedup && loss <= target_loss;
  char evaluations[16] = "march";
  if (row.evaluations > 0) std::snprintf(evaluations, sizeof evaluations, row.sampler ? "%d+S" : "%d", row.evaluations);
  char goal[64] = "";
  if (has_target)
    std::snprintf(goal, sizeof goal, "%.0fx, %.1f dB: %s", target_speedup, target_loss, met ? "met" : "not met");
  std::printf("%-20s %5s %9s %7.0f %10.2f %8.4f %10.1f %8.2fx %9.2f  %s\n", row.run.c_str(),
              row.sections > 0 ? std::to_string(row.sections).c_str() : "-", evaluations, row.steps, row.psnr,
              row.ssim, row.ms, speedup, loss, goal);
  nlohmann::ordered_json line;
  line["bench"] = "autoint";
  line["run"] = row.run;
  line["sections"] = row.sections;
  line["evaluations_per_ray"] = row.evaluations;
  line["sampling_network"] = row.sampler;
  line["steps"] = row.steps;
  line["train_s"] = row.train_s;
  line["psnr_mean"] = number(row.psnr);
  line["ssim_mean"] = number(row.ssim);
  line["render_ms"] = row.ms;
  line["speedup"] = speedup;
  line["psnr_loss_db"] = loss;
  line["target_speedup"] = number(target_speedup);
  line["target_psnr_loss_db"] = number(target_loss);
  if (has_target) line["met"] = met;
  return line;
}

}  // namespace

int run_autoint_bench(const AutointBenchOptions& options) {
  std::vector<Run> runs = plan_runs(options);
  for (size_t r = 0; r < runs.size(); ++r) {
    std::printf("== %s (%zu/%zu, %.0f s of training): %s\n", runs[r].name.c_str(), r + 1, runs.size(),
                options.seconds, runs[r].setup.config_path.string().c_str());
    std::fflush(stdout);
    const int code = solvers::execute_run(runs[r].setup);
    if (code != 0) return code;
    std::ifstream file(runs[r].setup.output.dir / "metrics.json");
    runs[r].metrics = nlohmann::json::parse(file);
    if (!runs[r].metrics.contains("psnr_mean"))
      throw std::runtime_error(runs[r].setup.config_path.string() + " has no data.test: the bench compares test views");
  }

  const nlohmann::json& reference = runs.front().metrics;
  std::printf("\nsame training time (%.0f s) per run; reference: NeRF quadrature, %d samples a ray\n",
              options.seconds, options.nerf_samples);
  std::printf("%-20s %5s %9s %7s %10s %8s %10s %9s %9s  %s\n", "run", "K", "evals/ray", "steps", "test PSNR",
              "SSIM", "ms/frame", "speed-up", "dB lost", "target (speed-up >=, dB lost <=)");
  nlohmann::ordered_json all = nlohmann::ordered_json::array();
  for (const Row& row : table_rows(runs))
    all.push_back(print_row(row, reference["render_ms_mean"].get<double>(), reference["psnr_mean"].get<double>()));
  std::fflush(stdout);
  const std::filesystem::path json = options.out / "autoint_bench.json";
  io::write_atomically(json, [&all](const std::filesystem::path& temporary) {
    std::ofstream file(temporary);
    file << all.dump(1) << "\n";
    if (!file) throw std::runtime_error("write failed");
  });
  for (const auto& line : all) std::puts(line.dump().c_str());
  std::printf("wrote %s\n", json.string().c_str());
  return 0;
}

}  // namespace nfield::apps
