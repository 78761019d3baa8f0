// SPDX-License-Identifier: MIT
//
// The output activations that turn a radiance field's raw outputs into what volume rendering
// (volume_rendering.h) composites: a density σ ≥ 0 from the raw density s, a colour in (0, 1)
// from each raw colour channel. Training, rendering and the benchmarks apply the same ones,
// so a field trained by one is rendered the same by the others.
#pragma once

#include <algorithm>
#include <cmath>

namespace nfield::integrators {

// σ = density(s) and dσ/ds: softplus, or Instant NGP's truncated exponential.
struct DensityActivation {
  bool truncated_exp = false;  // else softplus
  double value(double s) const {
    if (truncated_exp) return std::exp(std::min(s, 15.0));
    return s > 20 ? s : std::log1p(std::exp(s));
  }
  double derivative(double s) const {
    // The truncated exponential: exp with its gradient clamped at s = ±15.
    if (truncated_exp) return std::exp(std::clamp(s, -15.0, 15.0));
    return 1.0 / (1.0 + std::exp(-s));
  }
};

// The logistic sigmoid, per colour channel.
inline double colour_activation(double z) { return 1.0 / (1.0 + std::exp(-z)); }

}  // namespace nfield::integrators
