// SPDX-License-Identifier: MIT
//
// Samples along rays: where the field is evaluated, and the interval each sample stands for.
//
// Flat layout. A batch of R rays with different sample counts (a ray that misses the scene, or
// runs through empty space, has few or none) is stored as one list of samples:
//
//   offsets  R + 1 indices, offsets[0] = 0; ray r owns samples [offsets[r], offsets[r+1])
//   t        one per sample, increasing within a ray: the field is evaluated at o + t·d
//   delta    one per sample: the length δ of the interval the sample stands for
//
// so a batch's points form one N × 3 matrix for the network (sample_points) and the
// renderer walks each ray's range.
//
// Intervals. The quadrature of volume rendering (volume_rendering.h) treats density and
// colour as constant on [tᵢ, tᵢ + δᵢ]. The samplers here use NeRF's choice
//
//   δᵢ = tᵢ₊₁ − tᵢ,   δ_last = far − t_last   (not NeRF's 10¹⁰)
//
// The last interval ends at the ray's far bound so that light beyond `far` comes from the
// background colour, which the renderer composites explicitly; NeRF's 10¹⁰ makes the last
// sample absorb everything left and leaves no room for a background. Pitfall: the stretch
// [near, t₀] before the first sample belongs to no interval (half a bin on average, for
// stratified samples); NeRF has the same gap. The occupancy-grid marcher (occupancy_grid.h)
// instead centres each sample in its own interval of fixed length.
//
// Randomness comes from raw std::mt19937_64 bits (random_bits.h): a seed gives the same
// samples on every standard library. Positions are computed in double and stored in Scalar.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "integrators/rays.h"

namespace nfield::integrators {

template <typename Scalar>
struct RaySamples {
  std::vector<Eigen::Index> offsets{0};
  Vector<Scalar> t;
  Vector<Scalar> delta;

  Eigen::Index rays() const { return static_cast<Eigen::Index>(offsets.size()) - 1; }
  Eigen::Index size() const { return t.size(); }
  Eigen::Index begin(Eigen::Index ray) const { return offsets[ray]; }
  Eigen::Index end(Eigen::Index ray) const { return offsets[ray + 1]; }
  Eigen::Index count(Eigen::Index ray) const { return offsets[ray + 1] - offsets[ray]; }

  // Throws std::invalid_argument unless offsets start at 0, never decrease and end at
  // size(), and t and delta have size() entries.
  void validate() const;
};

// World positions o + t·d of all samples, N × 3 (the network's input).
// Rays [first_ray, end_ray) of `samples` as samples of their own (offsets from their first
// sample): what one block of a pass over ray groups renders.
template <typename Scalar>
RaySamples<Scalar> ray_range(const RaySamples<Scalar>& samples, Eigen::Index first_ray,
                             Eigen::Index end_ray);

template <typename Scalar>
Matrix<Scalar> sample_points(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples);
// The unit direction of each sample's ray, N × 3 (the view direction of a radiance field).
template <typename Scalar>
Matrix<Scalar> sample_directions(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples);

struct StratifiedOptions {
  int samples_per_ray = 64;  // ≥ 1
  // true: one uniform draw in each of the equal bins of [near, far] (training);
  // false: the bin midpoints (evaluation, deterministic).
  bool jitter = true;

  void validate() const;
};

// samples_per_ray samples in each ray's [near, far]; none for an empty interval. Throws
// std::invalid_argument naming the ray when near or far is not finite.
template <typename Scalar>
RaySamples<Scalar> stratified_samples(const Rays<Scalar>& rays, const StratifiedOptions& options,
                                      std::mt19937_64& rng);

// `sections` equal sections of each ray's [near, far] (none for an empty interval), each as
// one sample at its midpoint standing for its whole length: t = near + (i + ½)Δ, δ = Δ =
// (far − near)/sections for every section, the last one included (unlike stratified
// midpoints, whose last δ ends at far). Piecewise-constant integrals over sections (AutoInt)
// render with these. Throws std::invalid_argument for sections < 1 or a ray without finite
// bounds.
template <typename Scalar>
RaySamples<Scalar> equal_sections(const Rays<Scalar>& rays, int sections);

struct ImportanceOptions {
  int samples_per_ray = 128;  // fine samples drawn per ray that has coarse samples; ≥ 1
  // true: u at the midpoints (k + ½)/n (evaluation); false: u = (k + ξₖ)/n, one uniform ξ per
  // stratum (lower variance than NeRF's sorted independent u, and sorted by construction).
  bool deterministic = false;
  // Added to every coarse weight before normalizing (NeRF: 1e-5), so that rays whose
  // weights are all but zero still spread some samples over the whole interval; ≥ 0.
  double weight_floor = 1e-5;
  // true: the result holds the coarse and the fine samples merged in order (what NeRF's fine
  // network evaluates); false: the fine samples alone.
  bool include_coarse = true;

  void validate() const;
};

// Hierarchical sampling (NeRF's sample_pdf, in this layout). Coarse sample i of a ray stands
// for the interval [tᵢ, tᵢ + δᵢ]; these intervals form a piecewise-constant density whose mass
// on interval i is mᵢ = max(wᵢ, 0) + weight_floor (weights as written by render(), one per
// coarse sample). Fine samples invert its CDF: with c₀ = 0, cᵢ₊₁ = cᵢ + mᵢ/Σm, a u in
// [cᵢ, cᵢ₊₁) maps to t = tᵢ + δᵢ (u − cᵢ)/(cᵢ₊₁ − cᵢ). The u are sorted, so one pass over the
// intervals serves all of them: O(coarse + fine) per ray. A ray whose total mass is zero
// (all weights ≤ 0 and no floor) falls back to mᵢ = δᵢ (uniform in t). δ of the result is
// recomputed from the merged positions and the ray's far bound (top of this file); rays
// without coarse samples get no fine ones.
template <typename Scalar>
RaySamples<Scalar> importance_samples(const Rays<Scalar>& rays, const RaySamples<Scalar>& coarse,
                                      const ConstVectorRef<Scalar>& weights,
                                      const ImportanceOptions& options, std::mt19937_64& rng);

}  // namespace nfield::integrators
