// SPDX-License-Identifier: MIT
//
// Samples along a ray as Gaussians (mip-NeRF, Barron et al. 2021, Sec. 3.1): a camera ray is a
// cone with radius ρ(t) = r·t (r = Rays::radius, from the pixel's width), and a sample stands
// for the conical frustum t ∈ [t₀, t₁] of it. The frustum is replaced by the Gaussian with the
// mean and the axis-aligned (along / across the ray) variances of a point uniform in it, which
// the integrated positional encoding reads (fields/integrated_positional.h).
//
// Moments. The frustum's cross-section at t has area π r² t², so t has the density ∝ t² on
// [t₀, t₁], and given t the offset across the ray is uniform on a disc of radius r·t: mean 0,
// variance r²t²/4 along each of the two perpendicular axes. With m = (t₀ + t₁)/2, h =
// (t₁ − t₀)/2 and D = 3m² + h² (written so that a thin frustum, h ≪ m, loses no digits to
// cancellation):
//
//   E[t]       = (3/4)(t₁⁴ − t₀⁴)/(t₁³ − t₀³)          = m + 2mh²/D
//   E[t²]      = (3/5)(t₁⁵ − t₀⁵)/(t₁³ − t₀³)          = m² + 5h²/3 − 16h⁴/(15D)
//   σ_t²       = E[t²] − E[t]²                          = h²/3 − (4/15) h⁴ (12m² − h²)/D²
//   σ_r²       = (r²/4) E[t²]                           = r² (m²/4 + 5h²/12 − 4h⁴/(15D))
//
// In world coordinates, for a unit direction d: mean o + E[t] d, covariance
// σ_t² d dᵀ + σ_r² (I − d dᵀ), whose diagonal σ_t² d∘d + σ_r² (1 − d∘d) is what the field reads
// (the diagonal approximation of mip-NeRF).
//
// Which frustum a sample stands for: the stretch of length δ centred on it, [t − δ/2, t + δ/2]
// (t₀ clamped at 0). That is exactly the interval of the occupancy grid's march
// (occupancy_grid.h) and of a stratified bin's midpoint; a jittered stratified sample, whose
// quadrature interval is [t, t + δ] (ray_sampling.h), gets the same length half an interval
// earlier, and the frustum moves with the jitter, as mip-NeRF's random intervals do.
#pragma once

#include "integrators/ray_sampling.h"
#include "integrators/rays.h"

namespace nfield::integrators {

// The moments above of the frustum [t0, t1] (0 ≤ t0 ≤ t1) of a cone of radius r·t.
struct FrustumMoments {
  double mean = 0;    // E[t]
  double along = 0;   // σ_t², the variance of t
  double across = 0;  // σ_r², the variance of the offset along each perpendicular axis
};
FrustumMoments frustum_moments(double t0, double t1, double radius);

// Each sample's frustum Gaussian: means o + E[t] d (N × 3) and the diagonals of the
// covariances, σ_t² d∘d + σ_r² (1 − d∘d) (N × 3), in the sample order of `samples`.
template <typename Scalar>
struct SampleGaussians {
  Matrix<Scalar> mean;
  Matrix<Scalar> variance;
};
template <typename Scalar>
SampleGaussians<Scalar> sample_gaussians(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples);

}  // namespace nfield::integrators
