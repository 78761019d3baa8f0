// SPDX-License-Identifier: MIT
//
// Volume rendering of sampled rays (NeRF's quadrature, Max 1995; Mildenhall et al. 2020) and
// its reverse pass.
//
// Forward, per ray with samples i = 0 … n−1 (ray_sampling.h: position tᵢ, interval δᵢ,
// density σᵢ ≥ 0 and colour cᵢ ∈ R³ at the sample, background b ∈ R³):
//
//   τᵢ = σᵢ δᵢ                   optical depth of the interval
//   αᵢ = 1 − e^{−τᵢ}             its opacity (computed as −expm1(−τᵢ): exact for small τ in float)
//   Tᵢ = Πⱼ<ᵢ (1 − αⱼ)           transmittance up to the interval, T₀ = 1
//   wᵢ = Tᵢ αᵢ = Tᵢ − Tᵢ₊₁       its weight
//   C = Σ wᵢ cᵢ + T_n b          colour
//   A = Σ wᵢ = 1 − T_n           accumulated opacity
//   D = Σ wᵢ tᵢ                  expected distance, tᵢ the sample's position (where σ and c
//                                were evaluated), along the unit direction; a miss counts 0,
//                                so D/A is the expected distance given a hit and D·depth_scale
//                                (rays.h) the camera-space depth
//
// A ray with no samples (outside the scene box, or all empty space skipped) gets C = b,
// A = 0, D = 0 and has no adjoints.
//
// Reverse. For a loss L(C, A, D) with adjoints C̄ ∈ R³, Ā, D̄ per ray, let each sample carry
// the scalar gᵢ = C̄·cᵢ + Ā + D̄ tᵢ (what the loss gains per unit of weight on sample i) and
// the background g_b = C̄·b. Since Tⱼ = exp(−Σₖ<ⱼ τₖ),
//
//   ∂Tⱼ/∂τᵢ = −Tⱼ for j > i, else 0,  so  ∂wᵢ/∂τᵢ = Tᵢ e^{−τᵢ} = Tᵢ₊₁,  ∂wⱼ/∂τᵢ = −wⱼ (j > i),
//   ∂T_n/∂τᵢ = −T_n, and
//
//   c̄ᵢ = wᵢ C̄
//   σ̄ᵢ = δᵢ (Tᵢ₊₁ gᵢ − Rᵢ),   Rᵢ = Σⱼ>ᵢ wⱼ gⱼ + T_n g_b
//
// Rᵢ is what everything behind sample i (later samples and the background) contributes to
// L: raising σᵢ moves weight from all of it onto sample i. One sweep from the back computes
// every Rᵢ as a suffix sum (R_{n−1} = T_n g_b, Rᵢ₋₁ = Rᵢ + wᵢ gᵢ), so the pass is O(n) per
// ray. It rebuilds Tᵢ₊₁ = T_n + Σⱼ>ᵢ wⱼ in the same sweep, a sum of non-negative terms: the
// alternative Tᵢ = Tᵢ₊₁ e^{τᵢ} overflows behind an opaque surface, and Instant NGP's
// Rᵢ = C − (prefix sum) cancels in float.
//
// Early ray termination (inference only): a ray stops once Tᵢ < termination_threshold; the
// samples after that get weight 0 and the remaining Tᵢ·b stays in the colour (as if the rest
// of the ray were empty), A = 1 − Tᵢ. render_backward always assumes the full sum, so a
// training step must not use it.
//
// Threads: rays are independent, so both passes run over rays in parallel (OpenMP) and
// give the same bits for any thread count. σ ≥ 0 is the caller's business (the field's
// output activation); it is not checked per sample.
#pragma once

#include <Eigen/Core>

#include "integrators/ray_sampling.h"

namespace nfield::integrators {

struct RenderOptions {
  bool early_termination = false;       // inference only (see above)
  double termination_threshold = 1e-4;  // T below which a ray stops; in (0, 1)

  void validate() const;
};

template <typename Scalar>
struct RenderResult {
  Matrix<Scalar> color;    // R × 3
  Vector<Scalar> opacity;  // R: A
  Vector<Scalar> depth;    // R: D (not divided by A)
  Vector<Scalar> weights;  // one per sample: wᵢ (the coarse weights of importance_samples)
};

// Per-ray loss adjoints. color is R × 3; opacity and depth are R or empty (no such term).
template <typename Scalar>
struct RenderAdjoint {
  Matrix<Scalar> color;
  Vector<Scalar> opacity;
  Vector<Scalar> depth;
};

// sigma: one per sample (N); rgb: N × 3; background: 1 × 3 (one colour for all rays) or
// R × 3 (one per ray: "random background" training draws them and passes them here).
// sigma and rgb may be columns and blocks of a network's output (the Ref types of rays.h).
template <typename Scalar>
RenderResult<Scalar> render(const RaySamples<Scalar>& samples,
                            const ConstVectorRef<Scalar>& sigma,
                            const ConstMatrixRef<Scalar>& rgb,
                            const ConstMatrixRef<Scalar>& background,
                            const RenderOptions& options = {});

// σ̄ and c̄ of every sample (overwritten; sigma_bar of size N, rgb_bar N × 3) from the
// per-ray adjoints, for the same samples, sigma, rgb and background as render().
template <typename Scalar>
void render_backward(const RaySamples<Scalar>& samples,
                     const ConstVectorRef<Scalar>& sigma,
                     const ConstMatrixRef<Scalar>& rgb,
                     const ConstMatrixRef<Scalar>& background,
                     const RenderAdjoint<Scalar>& adjoint, VectorRef<Scalar> sigma_bar,
                     MatrixRef<Scalar> rgb_bar);

}  // namespace nfield::integrators
