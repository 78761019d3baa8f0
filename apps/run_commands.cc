// SPDX-License-Identifier: MIT
#include "apps/run_commands.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "io/hdf5_file.h"
#include "solvers/run/latent_run.h"
#include "solvers/run/run.h"

namespace nfield::apps {
namespace {

struct RunArguments {
  std::string config;
  std::vector<std::string> overrides;
  std::string out;
  std::string resume;
  std::string progress = "auto";
};

struct RenderArguments {
  std::string checkpoint;
  std::string poses;
  int frames = 36;
  double elevation = 30;
  std::string out;
  solvers::RenderCode code;
};

struct FitCodeArguments {
  std::string checkpoint;
  std::string config;
  std::vector<std::string> overrides;
  std::string out;
  bool fine_tune = false;
  std::optional<int> steps;
  std::optional<double> lr;
};

struct EvalArguments {
  std::string checkpoint;
  int grid = 128;
  std::string out;
};

// A file that is not a checkpoint is bad input (exit code 2), like a missing one.
const CLI::Validator kCheckpointFile(
    [](std::string& path) -> std::string {
      try {
        if (!io::H5Reader(path).has_group("field")) return path + ": not an nfield checkpoint (no group 'field')";
      } catch (const io::H5Error& e) {
        return e.what();
      }
      return {};
    },
    "CHECKPOINT");

void add_fit_code_command(CLI::App& app) {
  auto fit = std::make_shared<FitCodeArguments>();
  CLI::App* fit_command = app.add_subcommand(
      "fit-code", "Fit latent codes with a trained latent field (field.latent) to new signals, the field frozen");
  fit_command->add_option("checkpoint", fit->checkpoint, "A checkpoint.h5 of an auto-decoder run (field.latent)")
      ->required()
      ->check(CLI::ExistingFile)
      ->check(kCheckpointFile);
  fit_command->add_option("config", fit->config, "A config whose signals to fit: a family's held-out instances, or one signal")
      ->required()
      ->check(CLI::ExistingFile);
  fit_command->add_option("--set", fit->overrides, "Override a config value: key.path=value (repeatable)");
  fit_command->add_option("--out", fit->out, "Output folder (overrides output.dir)");
  fit_command->add_flag("--fine-tune", fit->fine_tune, "Train every parameter of the field with the code");
  fit_command->add_option("--steps", fit->steps, "Adam steps (default: training.auto_decoder.fit_steps)")
      ->check(CLI::Range(0, 1 << 24));
  fit_command->add_option("--lr", fit->lr, "Adam's rate (default: training.auto_decoder.fit_lr)")
      ->check(CLI::Range(1e-12, 1e3));
  fit_command->callback([fit] {
    solvers::RunSetup setup = solvers::load_run(fit->config, fit->overrides, fit->out);
    try {
      solvers::fit_codes(fit->checkpoint, setup, {fit->fine_tune, fit->steps, fit->lr});
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("checkpoint", e.what());
    }
  });
}

void add_render_command(CLI::App& app) {
  auto render = std::make_shared<RenderArguments>();
  CLI::App* render_command = app.add_subcommand(
      "render", "Render views of a radiance-field checkpoint: the cameras of a transforms.json, or a turntable");
  render_command->add_option("checkpoint", render->checkpoint, "A checkpoint.h5 from nfield run (problem: nerf)")
      ->required()
      ->check(CLI::ExistingFile)
      ->check(kCheckpointFile);
  render_command->add_option("--poses", render->poses, "A transforms.json whose frames give the cameras (images, when present, give PSNRs)")
      ->check(CLI::ExistingFile);
  render_command->add_option("--frames", render->frames, "Turntable: views around the scene")
      ->check(CLI::Range(1, 10000))->capture_default_str();
  render_command->add_option("--elevation", render->elevation, "Turntable: degrees above the horizontal plane")
      ->check(CLI::Range(-89.0, 89.0))->capture_default_str();
  render_command->add_option("--out", render->out, "Output folder (default: beside the checkpoint, render/)");
  render_command->add_option("--code", render->code.from,
                             "With appearance codes (data.appearance): render with this training image's code "
                             "(its name, e.g. r_3, or its row)");
  render_command->add_option("--to", render->code.to, "With --code: blend towards this image's code")
      ->needs("--code");
  render_command->add_option("--t", render->code.t, "With --to: the blend, (1 - t)·code + t·to")
      ->check(CLI::Range(0.0, 1.0))
      ->needs("--to")
      ->capture_default_str();
  render_command->callback([render] {
    const std::filesystem::path out = render->out.empty()
                                          ? std::filesystem::path(render->checkpoint).parent_path() / "render"
                                          : std::filesystem::path(render->out);
    solvers::RenderRequest request;
    request.poses = render->poses;
    request.turntable_frames = render->frames;
    request.elevation_degrees = render->elevation;
    solvers::render_checkpoint(render->checkpoint, request, out, render->code);
  });
}

}  // namespace

void add_run_commands(CLI::App& app) {
  auto run = std::make_shared<RunArguments>();
  CLI::App* run_command = app.add_subcommand("run", "Train a field on the problem a config describes and write its outputs");
  run_command->add_option("config", run->config, "The YAML config")->required()->check(CLI::ExistingFile);
  run_command->add_option("--set", run->overrides, "Override a config value: key.path=value (repeatable)");
  run_command->add_option("--out", run->out, "Output folder (overrides output.dir)");
  run_command->add_option("--resume", run->resume, "Continue from a checkpoint written by an earlier run")
      ->check(CLI::ExistingFile)
      ->check(kCheckpointFile);
  run_command
      ->add_option("--progress", run->progress,
                   "Progress lines: live (one line redrawn in place), plain (one line each, for logs), "
                   "or auto (live on a terminal, plain otherwise and under mpirun)")
      ->check(CLI::IsMember({"auto", "live", "plain"}))
      ->capture_default_str();
  run_command->callback([run] {
    solvers::RunSetup setup = solvers::load_run(run->config, run->overrides, run->out);
    if (run->progress != "auto") setup.live_progress = run->progress == "live";
    const int code = solvers::execute_run(setup, run->resume);
    if (code != 0) throw CLI::RuntimeError(code);
  });

  auto validate = std::make_shared<RunArguments>();
  CLI::App* validate_command = app.add_subcommand("validate", "Check a config and print it resolved; writes nothing");
  validate_command->add_option("config", validate->config, "The YAML config")->required()->check(CLI::ExistingFile);
  validate_command->add_option("--set", validate->overrides, "Override a config value: key.path=value (repeatable)");
  validate_command->callback([validate] {
    const solvers::RunSetup setup = solvers::load_run(validate->config, validate->overrides);
    std::printf("%s: valid\n%s\n", validate->config.c_str(), io::to_yaml(setup.resolved).c_str());
  });

  auto eval = std::make_shared<EvalArguments>();
  CLI::App* eval_command = app.add_subcommand("eval", "Sample a checkpoint's field onto a grid and write VTK and metrics.json (a fit: its signal's outputs again)");
  eval_command->add_option("checkpoint", eval->checkpoint, "A checkpoint.h5 from nfield run")
      ->required()
      ->check(CLI::ExistingFile)
      ->check(kCheckpointFile);
  eval_command->add_option("--grid", eval->grid, "Points per space axis")->check(CLI::Range(2, 4096))->capture_default_str();
  eval_command->add_option("--out", eval->out, "Output folder (default: beside the checkpoint, eval/)");
  eval_command->callback([eval] {
    const std::filesystem::path out =
        eval->out.empty() ? std::filesystem::path(eval->checkpoint).parent_path() / "eval" : std::filesystem::path(eval->out);
    solvers::evaluate_checkpoint(eval->checkpoint, eval->grid, out);
  });

  add_fit_code_command(app);
  add_render_command(app);
}

}  // namespace nfield::apps
