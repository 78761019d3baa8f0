// SPDX-License-Identifier: MIT
//
// The field's options fitted to the run around them, once the problem and `training:` are
// read (load_run, solvers/run/run.cc): what a field's encoding needs of the problem and the
// stages, asked through the encoding's registry entry (fields/encoding_type.h), so that the
// run driver knows no encoding's keys.
//
//   * an encoding that reads a variance beside each coordinate (EncodingType::reads_variances,
//     integrated_positional) needs a problem that gives them (TakesInputVariances, nerf); the
//     problem then appends them to every point it hands the field;
//   * every encoding keeps the problem's domain box (EncodingOptions::lower/upper: a hash grid
//     maps it onto its levels, bacon and acorn tile it) and checks its options against the
//     run (EncodingType::check_run: cusp's from_stage must name a stage the run has).
//
// Errors are io::ConfigError at the key of `field.encoding`.
#pragma once

#include "solvers/run/run_setup.h"

namespace nfield::solvers {

void fit_field_to_run(RunSetup& setup);

}  // namespace nfield::solvers
