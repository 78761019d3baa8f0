// SPDX-License-Identifier: MIT
//
// A run of a family (equation.family, Problem::instances) whose field takes a latent code
// (field.latent; training.auto_decoder; the algorithm: solvers/training/auto_decoder.h).
// `nfield run` trains the field and one code per training instance, then fits a code to each
// held-out instance with the field frozen. It writes into output.dir:
//
//   config.yaml         the config as resolved
//   checkpoint.h5       the field (its own code slot at 0), and /latent/codes (K × c, one row
//                       per training instance; attribute names, the instances' names) for
//                       `nfield fit-code` and h5py
//   training/NAME/      each training instance's outputs with its code (fit: reconstruction.png,
//                       error.png; nerf with data.appearance: view/, the image rendered)
//   held_out/NAME/      each held-out instance's outputs after its code fit
//   interpolation/S/    the first two training instances' outputs along the line between
//                       their codes, S = 0 … interpolation_steps − 1, drawn by the first one's
//                       problem; interpolation.pvd lists their surfaces (sdf) as a series
//   metrics.json        problem, steps, wall_s, the last step's data and prior losses;
//                       `training` and `held_out`: per instance the metrics its outputs give
//                       (fit: psnr, …; sdf: chamfer_mean_per_diagonal, …; nerf: psnr_mean and
//                       psnr_right_half_mean, the half a held-out code never saw), held-out ones also
//                       their progress figure with the code at 0 (psnr_zero_code) and the fit's
//                       final loss; `training_summary` and `held_out_summary`: per metric its
//                       mean, min, max and count over the instances
//
// `nfield fit-code CHECKPOINT CONFIG [--fine-tune] [--steps N] [--lr X]` (fit_codes below)
// fits codes with a trained field to the signals of CONFIG: the held-out instances of a
// family, or the one signal of any other fit. CONFIG gives the problem, the training options
// (precision, batch, threads, seed, training.auto_decoder's prior, fit_steps, fit_lr) and
// output.dir; the field is the checkpoint's. It writes NAME/ per instance, checkpoint.h5 (the
// field, fine-tuned or not, and /latent/codes of the fitted codes) and metrics.json (`instances`
// and `summary` as above).
#pragma once

#include <filesystem>
#include <optional>

#include "solvers/run/run_setup.h"

namespace nfield::solvers {

// The checks of field.latent and training.auto_decoder against the rest of a config: codes
// are trained over a family, under no training.meta and no training strategy, by one Adam
// stage; training.auto_decoder without field.latent is refused. Throws io::ConfigError.
void check_latent(const RunSetup& setup);

// Whether `setup` is a latent-code run (a family whose field takes a code).
bool is_latent_run(const RunSetup& setup);

// Runs setup as above; `resume` must be empty. Returns 0, or 130 when interrupted (the codes
// and field reached are still written).
int execute_latent_run(RunSetup& setup, const std::filesystem::path& resume);

struct FitCodeOptions {
  bool fine_tune = false;        // every parameter moves, not only the code
  std::optional<int> steps;      // unset: training.auto_decoder.fit_steps of the config
  std::optional<double> lr;      // unset: its fit_lr
};

// `nfield fit-code`: fits codes with the latent field of `checkpoint` to `setup`'s signals.
// Throws std::invalid_argument when the checkpoint's field takes no code or does not fit the
// problem's inputs and outputs. Returns 0.
int fit_codes(const std::filesystem::path& checkpoint, RunSetup& setup, const FitCodeOptions& options);

}  // namespace nfield::solvers
