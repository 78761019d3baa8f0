// SPDX-License-Identifier: MIT
//
// `field.init: CHECKPOINT`: a run whose field starts from the network of a checkpoint (a
// meta-learned initialisation, solvers/training/reptile.h, or any earlier run) instead of
// its seeded random initialisation. Only the network's parameters are taken: the optimizer,
// the step counters and the points start afresh (unlike `nfield run --resume`).
//
//   field:
//     type: siren
//     hidden: [64, 64, 64]
//     init: ../out/meta_images/checkpoint.h5   # relative to the config's folder
//
// The checkpoint's field must have the config's shape: the same type, inputs, outputs,
// hidden widths and parameter count; otherwise, as for a missing or unreadable file, a
// located error at field.init names both shapes, and nothing is written.
#pragma once

#include <filesystem>
#include <string>

#include <Eigen/Core>

#include "fields/field_options.h"
#include "io/config.h"

namespace nfield::solvers {

struct FieldInit {
  std::string text;                 // as written in the config (kept in the resolved config)
  Eigen::VectorXd parameters;       // the network's parameters; empty: no field.init
};

// Reads field.init of `field_node` (the `field:` section; absent: an empty FieldInit) against
// the config's field `options`, with relative paths against `data_dir`.
FieldInit read_field_init(const io::ConfigNode& field_node, const fields::FieldOptions& options,
                          const std::filesystem::path& data_dir);

}  // namespace nfield::solvers
