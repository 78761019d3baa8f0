// SPDX-License-Identifier: MIT
#include "solvers/run/meta_run.h"
#include "solvers/core/problem_capabilities.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "fields/field_io.h"
#include "io/atomic_write.h"
#include "io/version.h"
#include "solvers/core/solution.h"
#include "solvers/training/optimizers.h"
#include "solvers/training/progress_printer.h"
#include "solvers/training/maml.h"
#include "solvers/training/reptile.h"
#include "solvers/run/instance_outputs.h"
#include "solvers/run/run_metrics.h"
#include "solvers/run/run_progress.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// A held-out instance's curves: the figure after each step (index 0: before any).
struct HeldOutCurves {
  std::string name;
  InstanceFigure figure;
  std::vector<double> meta, standard;
  long steps_to_match = -1;  // the standard curve's first step as good as meta[inner_steps]
  long meta_steps_to_end = -1;  // the meta curve's first step as good as the standard's last
  std::vector<std::pair<std::string, double>> values;  // a drawn instance's values
};

template <typename Scalar>
class HeldOutEvaluation {
 public:
  HeldOutEvaluation(const RunSetup& setup, fields::Field<Scalar>& field, const fs::path& dir)
      : setup_(setup), field_(field), dir_(dir) {}

  // The curves of `instance` from θ_meta and from θ_standard; writes its snapshots.
  // `rates`: the learned per-parameter inner rates, when there are (maml.h).
  HeldOutCurves run(const ProblemInstance& instance, const autodiff::Vector<Scalar>& meta_theta,
                    const autodiff::Vector<Scalar>& standard_theta, std::uint64_t seed,
                    const autodiff::Vector<Scalar>* rates) {
    const MetaOptions& meta = setup_.training.meta;
    const StageOptions& stage = setup_.training.stages.front();
    const Problem& problem = *instance.problem;
    HeldOutCurves c;
    c.name = instance.name;
    c.values = instance.values;
    const fs::path folder = dir_ / "held_out" / instance_stem(instance.name);
    const int last = std::max(meta.curve_steps, meta.inner_steps);
    const auto record = [&](std::vector<double>& curve, const std::string& label, int step, bool snapshot) {
      const auto figure = outputs_.figure(problem);
      if (!figure) throw std::runtime_error("held-out instance " + instance.name + " reports no figure");
      c.figure = *figure;
      curve.push_back(figure->value);
      if (snapshot) (void)outputs_.write(problem, folder / (label + "_" + std::to_string(step)));
      report(instance.name, label, step, label == "meta" ? last : stage.steps, *figure);
    };
    const auto snapshot_at = [&](int step) { return step == 0 || step == meta.inner_steps || step == meta.curve_steps; };
    field_.parameters() = meta_theta;
    record(c.meta, "meta", 0, true);
    adapt(problem, field_, setup_.training, meta.inner_optimizer, meta.inner_lr, last, seed,
          [&](int s) { record(c.meta, "meta", s, snapshot_at(s)); }, rates);
    field_.parameters() = standard_theta;
    record(c.standard, "standard", 0, true);
    const double lr = stage.options<AdamStageOptions>().lr;
    const double target = c.meta[static_cast<std::size_t>(meta.inner_steps)];
    adapt(problem, field_, setup_.training, "adam", lr, stage.steps, seed, [&](int s) {
      record(c.standard, "standard", s, snapshot_at(s));
      if (c.steps_to_match < 0 && c.figure.as_good(c.standard.back(), target)) {
        c.steps_to_match = s;
        (void)outputs_.write(problem, folder / "standard_match");
      }
    });
    for (std::size_t s = 0; s < c.meta.size() && c.meta_steps_to_end < 0; ++s)
      if (c.figure.as_good(c.meta[s], c.standard.back())) c.meta_steps_to_end = static_cast<long>(s);
    return c;
  }

 private:
  // A progress line at most every 5 s: a baseline of thousands of steps is minutes long.
  void report(const std::string& name, const std::string& label, int step, int steps, const InstanceFigure& figure) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_report_ < std::chrono::seconds(5)) return;
    last_report_ = now;
    std::printf("  %s, from the %s θ: step %d/%d, %s %.4g\n", name.c_str(), label == "meta" ? "learned" : "standard",
                step, steps, figure.name.c_str(), figure.value);
    std::fflush(stdout);
  }

  const RunSetup& setup_;
  fields::Field<Scalar>& field_;
  fs::path dir_;
  InstanceOutputs<Scalar> outputs_{setup_.output, field_};
  std::chrono::steady_clock::time_point last_report_ = std::chrono::steady_clock::now();
};

void write_curves(const fs::path& path, const std::vector<HeldOutCurves>& curves) {
  io::write_atomically(path, [&](const fs::path& p) {
    std::ofstream out(p);
    out << "step";
    for (const auto& c : curves) out << ",meta_" << instance_stem(c.name) << ",standard_" << instance_stem(c.name);
    out << ",meta_mean,standard_mean\n";
    std::size_t rows = 0;
    for (const auto& c : curves) rows = std::max({rows, c.meta.size(), c.standard.size()});
    const auto cell = [](const std::vector<double>& v, std::size_t i) {
      return i < v.size() ? std::to_string(v[i]) : std::string();
    };
    for (std::size_t i = 0; i < rows; ++i) {
      out << i;
      double meta = 0, standard = 0;
      bool meta_all = true, standard_all = true;
      for (const auto& c : curves) {
        out << "," << cell(c.meta, i) << "," << cell(c.standard, i);
        meta_all = meta_all && i < c.meta.size();
        standard_all = standard_all && i < c.standard.size();
        if (i < c.meta.size()) meta += c.meta[i];
        if (i < c.standard.size()) standard += c.standard[i];
      }
      const auto n = static_cast<double>(curves.size());
      out << "," << (meta_all ? std::to_string(meta / n) : "") << ","
          << (standard_all ? std::to_string(standard / n) : "") << "\n";
    }
  });
}

// The held-out summaries of metrics.json.
void summarise(nlohmann::ordered_json& metrics, const std::vector<HeldOutCurves>& curves, const MetaOptions& meta,
               int baseline_steps) {
  if (curves.empty()) return;
  metrics["held_out_figure"] = curves.front().figure.name;
  for (int s : {0, meta.inner_steps, meta.curve_steps}) {
    double m = 0, st = 0;
    for (const auto& c : curves) {
      m += c.meta[static_cast<std::size_t>(s)];
      st += c.standard[static_cast<std::size_t>(std::min<std::size_t>(s, c.standard.size() - 1))];
    }
    metrics["held_out_meta_step" + std::to_string(s)] = m / static_cast<double>(curves.size());
    metrics["held_out_standard_step" + std::to_string(s)] = st / static_cast<double>(curves.size());
  }
  std::vector<double> ratios;
  bool all_matched = true;
  for (const auto& c : curves) {
    all_matched = all_matched && c.steps_to_match > 0;
    const double steps = c.steps_to_match > 0 ? static_cast<double>(c.steps_to_match) : baseline_steps;
    ratios.push_back(steps / meta.inner_steps);
  }
  if (all_matched)
    metrics["speedup"] = median(ratios);
  else
    metrics["speedup_at_least"] = median(ratios);
  // The other reading: how many steps from the learned θ reach what the whole baseline reached.
  std::vector<double> end_ratios;
  for (const auto& c : curves)
    if (c.meta_steps_to_end >= 0)
      end_ratios.push_back(static_cast<double>(c.standard.size() - 1) / std::max(1L, c.meta_steps_to_end));
  metrics["held_out_reaching_standard_end"] = end_ratios.size();
  if (end_ratios.size() == curves.size()) metrics["speedup_to_standard_end"] = median(end_ratios);
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const auto& c : curves) {
    nlohmann::ordered_json item;
    item["name"] = c.name;
    for (const auto& [key, value] : c.values) item[key] = value;
    item["meta"] = c.meta;
    item["standard_steps_to_match"] = c.steps_to_match > 0 ? nlohmann::ordered_json(c.steps_to_match) : nullptr;
    item["standard_final"] = c.standard.back();
    item["meta_steps_to_standard_final"] =
        c.meta_steps_to_end >= 0 ? nlohmann::ordered_json(c.meta_steps_to_end) : nullptr;
    list.push_back(item);
  }
  metrics["held_out"] = list;
}

void write_meta_checkpoint(const fs::path& path, const auto& field, const auto& rates, const RunSetup& setup,
                           const std::string& config_text) {
  io::H5Writer file(path);
  fields::save_field(file, field);
  if (rates.size() > 0) file.write("/meta/inner_rates", rates.template cast<double>().eval());
  file.write_attribute("/", "config", config_text);
  file.write_attribute("/", "config_dir", fs::absolute(setup.data_dir).lexically_normal().string());
  file.write_attribute("/", "nfield_version", std::string(version()));
  file.write_attribute("/", "meta_algorithm", setup.training.meta.algorithm);
  file.commit();
}

template <typename Scalar>
int meta_train_and_write(RunSetup& setup) {
  const MetaOptions& meta = setup.training.meta;
  const fs::path dir = setup.output.dir;
  const std::string config_text = io::to_yaml(setup.resolved);
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  const std::vector<ProblemInstance> held_out = instances(*setup.problem, true);
  fields::Field<Scalar> field(setup.field);
  if (setup.init.parameters.size() > 0)
    field.parameters().head(setup.init.parameters.size()) = setup.init.parameters.cast<Scalar>();
  const autodiff::Vector<Scalar> standard = field.parameters();
  autodiff::Vector<Scalar> rates;  // learned per-parameter inner rates (maml.h), when asked for
  fs::create_directories(dir);
  io::write_atomically(dir / "config.yaml", [&](const fs::path& p) { std::ofstream(p) << config_text << "\n"; });
  std::printf("meta-learning (%s) over %zu training instances, %zu held out: %d outer steps of %d draws x %d %s steps\n",
              meta.algorithm.c_str(), tasks.size(), held_out.size(), meta.steps, meta.tasks_per_step,
              meta.inner_steps, meta.inner_optimizer.c_str());
  const auto started = std::chrono::steady_clock::now();
  const MetaResult result = train_with_progress(setup, [&](const auto& stop_requested, const auto& progress) {
    if (meta.algorithm == "reptile") return run_reptile(tasks, field, setup.training, meta, {stop_requested, progress});
    return run_maml(tasks, field, setup.training, meta, {stop_requested, progress}, &rates);
  });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!result.finished) std::printf("\ninterrupted at outer step %ld: writing the initialisation reached\n", result.steps);
  write_meta_checkpoint(dir / "checkpoint.h5", field, rates, setup, config_text);
  const autodiff::Vector<Scalar> learned = field.parameters();

  nlohmann::ordered_json metrics;
  metrics["problem"] = setup.root.get<std::string>("problem");
  metrics["finished"] = result.finished;
  metrics["meta_algorithm"] = meta.algorithm;
  metrics["meta_steps"] = result.steps;
  metrics["training_instances"] = tasks.size();
  metrics["held_out_instances"] = held_out.size();
  metrics["wall_s"] = wall;
  metrics["mean_inner_loss_before"] = result.mean_first_loss;
  metrics["mean_inner_loss_last"] = result.mean_last_loss;
  metrics["precision"] = setup.training.precision;
  metrics["parameters"] = field.parameter_count();
  if (rates.size() > 0) {
    metrics["inner_rate_min"] = static_cast<double>(rates.minCoeff());
    metrics["inner_rate_mean"] = static_cast<double>(rates.mean());
    metrics["inner_rate_max"] = static_cast<double>(rates.maxCoeff());
  }
  if (result.finished && !held_out.empty()) {
    std::printf("held-out curves: %d %s steps from the learned initialisation, %d adam steps from the standard one\n",
                std::max(meta.curve_steps, meta.inner_steps), meta.inner_optimizer.c_str(),
                setup.training.stages.front().steps);
    HeldOutEvaluation<Scalar> evaluation(setup, field, dir);
    std::vector<HeldOutCurves> curves;
    for (std::size_t k = 0; k < held_out.size(); ++k) {
      curves.push_back(evaluation.run(held_out[k], learned, standard, setup.training.seed + 7919 * (k + 1),
                                        rates.size() > 0 ? &rates : nullptr));
      const HeldOutCurves& c = curves.back();
      std::printf("  %s: %s %.4g -> %.4g after %d steps (learned); standard %.4g -> %.4g after %zu, matches at %s; "
                  "the learned θ reaches the standard's last at %s\n",
                  c.name.c_str(), c.figure.name.c_str(), c.meta.front(), c.meta[static_cast<std::size_t>(meta.inner_steps)],
                  meta.inner_steps, c.standard.front(), c.standard.back(), c.standard.size() - 1,
                  c.steps_to_match > 0 ? ("step " + std::to_string(c.steps_to_match)).c_str() : "no step",
                  c.meta_steps_to_end >= 0 ? ("step " + std::to_string(c.meta_steps_to_end)).c_str() : "no step");
    }
    field.parameters() = learned;
    write_curves(dir / "held_out_curve.csv", curves);
    summarise(metrics, curves, meta, setup.training.stages.front().steps);
    if (metrics.contains("speedup"))
      std::printf("speedup (median standard steps to match / inner_steps): %.1fx\n", metrics["speedup"].get<double>());
    else
      std::printf("speedup at least %.1fx (some baselines never matched)\n", metrics["speedup_at_least"].get<double>());
    if (metrics.contains("speedup_to_standard_end"))
      std::printf("speedup to the baseline's end (median baseline steps / learned steps to its last figure): %.1fx\n",
                  metrics["speedup_to_standard_end"].get<double>());
  }
  metrics["nfield_version"] = std::string(version());
  write_metrics_json(dir, metrics);
  std::printf("wrote %s (%ld outer steps, %.1f s)\n", dir.string().c_str(), result.steps, wall);
  return result.finished ? 0 : 130;
}

}  // namespace

void check_meta(const RunSetup& s) {
  const io::ConfigNode training = s.root.child_or_empty("training");
  const bool family = !instances(*s.problem, false).empty();
  if (!s.training.meta.enabled) {
    if (family && s.field.latent_size == 0)
      throw s.root.child("equation").error(
          "family", "a family of instances is trained by training.meta (a learned initialisation, "
                    "solvers/training/reptile.h) or with a latent code per instance (field.latent: {size: N}, "
                    "solvers/training/auto_decoder.h); add one, or drop equation.family to solve one signal");
    return;
  }
  const io::ConfigNode meta = training.child("meta");
  if (!family)
    throw meta.error("problem '" + s.root.get<std::string>("problem") +
                     "' has no family of instances (problem: fit with equation.family has)");
  const StageOptions& stage = s.training.stages.front();
  const io::ConfigNode stage_node = training.has("stages") ? training.child("stages").at(0) : training;
  if (stage.optimizer != "adam" || stage.options<AdamStageOptions>().schedule != "constant")
    throw stage_node.error("optimizer", "under training.meta, stages[0] is the standard initialisation's baseline "
                                        "on the held-out instances: expected an adam stage with schedule constant");
  if (s.training.has_strategies())
    throw meta.error("training.meta takes no training strategy (adaptive, causal, balance): its inner steps "
                     "are plain gradient steps");
}

int execute_meta_run(RunSetup& setup, const fs::path& resume) {
  if (!resume.empty())
    throw std::invalid_argument(resume.string() + ": a meta-learning run is not resumed; start it again, or "
                                "start a fit from its checkpoint with field.init");
  return setup.training.precision == "double" ? meta_train_and_write<double>(setup)
                                              : meta_train_and_write<float>(setup);
}

}  // namespace nfield::solvers
