// SPDX-License-Identifier: MIT
//
// `field.encoding: {type: positional, frequencies: 6, include_input: true, normalize: false}`
// (NeRF; Mildenhall et al. 2020):
//   γ(x) = [x if include_input, sin(B x), cos(B x)],   B = rows 2ˡ π eᵢ, l < L, i < d,
// L = frequencies, one octave per row block. With normalize, octave l is scaled by 2⁻ˡ so
// that every feature's derivative is at most π (AutoInt, Lindell et al. 2021: a network
// trained through its derivative along a ray otherwise sees the high octaves amplified by 2ˡ).
//
// Checkpoint attributes: encoding_frequencies, encoding_include_input, encoding_normalize
// (only when set).
#pragma once

#include <memory>
#include <string_view>

#include "fields/encodings.h"

namespace nfield::fields {

class EncodingType;

struct PositionalOptions {
  static constexpr std::string_view kType = "positional";
  int frequencies = 6;        // L, in [1, 24]: frequencies 2⁰π … 2^(L−1)π per axis
  bool include_input = true;  // keep x itself in γ(x)
  bool normalize = false;     // octave l scaled by 2⁻ˡ (derivatives bounded)

  // std::invalid_argument naming the key, its value and the rule.
  void validate() const;
};

// The registry entry of `positional` (fields/encoding_type.h).
std::unique_ptr<const EncodingType> make_positional_type();

}  // namespace nfield::fields
