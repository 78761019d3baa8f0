// SPDX-License-Identifier: MIT
//
// The `field:` section of a config (defaults in FieldOptions, fields/field.h):
//
//   field:
//     type: siren             # siren | mlp | nerf (color_hidden: [64], direction_frequencies: 4)
//                             # | bacon (resolution: [64, 128, 256], …; fields/bacon_type.cc)
//     hidden: [64, 64, 64]    # hidden widths
//     first_omega: 30         # siren
//     hidden_omega: 30        # siren (mlp with sine: its frequency)
//     activation: tanh        # mlp: sine | tanh | softplus | relu | identity
//     seed: 0                 # default: training.seed
//     encoding: {type: fourier, features: 128, scale: 10}   # identity | positional | fourier | cusp | hash_grid
//     encoding: {type: cusp, axis: y, at: [0.5]}             # |y − 0.5| as an extra input
//     encoding: {type: cusp, axis: y, at: [0.5], from_stage: 1}   # … from training stage 1
//     encoding: {type: hash_grid, levels: 8, base_resolution: 4, finest_resolution: 64,
//                interpolation: smoothstep}                       # fields/hash_grid.h
//     encoding: {type: integrated_positional, frequencies: 10}   # mip-NeRF: inputs gain σ²
//
// Each encoding type reads and writes its own keys (EncodingType, fields/encoding_type.h).
#pragma once

#include <yaml-cpp/yaml.h>

#include "fields/field.h"
#include "io/config.h"

namespace nfield::fields {

// input_dim and output_dim come from the problem; `seed` is the default seed; input_names
// name the inputs for `encoding.axis` (default x, y, z, w).
FieldOptions field_options_from_config(const io::ConfigNode& node, int input_dim, int output_dim,
                                       std::uint64_t seed, std::vector<std::string> input_names = {});
YAML::Node to_yaml(const FieldOptions& options, std::vector<std::string> input_names = {});

}  // namespace nfield::fields
