// SPDX-License-Identifier: MIT
//
// `field.encoding: {type: fourier, features: 128, scale: 10, seed: …}` (random Fourier
// features; Tancik et al. 2020):
//   γ(x) = [sin(2π B x), cos(2π B x)],   B ~ N(0, σ²), m × d,  m = features, σ = scale.
// With `scales: [σ₁, [σ_x, σ_t], …]` (in place of `scale`), B stacks one m × d block per
// entry, column a of block g drawn N(0, σ_ga²): several scales, and a different one per axis
// (x slow, t fast: the closest to DeepXDE's spatio-temporal multi-scale Fourier features,
// whose x and t features go through the network apart and are multiplied after it).
// B is drawn from `seed` (default: the field's seed), row by row, with normal draws that do
// not depend on the standard library, so one block at `scale` is the matrix it always was.
//
// Checkpoint attributes: encoding_features, encoding_scale, encoding_seed, and with `scales`
// encoding_scales (the blocks' σ in a row) and encoding_scales_sizes (the count of each).
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "fields/encodings.h"

namespace nfield::fields {

class EncodingType;

struct FourierOptions {
  static constexpr std::string_view kType = "fourier";
  int features = 128;  // m, ≥ 1
  double scale = 10.0;  // σ, > 0
  // One block of `features` rows per entry, σ per axis (one value: every axis); empty: one
  // block at `scale`.
  std::vector<std::vector<double>> scales;
  std::uint64_t seed = 0;  // draws B

  // std::invalid_argument naming the key, its value and the rule.
  void validate() const;
  // validate(), then the rules that need the input dimension d (σ per axis).
  void validate(int input_dim) const;
};

// The registry entry of `fourier` (fields/encoding_type.h).
std::unique_ptr<const EncodingType> make_fourier_type();

}  // namespace nfield::fields
