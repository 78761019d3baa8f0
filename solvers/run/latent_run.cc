// SPDX-License-Identifier: MIT
#include "solvers/run/latent_run.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "fields/field_io.h"
#include "io/atomic_write.h"
#include "io/pvd.h"
#include "io/text.h"
#include "io/version.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/core/solution.h"
#include "solvers/run/instance_outputs.h"
#include "solvers/run/run_metrics.h"
#include "solvers/run/run_progress.h"
#include "solvers/training/auto_decoder.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

using Metrics = std::vector<std::pair<std::string, double>>;

// An instance's progress figure under a metrics.json key: lower case (psnr).
std::optional<std::pair<std::string, double>> as_key(const std::optional<InstanceFigure>& figure) {
  if (!figure) return std::nullopt;
  return std::pair{io::to_lower(figure->name), figure->value};
}

template <typename Scalar>
void write_latent_checkpoint(const fs::path& path, const fields::Field<Scalar>& field, const LatentCodes& codes,
                             const std::vector<std::string>& names, const RunSetup& setup,
                             const std::string& config_text) {
  io::H5Writer file(path);
  fields::save_field(file, field);
  file.write("latent/codes", codes);
  file.write_attribute("latent/codes", "names", names);
  file.write_attribute("/", "config", config_text);
  file.write_attribute("/", "config_dir", fs::absolute(setup.data_dir).lexically_normal().string());
  file.write_attribute("/", "nfield_version", std::string(version()));
  file.commit();
}

void write_config_copy(const fs::path& dir, const std::string& config_text) {
  fs::create_directories(dir);
  io::write_atomically(dir / "config.yaml", [&](const fs::path& p) { std::ofstream(p) << config_text << "\n"; });
}

// One instance's outputs: its name, its metrics, and for a fitted code its progress figure
// with the code at 0 (before the fit) and the code.
struct InstanceResult {
  std::string name;
  Metrics values;  // a drawn instance's values (solvers/problems/drawn_family.h)
  Metrics metrics;
  std::optional<std::pair<std::string, double>> zero_code;
  double final_loss = 0;
  Eigen::VectorXd code;
};

nlohmann::ordered_json results_json(const std::vector<InstanceResult>& results) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const auto& r : results) {
    nlohmann::ordered_json item;
    item["name"] = r.name;
    for (const auto& [key, value] : r.values) item[key] = value;
    if (r.zero_code) item[r.zero_code->first + "_zero_code"] = r.zero_code->second;
    if (r.code.size() > 0) item["final_loss"] = r.final_loss;
    for (const auto& [key, value] : r.metrics) item[key] = value;  // NaN: null
    list.push_back(item);
  }
  return list;
}

// Per metric of the first instance: its mean, min and max over the instances that have it
// finite ({} when none has).
nlohmann::ordered_json summary_json(const std::vector<InstanceResult>& results) {
  nlohmann::ordered_json summary = nlohmann::ordered_json::object();
  if (results.empty()) return summary;
  for (const auto& [key, ignored] : results.front().metrics) {
    double sum = 0, low = std::numeric_limits<double>::infinity(), high = -low;
    int n = 0;
    for (const auto& r : results)
      for (const auto& [k, v] : r.metrics)
        if (k == key && std::isfinite(v)) {
          sum += v;
          low = std::min(low, v);
          high = std::max(high, v);
          ++n;
        }
    if (n > 0) summary[key] = {{"mean", sum / n}, {"min", low}, {"max", high}, {"count", n}};
  }
  if (results.front().zero_code) {
    double sum = 0;
    for (const auto& r : results) sum += r.zero_code->second;
    summary[results.front().zero_code->first + "_zero_code"] = {{"mean", sum / static_cast<double>(results.size())}};
  }
  return summary;
}

// An instance to fit: its name and problem (not owned).
struct Target {
  std::string name;
  const Problem* problem;
  Metrics values{};
};

std::vector<Target> targets_of(const std::vector<ProblemInstance>& instances) {
  std::vector<Target> targets;
  for (const auto& i : instances) targets.push_back({i.name, i.problem.get(), i.values});
  return targets;
}

// The summary line of a metric, when the results have it.
void print_summary(const char* what, const nlohmann::ordered_json& summary, const std::string& key) {
  if (!summary.contains(key)) return;
  std::printf("%s: %s mean %.4g, min %.4g, max %.4g\n", what, key.c_str(), summary[key]["mean"].get<double>(),
              summary[key]["min"].get<double>(), summary[key]["max"].get<double>());
}

// The metric a summary line shows: psnr_db (fit), chamfer_mean_per_diagonal (sdf), or a nerf
// view's psnr_mean (held out: psnr_right_half_mean, the half its code never saw); else the
// first one.
std::string headline(const std::vector<InstanceResult>& results, bool held_out) {
  if (results.empty() || results.front().metrics.empty()) return {};
  const std::string view_psnr = held_out ? "psnr_right_half_mean" : "psnr_mean";
  for (const std::string& wanted : {std::string("psnr_db"), std::string("chamfer_mean_per_diagonal"), view_psnr})
    for (const auto& [key, value] : results.front().metrics)
      if (key == wanted) return key;
  return results.front().metrics.front().first;
}

// Fits the field's code (or, fine-tuning, everything) to each instance from `start` (the
// trained field, code 0), writing each instance's outputs into dir/NAME.
template <typename Scalar>
std::vector<InstanceResult> fit_instances(const std::vector<Target>& targets, fields::Field<Scalar>& field,
                                          const autodiff::Vector<Scalar>& start, const RunSetup& setup, int steps,
                                          double lr, bool fine_tune, const fs::path& dir) {
  const InstanceOutputs<Scalar> outputs(setup.output, field);
  std::vector<InstanceResult> results;
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const Problem& problem = *targets[k].problem;
    field.parameters() = start;
    InstanceResult r;
    r.name = targets[k].name;
    r.values = targets[k].values;
    r.zero_code = as_key(outputs.figure(problem));
    // A progress line at most every 5 s: a fit of hundreds of steps can take tens of seconds.
    auto last_report = std::chrono::steady_clock::now();
    const auto losses = fit_code(problem, field, setup.training, steps, lr, fine_tune,
                                 setup.training.seed + 104729 * (k + 1), [&](int s) {
                                   const auto now = std::chrono::steady_clock::now();
                                   if (now - last_report < std::chrono::seconds(5)) return;
                                   last_report = now;
                                   std::printf("  %s: step %d/%d of its fit\n", r.name.c_str(), s, steps);
                                   std::fflush(stdout);
                                 });
    r.final_loss = losses.empty() ? 0.0 : losses.back();
    r.code = code_of(field);
    r.metrics = outputs.write(problem, dir / instance_stem(r.name));
    const auto after = as_key(outputs.figure(problem));
    if (r.zero_code && after)
      std::printf("  %s: %s %.4g with code 0 -> %.4g after %d steps (loss %.3e)\n", r.name.c_str(),
                  after->first.c_str(), r.zero_code->second, after->second, steps, r.final_loss);
    else
      std::printf("  %s: loss %.3e after %d steps\n", r.name.c_str(), r.final_loss, steps);
    results.push_back(std::move(r));
  }
  return results;
}

LatentCodes stack_codes(const std::vector<InstanceResult>& results, int size) {
  LatentCodes codes(static_cast<Eigen::Index>(results.size()), size);
  for (std::size_t k = 0; k < results.size(); ++k) codes.row(static_cast<Eigen::Index>(k)) = results[k].code.transpose();
  return codes;
}

// interpolation/STEP/: the first two training instances' outputs along the line between their
// codes, z = (1 − t) z_a + t z_b at t = STEP / (steps − 1), each written by instance a's
// problem (its figures are against shape a); interpolation.pvd lists the surfaces when the
// problem writes surface.vtp (sdf).
template <typename Scalar>
void write_interpolation(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                         const LatentCodes& codes, const RunSetup& setup, const fs::path& dir, int steps) {
  if (tasks.size() < 2 || steps < 2) return;
  const InstanceOutputs<Scalar> outputs(setup.output, field);
  io::PvdCollection pvd(dir / "interpolation.pvd");
  for (int s = 0; s < steps; ++s) {
    const double t = static_cast<double>(s) / (steps - 1);
    set_code(field, ((1 - t) * codes.row(0) + t * codes.row(1)).transpose());
    const fs::path folder = dir / "interpolation" / std::to_string(s);
    (void)outputs.write(*tasks[0].problem, folder);
    if (fs::exists(folder / "surface.vtp")) pvd.add(t, "interpolation/" + std::to_string(s) + "/surface.vtp");
  }
  if (!pvd.entries().empty()) pvd.write();
  std::printf("wrote interpolation/ (%d steps from %s's code to %s's)\n", steps, tasks[0].name.c_str(),
              tasks[1].name.c_str());
}

template <typename Scalar>
int latent_train_and_write(RunSetup& setup) {
  const AutoDecoderOptions& options = setup.training.auto_decoder;
  const fs::path dir = setup.output.dir;
  const std::string config_text = io::to_yaml(setup.resolved);
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  const std::vector<ProblemInstance> held_out = instances(*setup.problem, true);
  fields::Field<Scalar> field(setup.field);
  if (setup.init.parameters.size() > 0)
    field.parameters().head(setup.init.parameters.size()) = setup.init.parameters.cast<Scalar>();
  LatentCodes codes = initial_codes(static_cast<Eigen::Index>(tasks.size()), field.latent_size(), options.init_std,
                                    setup.training.seed);
  write_config_copy(dir, config_text);
  const StageOptions& stage = setup.training.stages.front();
  std::printf("auto-decoder over %zu training instances, %zu held out: %d adam steps of %d instances, codes of %d\n",
              tasks.size(), held_out.size(), stage.steps, options.instances_per_step, field.latent_size());
  const auto started = std::chrono::steady_clock::now();
  const AutoDecoderResult result = train_with_progress(setup, [&](const auto& stop_requested, const auto& progress) {
    return train_auto_decoder(tasks, field, codes, setup.training, {stop_requested, progress});
  });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!result.finished) std::printf("\ninterrupted at step %ld: writing the field and codes reached\n", result.steps);
  std::vector<std::string> names;
  for (const auto& t : tasks) names.push_back(t.name);
  write_latent_checkpoint(dir / "checkpoint.h5", field, codes, names, setup, config_text);
  const autodiff::Vector<Scalar> trained = field.parameters();

  nlohmann::ordered_json metrics;
  metrics["problem"] = setup.root.get<std::string>("problem");
  metrics["finished"] = result.finished;
  metrics["steps"] = result.steps;
  metrics["training_instances"] = tasks.size();
  metrics["held_out_instances"] = held_out.size();
  metrics["latent_size"] = field.latent_size();
  metrics["wall_s"] = wall;
  metrics["data_loss"] = result.data_loss;
  metrics["prior_loss"] = result.prior_loss;
  metrics["precision"] = setup.training.precision;
  metrics["parameters"] = field.parameter_count();
  const InstanceOutputs<Scalar> outputs(setup.output, field);
  std::vector<InstanceResult> training;
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    set_code(field, codes.row(static_cast<Eigen::Index>(k)).transpose());
    InstanceResult r;
    r.name = tasks[k].name;
    r.values = tasks[k].values;
    r.metrics = outputs.write(*tasks[k].problem, dir / "training" / instance_stem(tasks[k].name));
    training.push_back(std::move(r));
  }
  metrics["training_summary"] = summary_json(training);
  print_summary("training instances with their codes", metrics["training_summary"], headline(training, false));
  if (!held_out.empty()) {
    std::printf("held-out instances: a code each, %d adam steps at %g with the field frozen\n", options.fit_steps,
                options.fit_lr);
    const auto fitted = fit_instances(targets_of(held_out), field, trained, setup, options.fit_steps, options.fit_lr,
                                      false, dir / "held_out");
    metrics["held_out_summary"] = summary_json(fitted);
    metrics["held_out"] = results_json(fitted);
    print_summary("held-out instances, codes fitted", metrics["held_out_summary"], headline(fitted, true));
  }
  metrics["training"] = results_json(training);
  field.parameters() = trained;
  write_interpolation(tasks, field, codes, setup, dir, options.interpolation_steps);
  field.parameters() = trained;
  metrics["nfield_version"] = std::string(version());
  write_metrics_json(dir, metrics);
  std::printf("wrote %s (%ld steps, %.1f s)\n", dir.string().c_str(), result.steps, wall);
  return result.finished ? 0 : 130;
}

template <typename Scalar>
int fit_codes_with(const fs::path& checkpoint, RunSetup& setup, const FitCodeOptions& options) {
  const io::H5Reader file(checkpoint);
  fields::Field<Scalar> field = fields::load_field<Scalar>(file);
  if (field.latent_size() == 0)
    throw std::invalid_argument(checkpoint.string() + ": its field takes no latent code (trained without field.latent)");
  const Problem& problem = *setup.problem;
  if (field.input_dim() != problem.field_input_dim() || field.output_dim() != problem.output_dim())
    throw std::invalid_argument(checkpoint.string() + ": its field maps " + std::to_string(field.input_dim()) +
                                " inputs to " + std::to_string(field.output_dim()) + " outputs; " +
                                setup.config_path.string() + "'s problem needs " +
                                std::to_string(problem.field_input_dim()) + " to " + std::to_string(problem.output_dim()));
  set_code(field, Eigen::VectorXd::Zero(field.latent_size()));
  // A family's new signals are its held-out instances; any other problem is one signal.
  const std::vector<ProblemInstance> held_out = instances(problem, true);
  std::vector<Target> targets = targets_of(held_out);
  if (instances(problem, false).empty()) targets = {{setup.config_path.filename().string(), &problem}};
  if (targets.empty())
    throw std::invalid_argument(setup.config_path.string() + ": the family has no held-out instances to fit a code to "
                                "(equation.family.held_out)");
  const AutoDecoderOptions& ad = setup.training.auto_decoder;
  const int steps = options.steps.value_or(ad.fit_steps);
  const double lr = options.lr.value_or(ad.fit_lr);
  const fs::path dir = setup.output.dir;
  const std::string config_text = io::to_yaml(setup.resolved);
  write_config_copy(dir, config_text);
  std::printf("fitting %s to %zu instance%s: %d adam steps at %g%s\n", options.fine_tune ? "the field and a code" : "a code",
              targets.size(), targets.size() == 1 ? "" : "s", steps, lr, options.fine_tune ? "" : " with the field frozen");
  const autodiff::Vector<Scalar> start = field.parameters();
  const auto started = std::chrono::steady_clock::now();
  const std::vector<InstanceResult> fitted = fit_instances(targets, field, start, setup, steps, lr, options.fine_tune, dir);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::vector<std::string> names;
  for (const auto& f : fitted) names.push_back(f.name);
  // A fine-tuned field is the last instance's; a frozen one is the checkpoint's.
  if (!options.fine_tune) field.parameters() = start;
  set_code(field, Eigen::VectorXd::Zero(field.latent_size()));
  write_latent_checkpoint(dir / "checkpoint.h5", field, stack_codes(fitted, field.latent_size()), names, setup,
                          config_text);
  nlohmann::ordered_json metrics;
  metrics["problem"] = setup.root.get<std::string>("problem");
  metrics["checkpoint"] = fs::absolute(checkpoint).lexically_normal().string();
  metrics["fine_tune"] = options.fine_tune;
  metrics["steps"] = steps;
  metrics["lr"] = lr;
  metrics["wall_s"] = wall;
  metrics["summary"] = summary_json(fitted);
  metrics["instances"] = results_json(fitted);
  metrics["nfield_version"] = std::string(version());
  write_metrics_json(dir, metrics);
  print_summary("codes fitted", metrics["summary"], headline(fitted, true));
  std::printf("wrote %s (%.1f s)\n", dir.string().c_str(), wall);
  return 0;
}

}  // namespace

bool is_latent_run(const RunSetup& s) { return s.field.latent_size > 0 && !instances(*s.problem, false).empty(); }

void check_latent(const RunSetup& s) {
  const io::ConfigNode training = s.root.child_or_empty("training");
  const io::ConfigNode field = s.root.child_or_empty("field");
  if (s.training.auto_decoder.given && s.field.latent_size == 0)
    throw training.child("auto_decoder").error("training.auto_decoder trains a latent code per instance: add "
                                               "field.latent: {size: N}");
  if (s.field.latent_size == 0) return;
  if (instances(*s.problem, false).empty()) return;  // one signal: a code among the weights (nfield fit-code's use)
  if (s.training.meta.enabled)
    throw training.child("meta").error("training.meta and field.latent are two ways to train over a family; "
                                       "choose one");
  if (s.training.stages.size() != 1 || s.training.stages.front().optimizer != "adam") {
    const std::string rule = "an auto-decoder run (field.latent over a family) trains the field and its codes by one adam stage";
    throw training.has("stages") ? training.error("stages", rule) : field.error("latent", rule);
  }
  if (s.training.has_strategies())
    throw field.error("latent", "an auto-decoder run takes no training strategy (adaptive, causal, balance)");
}

int execute_latent_run(RunSetup& setup, const fs::path& resume) {
  if (!resume.empty())
    throw std::invalid_argument(resume.string() + ": an auto-decoder run is not resumed; start it again");
  return setup.training.precision == "double" ? latent_train_and_write<double>(setup)
                                              : latent_train_and_write<float>(setup);
}

int fit_codes(const fs::path& checkpoint, RunSetup& setup, const FitCodeOptions& options) {
  return setup.training.precision == "double" ? fit_codes_with<double>(checkpoint, setup, options)
                                              : fit_codes_with<float>(checkpoint, setup, options);
}

}  // namespace nfield::solvers
