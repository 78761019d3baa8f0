// SPDX-License-Identifier: MIT
//
// The `field:` section of a config (defaults in FieldOptions, fields/field.h):
//
//   field:
//     type: siren             # siren | mlp | nerf (color_hidden: [64], direction_frequencies: 4)
//                             # | bacon (resolution: [64, 128, 256], …; fields/bacon_type.cc)
//     hidden: [64, 64, 64]    # hidden widths
//     first_omega: 30         # siren (default: the problem's, SineFrequencies below)
//     hidden_omega: 30        # siren (mlp with sine: its frequency; default: the problem's)
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

// The sine frequencies a field starts from when its config names none, chosen per problem.
// SIREN's ω₀ = ω = 30 (Sitzmann et al.) is right for signals: images, audio, surfaces, where
// the field must resolve fine detail from its first step. A differential equation reads
// derivatives: each sine layer multiplies a derivative by about its ω, so at ω = 30 a
// Laplacian starts near 10⁴ and the loss near 10⁷–10⁹ while the solution is O(1), and a
// Glorot sine MLP at ω = 30 (sin(30(Wx + b))) is no longer DeepXDE's sin(Wx + b). Problems
// that solve an equation therefore ask for kPdeSineFrequencies (docs/experiments.md,
// 2026-11-26: DeepXDE's Helmholtz example; the shipped PDE configs all set first_omega 2–15,
// hidden_omega 1).
struct SineFrequencies {
  double first = 30.0;   // first_omega
  double hidden = 30.0;  // hidden_omega
};
inline constexpr SineFrequencies kSignalSineFrequencies{30.0, 30.0};
inline constexpr SineFrequencies kPdeSineFrequencies{10.0, 1.0};

// input_dim and output_dim come from the problem; `seed` is the default seed; input_names
// name the inputs for `encoding.axis` (default x, y, z, w); `sine` gives first_omega and
// hidden_omega where the config names none (the problem's, Problem::default_sine_frequencies).
FieldOptions field_options_from_config(const io::ConfigNode& node, int input_dim, int output_dim,
                                       std::uint64_t seed, std::vector<std::string> input_names = {},
                                       SineFrequencies sine = kSignalSineFrequencies);
YAML::Node to_yaml(const FieldOptions& options, std::vector<std::string> input_names = {});

}  // namespace nfield::fields
