// SPDX-License-Identifier: MIT
//
// A meta-learning run (`training.meta`, solvers/training/reptile.h) of a family problem
// (equation.family, Problem::instances): `nfield run` learns an initialisation over the
// training instances, then measures on every held-out instance how fast a fit starts from
// it, against the standard (seeded random) initialisation. It writes into output.dir:
//
//   config.yaml            the config as resolved
//   checkpoint.h5          the learned initialisation (the field and the config; no trainer
//                          state: such a run is not resumed) for `field.init` of later runs
//   held_out_curve.csv     step, then per held-out instance its figure (fit: PSNR in dB)
//                          from the learned θ (meta_NAME) and from the standard one
//                          (standard_NAME), and their means over the instances
//   held_out/NAME/meta_S/, held_out/NAME/standard_S/
//                          the instance's own outputs (fit: reconstruction.png, error.png)
//                          after S steps, S = 0, inner_steps and curve_steps, and the
//                          standard one also after the step where it first matches the
//                          learned θ's figure after inner_steps (standard_match/)
//   metrics.json           problem, meta options, outer steps, wall_s, the last outer step's
//                          mean inner losses, per held-out instance its figures and
//                          standard_steps_to_match, and their summaries (held_out_* keys)
//
// From the learned θ the held-out fits take the inner loop's own steps (inner_optimizer at
// inner_lr) for curve_steps steps; from the standard θ they take training.stages[0], which
// must be an Adam stage of constant rate (the baseline a plain `nfield run` would train; its
// steps are how far the baseline curve goes). Both draw their points by the same seeds. The
// figure is the instance's (solvers/run/instance_outputs.h: fit, PSNR over the pixels, higher
// is better; a drawn PDE family, the grid rel_l2, lower is better). `speedup` = the median over
// the held-out instances of standard_steps_to_match / inner_steps (absent when some instance's
// baseline never matched; then `speedup_at_least` uses the baseline's length for those).
// `speedup_to_standard_end` reads the race the other way: the baseline's steps over the steps
// the learned θ takes to be as good as the baseline's last figure (meta_steps_to_standard_final
// per instance; absent unless every learned curve gets there within its curve_steps).
#pragma once

#include <filesystem>

#include "solvers/run/run_setup.h"

namespace nfield::solvers {

// The checks of training.meta against the rest of a config: a family problem, stages[0] an
// Adam stage of constant rate, no training strategy; and a family problem without
// training.meta is refused (a family has no one signal to fit). Throws io::ConfigError.
void check_meta(const RunSetup& setup);

// Runs setup (training.meta enabled) as above; `resume` must be empty. Returns 0, or 130 when
// interrupted (the initialisation reached is still written).
int execute_meta_run(RunSetup& setup, const std::filesystem::path& resume);

}  // namespace nfield::solvers
