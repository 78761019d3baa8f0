// SPDX-License-Identifier: MIT
//
// The network of a radiance field (NeRF, Mildenhall et al. 2020) as one chain of modules.
//
//   input   [x (3), d (3)]: a sample's position and its ray's unit direction; with an
//           encoding that reads variances (integrated_positional) [x (3), d (3), σ² (3)],
//           σ² the diagonal of the covariance of the sample's Gaussian (world axes), moved
//           next to x for the encoding (autodiff/permute_columns.h)
//   trunk   γ(x) → [Dense → σ] × H             (σ = `activation`, relu by default)
//   heads   Dense → [s, f]                      raw density s and a feature vector f (width of
//                                               the last trunk layer): two heads, one product
//   colour  [f, γ_d(d)] → [Dense → σ] × C → Dense → raw colour (3); with a latent code
//           (FieldOptions::latent_size) [f, γ_d(d), z] (fields/latent_code.h): NeRF in the
//           Wild's appearance embedding (Martin-Brualla et al. 2021, NeRF-A), which changes
//           the colour of a view and never its density
//   output  [s, r, g, b] (4 channels, raw)
//
// The direction enters after the trunk and the density never sees it: it is carried past
// the trunk in extra columns (autodiff/on_columns.h), and so is s past the colour layers.
// γ is the field's `encoding` (positional, Fourier, hash grid, …) on x alone; γ_d the
// positional encoding of d with `direction_frequencies` octaves, d itself included.
// The output activations (softplus or truncated exp on s, a sigmoid on the colour) belong to
// the rendering problem, which also differentiates through them.
#pragma once

#include "autodiff/sequential.h"
#include "fields/field_options.h"

namespace nfield::fields {

inline constexpr int kRadianceInputs = 6;   // x, d
inline constexpr int kRadianceOutputs = 4;  // s, r, g, b

// Appends the modules above to `network` (empty on entry).
template <typename Scalar>
void add_radiance_modules(const FieldOptions& options, autodiff::Sequential<Scalar>& network);

}  // namespace nfield::fields
