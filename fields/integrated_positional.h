// SPDX-License-Identifier: MIT
//
// The integrated positional encoding of mip-NeRF (Barron et al. 2021, Sec. 3.1): the expected
// positional encoding of a point drawn from a Gaussian instead of the encoding of a point.
//
// Math. The positional encoding (fields/encodings.h) has frequencies ω_l = 2ˡ π, l < L, per
// coordinate. For a coordinate x ~ N(μ, σ²), E[sin(ωx)] = sin(ωμ) e^{−ω²σ²/2} and
// E[cos(ωx)] = cos(ωμ) e^{−ω²σ²/2} (the characteristic function of a Gaussian). With a
// diagonal covariance each coordinate is its own Gaussian, so per coordinate i and octave l
//
//   γ_IPE(μ, σ²) = [μ if include_input,
//                   sin(ω_l μᵢ) e^{−½ ω_l² σᵢ²} for every (l, i),
//                   cos(ω_l μᵢ) e^{−½ ω_l² σᵢ²} for every (l, i)]
//
// Octaves whose period is small beside the Gaussian's width fade out smoothly instead of
// aliasing: an encoding of a region, not of a point. At σ² = 0 it is the positional
// encoding, exactly (same frequencies, same feature order; the damping factor is exp(0) = 1).
// The frequencies carry π, as the positional encoding's do; mip-NeRF's own code uses 2ˡ
// without π on a scene scaled to its box.
//
// Memory layout. Input: 2k columns, [μ₁ … μ_k, σ₁² … σ_k²], the means then the diagonal
// variances of the same k coordinates (a radiance field: k = 3, the world axes; its input
// is [x, d, σ²] and fields/radiance_network.h moves σ² next to x). Output, like the
// positional encoding's: [μ (k columns) if include_input, then 2·L·k features: the sines
// in rows l·k + i (octave-major), then the cosines in the same order].
//
// Streams. Each feature is the product of s = sin(z), z = ω_l μᵢ + φ (φ = 0 or π/2), and
// g = exp(w), w = −½ ω_l² σᵢ²: both z and w are linear in the inputs, so their streams follow
// from the input streams by one product each, s and g by the elementwise rules
// (autodiff/elementwise.h) and the feature by Leibniz's rule (autodiff::product_forward).
// Every stream kind is exact: tangents and operator streams along any input direction
// (means, variances or both), Taylor series of any order. Its adjoint is exact too, so the
// gradient reaches the variances as well as the means.
//
// Pitfalls.
//  * The variances must be ≥ 0. A negative σ² makes e^{−½ω²σ²} grow like e^{ω²|σ²|/2}: at
//    ω = 2⁹π that is e^{1.3e6 |σ²|}, an overflow for |σ²| > 7e-5. Nothing clamps them here.
//  * A field trained with variances has learnt weights for damped high octaves. Evaluated at
//    σ² = 0 (a point) those octaves come back at full strength with weights that were never
//    fitted to them: query such a field with the variances it was trained at (a radiance
//    field's density queries use a typical sample's Gaussian, solvers/problems/nerf.cc).
//  * The variances are per axis of the input coordinates (the diagonal of Σ), so the
//    encoding is not invariant under rotations of the coordinates: mip-NeRF's approximation.
//  * Input width 2k is even: on a coordinate field (siren, mlp) the encoding reads the
//    field's inputs as k means and k variances, so input_dim must be even.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "autodiff/elementwise.h"
#include "autodiff/module.h"

namespace nfield::fields {

class EncodingType;

// `field.encoding: {type: integrated_positional, frequencies: 6, include_input: true}`
// (checkpoint attributes: encoding_frequencies, encoding_include_input).
struct IntegratedPositionalOptions {
  static constexpr std::string_view kType = "integrated_positional";
  int frequencies = 6;        // L, in [1, 24], as the positional encoding's
  bool include_input = true;  // keep μ itself in γ

  // std::invalid_argument naming the key, its value and the rule.
  void validate() const;
};

template <typename Scalar>
class IntegratedPositionalEncoding final : public autodiff::Module<Scalar> {
 public:
  // k = positions coordinates, L = frequencies octaves.
  IntegratedPositionalEncoding(int positions, int frequencies, bool include_input);

  std::string name() const override { return "integrated positional encoding"; }
  Eigen::Index input_width() const override { return 2 * positions_; }
  Eigen::Index output_width() const override {
    return (include_input_ ? positions_ : 0) + weights_.rows();
  }

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;

 private:
  int positions_;
  bool include_input_;
  autodiff::Matrix<Scalar> weights_;  // 2Lk × k: rows ω_l eᵢ, the sines' then the cosines'
  autodiff::Matrix<Scalar> offsets_;  // 1 × 2Lk: 0 for the sines, π/2 for the cosines
  autodiff::Matrix<Scalar> damping_;  // 2Lk × k: rows −½ ω_l² eᵢ
  std::shared_ptr<autodiff::ElementwiseFunction<Scalar>> sine_, exp_;
};

// The registry entry of `integrated_positional` (fields/encoding_type.h).
std::unique_ptr<const EncodingType> make_integrated_positional_type();

}  // namespace nfield::fields
