// SPDX-License-Identifier: MIT
#include "solvers/run/run.h"


#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>

#include "fields/acorn.h"
#include "fields/field_branches.h"
#include "fields/field_config.h"
#include "fields/field_io.h"
#include "solvers/output/block_output.h"
#include "solvers/output/unknowns_output.h"
#include "fields/field_type.h"
#include "io/atomic_write.h"
#include "io/version.h"
#include "solvers/geometry/geometry.h"
#include "solvers/output/grid_output.h"
#include "solvers/core/solution.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/training/communicator.h"
#include "solvers/training/progress_printer.h"
#include "solvers/training/trainer.h"
#include "solvers/run/field_setup.h"
#include "solvers/run/latent_run.h"
#include "solvers/training/auto_decoder.h"
#include "solvers/run/meta_run.h"
#include "solvers/run/stop_signal.h"
#include "solvers/run/run_metrics.h"

namespace nfield::solvers {
namespace {

OutputOptions output_options(const io::ConfigNode& node, const Domain& domain,
                             const std::filesystem::path& config,
                             const std::filesystem::path& out_override) {
  OutputOptions o;
  o.dir = node.get_or("dir", ("out/" + config.stem().string()));
  node.require("dir", !o.dir.empty(), "expected a folder name, got an empty string");
  if (!out_override.empty()) o.dir = out_override;
  const int d = domain.space_dim();
  const int fallback = d == 1 ? 256 : d == 2 ? 128 : 48;
  o.grid.assign(d, fallback);
  if (node.has("grid")) {
    o.grid = node.get_list<int>("grid", static_cast<std::size_t>(d));
    for (int g : o.grid) node.require("grid", g >= 2 && g <= 4096, "expected point counts in [2, 4096]");
  }
  if (node.has("frames")) o.frames = node.get_in_range("frames", 1, 10000);
  o.png = node.get_or("png", true);
  node.reject_unknown_keys();
  return o;
}

YAML::Node output_yaml(const OutputOptions& o) {
  YAML::Node n;
  n["dir"] = o.dir.string();
  n["grid"] = o.grid;
  n["frames"] = o.frames;
  n["png"] = o.png;
  return n;
}


// The scales of a multiscale field (fields/field.h) for outputs that write each one.
template <typename Scalar>
void set_scales(const fields::Field<Scalar>& field, std::shared_ptr<const Ansatz> ansatz, OutputContext& context) {
  context.scales = field.scales();
  context.output_scale = field.output_scale();
  context.scale_cutoffs = fields::field_type(field.options().type).scale_cutoffs(field.options());
  context.scale_values = scale_values(field, std::move(ansatz));
}

// What the outputs read of a trained field: its solution, in the field's precision.
template <typename Scalar>
OutputContext output_context(const std::filesystem::path& dir, const Solution& solution, const RunSetup& setup,
                             const fields::Field<Scalar>& field) {
  OutputContext context{dir, solution.values, setup.output.grid, solution.streams,
                        std::numeric_limits<Scalar>::epsilon()};
  set_scales(field, setup.problem->ansatz(), context);
  return context;
}

template <typename Scalar>
void write_checkpoint(const std::filesystem::path& path, const fields::Field<Scalar>& field,
                      const Trainer<Scalar>& trainer, const Problem& problem,
                      const std::string& config_text, const std::filesystem::path& config_dir) {
  io::H5Writer file(path);
  fields::save_field(file, field);
  trainer.save_state(file);
  if (const auto* state = capability<KeepsState>(problem)) state->save_state(file);
  file.write_attribute("/", "config", config_text);
  // Relative data paths in the config (point clouds, images) resolve against this folder.
  file.write_attribute("/", "config_dir", config_dir.string());
  file.write_attribute("/", "nfield_version", std::string(version()));
  file.commit();
}

// Puts the state of checkpoint `resume` back: the network's parameters (the unknown
// constants, θ's tail, come back with the trainer's state), the trainer's and the problem's.
template <typename Scalar>
void resume_from(const std::filesystem::path& resume, RunSetup& setup, fields::Field<Scalar>& field,
                 Trainer<Scalar>& trainer, bool root) {
  const io::H5Reader file(resume);
  const fields::Field<Scalar> saved = fields::load_field<Scalar>(file);
  if (saved.parameter_count() != field.network_parameter_count())
    throw std::runtime_error(resume.string() + ": its field has " +
                             std::to_string(saved.parameter_count()) +
                             " parameters, the config's has " +
                             std::to_string(field.network_parameter_count()));
  // The network's part; unknown constants (θ's tail) come back with the trainer's state.
  field.parameters().head(saved.parameter_count()) = saved.parameters();
  fields::restore_block_tree(saved.options(), field.options());  // an acorn field's blocks
  trainer.load_state(file);
  if (auto* state = capability<KeepsState>(*setup.problem)) state->load_state(file);
  if (root) {
    std::printf("resuming from %s at step %ld\n", resume.string().c_str(), trainer.step());
    // A finished run resumed with the same stages has nothing left to train: say so rather
    // than write the same outputs again as if the run had trained.
    if (trainer.remaining_stages() == 0)
      std::printf("note: that run finished all %zu stages of training.stages; nothing is trained, the outputs "
                  "are written again (to train further, add a stage)\n",
                  setup.training.stages.size());
  }
}

// The unknown constants' final values and trajectories into `metrics`, their plot beside it.
template <typename Scalar>
void report_unknowns(Trainer<Scalar>& trainer, const std::filesystem::path& dir, nlohmann::ordered_json& metrics) {
  const UnknownConstants* unknowns = trainer.unknowns().constants();
  if (!unknowns) return;
  UnknownTrajectory trajectory;
  const auto& samples = trainer.unknowns().trajectory();
  trajectory.values.resize(static_cast<Eigen::Index>(samples.size()), unknowns->count());
  for (std::size_t s = 0; s < samples.size(); ++s) {
    trajectory.steps.push_back(samples[s].step);
    for (int i = 0; i < unknowns->count(); ++i)
      trajectory.values(static_cast<Eigen::Index>(s), i) = samples[s].values[static_cast<std::size_t>(i)];
  }
  metrics["unknowns"] = unknowns_metrics(*unknowns, trajectory);
  write_unknowns_plot(dir / "unknowns.png", *unknowns, trajectory);
  std::printf("%s\n", unknowns_line(*unknowns).c_str());
}

// After training, on every rank (collective): how far the ranks' parameters (the network's,
// unknown fields' networks', unknown constants' ρ) are from rank 0's, 0 when they stayed in
// step as the design says they must (solvers/training/communicator.h); rank 0 warns otherwise.
template <typename Scalar>
double parameter_spread(Communicator& communicator, const fields::Field<Scalar>& field) {
  const double spread = spread_over_ranks(communicator, field.parameters().data(),
                                          static_cast<std::size_t>(field.parameter_count()));
  if (communicator.rank() == 0 && spread != 0.0)
    std::printf("warning: the MPI ranks' parameters differ after training (summed largest difference "
                "%.3e); the outputs are rank 0's\n", spread);
  return spread;
}

// The output folder with the resolved config in it, before training.
void start_output(const std::filesystem::path& dir, const std::string& config_text, int ranks) {
  std::filesystem::create_directories(dir);
  io::write_atomically(dir / "config.yaml", [&](const std::filesystem::path& p) { std::ofstream(p) << config_text << "\n"; });
  if (ranks > 1) std::printf("training over %d MPI ranks, each step's points split between them\n", ranks);
}

// Rank 0's callbacks: progress lines with the problem's own figures (refreshed at most every
// 10 s: they may render), the error after each stage, and checkpoints.
template <typename Scalar>
void add_root_callbacks(typename Trainer<Scalar>::Callbacks& callbacks, ProgressPrinter& printer,
                        const RunSetup& setup, const OutputContext& context, const Solution& solution,
                        std::function<void()> checkpoint) {
  const auto* reports = capability<ReportsProgress>(*setup.problem);
  callbacks.progress = [&printer, &context, reports, figures = std::vector<std::pair<std::string, double>>{},
                        figured = std::chrono::steady_clock::now()](const Progress& p) mutable {
    if (reports && std::chrono::steady_clock::now() - figured >= std::chrono::seconds(10)) {
      figures = reports->progress_metrics(context, {p.steps_per_second, p.term_points, p.term_groups});
      figured = std::chrono::steady_clock::now();
    }
    if (figures.empty()) return printer.step(p);
    Progress shown = p;
    shown.extras.insert(shown.extras.end(), figures.begin(), figures.end());
    printer.step(shown);
  };
  callbacks.stage_begins = [&printer](const Progress& p) { printer.stage_begins(p); };
  callbacks.notice = [&printer](const std::string& line) { printer.notice(line); };
  callbacks.stage_error = [&setup, &context, &solution] {
    if (const std::optional<double> error = setup.problem->reported_error(context)) return *error;
    return setup.problem->has_exact() && setup.problem->writes_grid_outputs()
               ? grid_error(*setup.problem, solution.streams, setup.output).rel_l2
               : std::numeric_limits<double>::quiet_NaN();
  };
  callbacks.checkpoint = std::move(checkpoint);
}

template <typename Scalar>
int train_and_write(RunSetup& setup, const std::filesystem::path& resume) {
  const std::filesystem::path dir = setup.output.dir;
  const std::string config_text = io::to_yaml(setup.resolved);
  const std::filesystem::path config_dir =
      std::filesystem::absolute(setup.data_dir).lexically_normal();
  fields::Field<Scalar> field(setup.field);
  if (setup.init.parameters.size() > 0)  // field.init; --resume below replaces it
    field.parameters().head(setup.init.parameters.size()) = setup.init.parameters.cast<Scalar>();
  // Under mpirun every rank trains (solvers/training/trainer.h); rank 0 alone prints and
  // writes the config, checkpoints, outputs and metrics.
  Communicator& communicator = world_communicator();
  const bool root = communicator.rank() == 0;
  Trainer<Scalar> trainer(*setup.problem, field, setup.training, &communicator);
  if (!resume.empty()) resume_from(resume, setup, field, trainer, root);
  const long first_step = trainer.step();
  if (root) start_output(dir, config_text, communicator.size());

  // The field as everything after training sees it, wrapped once: with hard conditions
  // u = A + D·N, not the network N.
  const Solution solution = make_solution(field, setup.problem->ansatz());
  const OutputContext context = output_context(dir, solution, setup, field);
  const auto started = std::chrono::steady_clock::now();
  bool finished;
  {
    StopSignalGuard guard;
    ProgressPrinterOptions printing;
    printing.log_every = setup.training.log_every;
    printing.terminal = setup.live_progress;
    ProgressPrinter printer(printing);
    typename Trainer<Scalar>::Callbacks callbacks;
    callbacks.stop_requested = [] { return StopSignalGuard::stop_requested(); };
    if (auto* sampling = capability<SamplesWithSolution>(*setup.problem))
      callbacks.before_draw = [sampling, &solution](long step, Random& rng) { sampling->before_step(step, solution, rng); };
    if (!root) {
      // The other ranks only train; an error is rank 0's to compute and write.
      callbacks.stage_error = [] { return std::numeric_limits<double>::quiet_NaN(); };
      finished = trainer.run(callbacks);
      parameter_spread(communicator, field);
      // Wait for rank 0's outputs: mpirun ends the whole job when one rank exits with 130.
      communicator.any(false);
      return finished ? 0 : trainer.divergence() ? kExitDiverged : 130;
    }
    add_root_callbacks<Scalar>(callbacks, printer, setup, context, solution, [&] {
      write_checkpoint(dir / "checkpoint.h5", field, trainer, *setup.problem, config_text, config_dir);
    });
    finished = trainer.run(callbacks);
  }
  const double spread = parameter_spread(communicator, field);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (const auto& d = trainer.divergence())
    std::printf(d->last_finite_step > 0
                    ? "diverged: writing the checkpoint and outputs of the last finite parameters (step %ld)\n"
                    : "diverged: writing the checkpoint and outputs of the parameters the run started from\n",
                d->last_finite_step);
  else if (!finished)
    std::printf("\ninterrupted at step %ld: writing the checkpoint and outputs\n", trainer.step());
  write_checkpoint(dir / "checkpoint.h5", field, trainer, *setup.problem, config_text, config_dir);

  const GridMetrics grid =
      setup.problem->writes_grid_outputs()
          ? write_grid_outputs(*setup.problem, solution.streams, setup.output, &context)
          : GridMetrics{};
  std::vector<std::pair<std::string, double>> extra;
  OutputContext final_context = context;
  final_context.field_as_last_reported = finished;  // the trainer reports an error only at a completed stage's end
  setup.problem->write_outputs(final_context, extra);
  write_block_outputs(field.options(), dir);  // an acorn field's blocks (blocks.vtp)

  nlohmann::ordered_json metrics =
      run_metrics(setup, trainer, field, finished, wall, grid, extra, first_step, communicator);
  report_unknowns(trainer, dir, metrics);
  if (communicator.size() > 1) metrics["mpi_parameter_spread"] = spread;
  metrics["nfield_version"] = std::string(version());
  write_metrics_json(dir, metrics);
  std::printf("wrote %s (steps %ld, %.1f s", dir.string().c_str(), trainer.step(), wall);
  if (grid.has_error) std::printf(", rel_l2 %.3e, max_abs_err %.3e", grid.rel_l2, grid.max_abs_err);
  std::printf(")\n");
  if (communicator.size() > 1) communicator.any(false);  // the other ranks wait for this
  return finished ? 0 : trainer.divergence() ? kExitDiverged : 130;
}

// Stages whose optimizer cannot take the problem (an lm stage's dense Jacobian has to fit
// Ceres' int-indexed matrices; it takes no term over groups of points) are reported at load
// time, not after the stages before them have run (the optimizer checks again when its stage
// starts).
void check_stage_sizes(const RunSetup& s) {
  std::optional<double> rows;
  std::optional<Eigen::Index> parameters;
  std::optional<std::string> grouped;
  const ProblemSize size{
      .residual_rows =
          [&] {
            // The batch of each term, plus the points strategies add to the PDE term (RAR).
            if (!rows) {
              const std::vector<LossTerm> terms = s.problem->loss_terms();
              Random rng(0);
              rows = 0;
              for (size_t k = 0; k < terms.size(); ++k) {
                double points = terms[k].batch_key.empty()
                                    ? static_cast<double>(terms[k].sample(rng, 0).residual_rows())
                                    : static_cast<double>(s.training.batch.at(terms[k].batch_key));
                if (static_cast<int>(k) == s.problem->residual_term())
                  for (const auto& strategy : s.training.strategies)
                    if (strategy->enabled()) points += static_cast<double>(strategy->extra_points());
                *rows += points * terms[k].residual(terms[k].sample(rng, 1))->components();
              }
            }
            return *rows;
          },
      .parameters =
          [&] {
            if (!parameters) parameters = fields::Field<double>(s.field).parameter_count();
            return *parameters;
          },
      .grouped_term =
          [&] {
            if (!grouped) {
              grouped.emplace();
              Random rng(0);
              for (const LossTerm& term : s.problem->loss_terms()) {
                const TermPoints points = term.sample(rng, 1);
                if (!points.groups.empty() || points.tangents.size() > 0) {
                  *grouped = term.name;
                  break;
                }
              }
            }
            return *grouped;
          }};
  for (std::size_t i = 0; i < s.training.stages.size(); ++i) {
    // A stage with batch_scale k draws k times the points (an upper bound: RAR's set is not scaled).
    ProblemSize stage_size = size;
    stage_size.residual_rows = [&size, k = s.training.stages[i].batch_scale] { return k * size.residual_rows(); };
    const std::string refusal = s.training.stages[i].settings->refuse(stage_size);
    if (!refusal.empty())
      throw s.root.child("training").child("stages").at(i).error("optimizer", refusal);
  }
}

// The batch keys are the problem's loss-term kinds: a misspelled one is an error, and the
// resolved config lists only those the problem draws.
void check_batch_keys(RunSetup& s) {
  std::vector<std::string> batch_keys;
  for (const LossTerm& term : s.problem->loss_terms()) {
    if (term.batch_key.empty()) continue;  // draws its own points (measurements)
    if (!s.training.batch.count(term.batch_key))
      throw s.root.child_or_empty("training").error(
          "batch", "needs an entry '" + term.batch_key + "' for the loss term '" + term.name + "'");
    if (std::find(batch_keys.begin(), batch_keys.end(), term.batch_key) == batch_keys.end())
      batch_keys.push_back(term.batch_key);
  }
  // The common kinds stay valid when a problem does not draw them (boundary when every
  // condition is hard, initial without time): one config can switch such options.
  if (s.root.child_or_empty("training").has("batch")) {
    std::vector<std::string> allowed = batch_keys;
    for (const char* common : {"interior", "boundary", "initial"})
      if (std::find(allowed.begin(), allowed.end(), common) == allowed.end()) allowed.push_back(common);
    s.root.child("training").child("batch").expect_keys(allowed);
  }
  std::erase_if(s.training.batch, [&](const auto& entry) {
    return std::find(batch_keys.begin(), batch_keys.end(), entry.first) == batch_keys.end();
  });
}

// Unknown fields with networks of their own become the field's branches (fields/field_branches.h).
void set_field_branches(RunSetup& s, std::vector<fields::FieldBranch> branches) {
  if (branches.empty()) return;
  for (fields::FieldBranch& branch : branches) branch.options.seed = s.field.seed;
  s.field.branches = std::move(branches);
  try {
    fields::validate_branches(s.field);
  } catch (const std::invalid_argument& e) {
    throw s.root.child_or_empty("field").error("type", std::string(e.what()) + " (unknown_fields with hidden)");
  }
}

// A field type without a stream that a loss term needs (acorn: no second derivatives) is
// refused at field.type here, before anything is written, not at the first training step.
void check_field_streams(const RunSetup& s) {
  const fields::FieldType& type = fields::field_type(s.field.type);
  for (const LossTerm& term : s.problem->loss_terms()) {
    const std::string refusal = type.refused_streams(term.spec);
    if (!refusal.empty())
      throw s.root.child_or_empty("field").error(
          "type", "'" + s.field.type + "' " + refusal + "; the loss term '" + term.name + "' needs them");
  }
}

// A multiscale field's band limits, for a problem with a target per scale.
void give_scale_cutoffs(RunSetup& s) {
  auto* targets = capability<HasScaleTargets>(*s.problem);
  const fields::FieldType& type = fields::field_type(s.field.type);
  if (targets && type.output_scales(s.field) > 1)
    targets->set_scale_cutoffs(type.scale_cutoffs(s.field), type.output_scale(s.field));
}

// The setup of a config already parsed; `config` names it (and its folder is the default
// data folder).
RunSetup setup_run(io::ConfigNode root, const std::filesystem::path& config,
                   const std::filesystem::path& out_dir_override,
                   const std::filesystem::path& data_dir) {
  RunSetup s{.config_path = config, .root = std::move(root)};
  // A bare file name ("nfield run poisson.yaml") has an empty parent: its folder is ".".
  s.data_dir = !data_dir.empty()         ? data_dir
               : config.has_parent_path() ? config.parent_path()
                                          : std::filesystem::path(".");
  s.root.get_choice("problem", problem_names());
  s.problem = make_problem({s.root, s.data_dir});
  s.training = TrainingOptions::from_config(s.root.child_or_empty("training"));
  (void)s.root.child_or_empty("field").has("init");  // read below, once the field's shape is known
  s.field = fields::field_options_from_config(s.root.child_or_empty("field"),
                                              s.problem->field_input_dim(),
                                              s.problem->output_dim(), s.training.seed,
                                              s.problem->domain().input_names(),
                                              s.problem->default_sine_frequencies());
  if (const auto* branched = capability<HasFieldBranches>(*s.problem)) set_field_branches(s, branched->field_branches());
  fit_field_to_run(s);  // the encoding: input variances, domain box, stages
  give_scale_cutoffs(s);
  check_field_streams(s);
  s.init = read_field_init(s.root.child_or_empty("field"), s.field, s.data_dir);
  check_latent(s);
  check_meta(s);
  s.output = output_options(s.root.child_or_empty("output"), s.problem->domain(), config,
                            out_dir_override);
  check_batch_keys(s);
  for (const auto& strategy : s.training.strategies)
    if (strategy->enabled()) strategy->check(s.root.child_or_empty("training"), *s.problem);
  check_stage_sizes(s);
  s.root.child_or_empty("training").reject_unknown_keys();
  s.root.reject_unknown_keys_recursive();
  s.resolved = YAML::Clone(s.root.yaml());
  s.resolved["training"] = s.training.to_yaml();
  s.resolved["field"] = fields::to_yaml(s.field, s.problem->domain().input_names());
  if (!s.init.text.empty()) s.resolved["field"]["init"] = s.init.text;
  s.resolved["output"] = output_yaml(s.output);
  return s;
}

}  // namespace

RunSetup load_run(const std::filesystem::path& config, const std::vector<std::string>& overrides,
                  const std::filesystem::path& out_dir_override,
                  const std::filesystem::path& data_dir) {
  return setup_run(io::load_config(config, overrides), config, out_dir_override, data_dir);
}

int execute_run(RunSetup& setup, const std::filesystem::path& resume) {
  if (setup.training.meta.enabled) return execute_meta_run(setup, resume);
  if (is_latent_run(setup)) return execute_latent_run(setup, resume);
  return setup.training.precision == "double" ? train_and_write<double>(setup, resume)
                                              : train_and_write<float>(setup, resume);
}

namespace {
// The folder a checkpoint's relative data paths resolve in. Checkpoints written before
// config_dir existed: the cwd.
std::filesystem::path checkpoint_data_dir(const io::H5Reader& file) {
  return file.has_attribute("/", "config_dir")
             ? std::filesystem::path(file.read_attribute<std::string>("/", "config_dir"))
             : std::filesystem::current_path();
}

// The run a checkpoint was trained by, its config copied into out_dir (messages name the copy).
RunSetup checkpoint_run(const io::H5Reader& file, const std::filesystem::path& out_dir) {
  const std::string config_text = file.read_attribute<std::string>("/", "config");
  const std::filesystem::path config_copy = out_dir / "config.yaml";
  std::filesystem::create_directories(out_dir);
  io::write_atomically(config_copy, [&](const std::filesystem::path& p) { std::ofstream(p) << config_text; });
  return load_run(config_copy, {}, out_dir, checkpoint_data_dir(file));
}
}  // namespace

RunSetup load_checkpoint_run(const io::H5Reader& file) {
  const std::filesystem::path name = file.path().string() + ":config";
  return setup_run(io::parse_config(file.read_attribute<std::string>("/", "config"), name.string()),
                   name, {}, checkpoint_data_dir(file));
}

namespace {

// The row of /latent/codes that `argument` (an instance name, its stem, or a row index) names.
Eigen::Index code_row(const std::vector<std::string>& names, const std::string& argument, const char* option,
                      const std::filesystem::path& checkpoint) {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == argument || std::filesystem::path(names[k]).stem().string() == argument)
      return static_cast<Eigen::Index>(k);
  if (!argument.empty() && argument.find_first_not_of("0123456789") == std::string::npos && argument.size() < 10) {
    const long k = std::stol(argument);
    if (k < static_cast<long>(names.size())) return k;
  }
  std::string valid;
  for (std::size_t k = 0; k < names.size() && k < 12; ++k) valid += (k ? ", " : "") + names[k];
  if (names.size() > 12) valid += ", …";
  throw std::invalid_argument(std::string(option) + " " + argument + ": " + checkpoint.string() + " holds no code of "
                              "that name or row; its " + std::to_string(names.size()) + " training images are " +
                              valid + " (rows 0 to " + std::to_string(names.size() - 1) + ")");
}

// The code `choice` names in a checkpoint's /latent/codes; nullopt when it names none.
std::optional<Eigen::VectorXd> chosen_code(const io::H5Reader& file, const std::filesystem::path& checkpoint,
                                           const RenderCode& choice) {
  if (choice.from.empty() && choice.to.empty()) return std::nullopt;
  if (choice.from.empty()) throw std::invalid_argument("--to " + choice.to + ": expected --code too (the code at t = 0)");
  if (!file.has_dataset("latent/codes"))
    throw std::invalid_argument("--code " + choice.from + ": " + checkpoint.string() +
                                " holds no latent codes (a run with data.appearance and field.latent writes them)");
  const Eigen::MatrixXd codes = file.read_matrix<double>("latent/codes");
  const auto names = file.read_attribute<std::vector<std::string>>("latent/codes", "names");
  Eigen::VectorXd z = codes.row(code_row(names, choice.from, "--code", checkpoint)).transpose();
  if (!choice.to.empty()) {
    const Eigen::VectorXd to = codes.row(code_row(names, choice.to, "--to", checkpoint)).transpose();
    z = (1 - choice.t) * z + choice.t * to;
  }
  return z;
}

}  // namespace

void render_checkpoint(const std::filesystem::path& checkpoint, const RenderRequest& request,
                       const std::filesystem::path& out_dir, const RenderCode& code) {
  const io::H5Reader file(checkpoint);
  const std::optional<Eigen::VectorXd> z = chosen_code(file, checkpoint, code);
  RunSetup setup = checkpoint_run(file, out_dir);
  const auto* renders = capability<RendersViews>(*setup.problem);
  if (!renders)
    throw std::invalid_argument(checkpoint.string() + ": problem '" + setup.root.get<std::string>("problem") +
                                "' renders no images (nfield render takes a radiance-field checkpoint, problem: nerf)");
  if (auto* state = capability<KeepsState>(*setup.problem)) state->load_state(file);
  // In the precision it was trained in (a float field renders about twice as fast).
  const auto render = [&](auto field) {
    if (z) set_code(field, *z);
    else if (field.latent_size() > 0 && file.has_dataset("latent/codes"))
      std::printf("rendering with the code at 0, the codes' prior mean (--code NAME: a training image's appearance)\n");
    const Solution solution = make_solution(field, setup.problem->ansatz());
    renders->render_views(output_context(out_dir, solution, setup, field), request);
  };
  if (setup.training.precision == "float") render(fields::load_field<float>(file));
  else render(fields::load_field<double>(file));
}

nlohmann::ordered_json evaluate_checkpoint(const std::filesystem::path& checkpoint, int grid_points,
                                           const std::filesystem::path& out_dir) {
  const io::H5Reader file(checkpoint);
  RunSetup setup = checkpoint_run(file, out_dir);
  if (is_latent_run(setup))
    throw std::runtime_error(checkpoint.string() + ": the field and latent codes of a family (field.latent); its "
                                "outputs per instance are in its run's training/ and held_out/ folders, and "
                                "`nfield fit-code` fits codes to new signals");
  setup.output.grid.assign(setup.problem->domain().space_dim(), grid_points);
  if (capability<RendersViews>(*setup.problem))
    throw std::runtime_error(checkpoint.string() + ": problem '" + setup.root.get<std::string>("problem") +
                             "' renders views instead of a grid: `nfield render " + checkpoint.string() + "`");
  const fields::Field<double> field = fields::load_field<double>(file);
  const Solution solution = make_solution(field, setup.problem->ansatz());
  const OutputContext context = output_context(out_dir, solution, setup, field);
  // A problem without grid outputs (a fit) writes only its own: the signal at its samples.
  const GridMetrics grid = setup.problem->writes_grid_outputs()
                               ? write_grid_outputs(*setup.problem, solution.streams, setup.output, &context)
                               : GridMetrics{};
  std::vector<std::pair<std::string, double>> extra;
  setup.problem->write_outputs(context, extra);  // a reference.file's errors, printed as the run prints them
  nlohmann::ordered_json metrics = eval_metrics(setup, grid, extra);
  write_metrics_json(out_dir, metrics);
  std::printf("wrote %s", out_dir.string().c_str());
  if (grid.has_error) std::printf(" (rel_l2 %.3e, max_abs_err %.3e)", grid.rel_l2, grid.max_abs_err);
  std::printf("\n");
  return metrics;
}

}  // namespace nfield::solvers
