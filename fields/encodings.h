// SPDX-License-Identifier: MIT
//
// Input encodings γ(x). Both sinusoidal encodings are a fixed linear map followed by sine
// and cosine, so they reuse the elementwise stream rules (cos z = sin(z + π/2)):
//
//   positional  γ(x) = [x, sin(B x), cos(B x)], B = rows 2ˡ π eᵢ, l < L (NeRF; Mildenhall 2020)
//   fourier     γ(x) = [sin(2π B x), cos(2π B x)], B ~ N(0, σ²), m × d (Tancik et al. 2020)
//   identity    γ(x) = x (no module)
//
// The matrix B is part of the field and saved with it; it is not trained.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "autodiff/module.h"

namespace nfield::fields {

struct EncodingOptions {
  std::string type = "identity";  // identity | positional | fourier
  int frequencies = 6;            // positional: L, frequencies 2⁰π … 2^(L−1)π per axis
  bool include_input = true;      // positional: keep x itself in γ(x)
  int features = 128;             // fourier: m
  double scale = 10.0;            // fourier: σ
  std::uint64_t seed = 0;         // fourier: draws B

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

// Rows of B (with the 2π of Fourier features folded in) for an input of dimension d.
Eigen::MatrixXd encoding_matrix(const EncodingOptions& options, int input_dim);

template <typename Scalar>
class SinusoidalEncoding final : public autodiff::Module<Scalar> {
 public:
  // frequencies: m × d; output = [x if include_input, sin(x Bᵀ), cos(x Bᵀ)].
  SinusoidalEncoding(Eigen::MatrixXd frequencies, bool include_input);

  std::string name() const override { return "sinusoidal encoding"; }
  Eigen::Index input_width() const override { return frequencies_.cols(); }
  Eigen::Index output_width() const override {
    return (include_input_ ? frequencies_.cols() : 0) + 2 * frequencies_.rows();
  }
  const Eigen::MatrixXd& frequencies() const { return frequencies_; }

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;

 private:
  Eigen::MatrixXd frequencies_;
  autodiff::Matrix<Scalar> doubled_;  // [B; B], 2m × d
  autodiff::Matrix<Scalar> phase_;    // 1 × 2m: 0 for sines, π/2 for cosines
  bool include_input_;
};

std::vector<std::string> encoding_names();

}  // namespace nfield::fields
