// SPDX-License-Identifier: MIT
//
// Input encodings γ(x). Each is a fixed affine map z = W x + b followed by an elementwise
// function, so it reuses the elementwise stream rules of autodiff/elementwise.h:
//
//   positional  γ(x) = [x, sin(B x), cos(B x)], B = rows 2ˡ π eᵢ, l < L (NeRF; Mildenhall 2020),
//               fields/positional_encoding.h
//   fourier     γ(x) = [sin(2π B x), cos(2π B x)], B ~ N(0, σ²), m × d (Tancik et al. 2020);
//               with `scales`, B stacks one m × d block per scale, column a of block g drawn
//               N(0, σ_ga²): several scales, and a different one per axis (x slow, t fast:
//               the closest to DeepXDE's spatio-temporal multi-scale Fourier features, whose
//               x and t features go through the network apart and are multiplied after it),
//               fields/fourier_encoding.h
//   cusp        γ(x) = [x, |x_a − c₁|, …, |x_a − c_k|] for planes x_a = c_k (a kink across
//               a plane; features that may enter at a later stage), fields/cusp_encoding.h
//   identity    γ(x) = x (no module)
//   hash_grid   trainable multiresolution grids (Müller et al. 2022), fields/hash_grid.h
//   integrated_positional  E[γ(x)] for x ~ N(μ, diag σ²): the positional encoding damped
//               by e^{−½ω²σ²}, input [μ, σ²] (mip-NeRF; Barron 2021), fields/integrated_positional.h
//
// Each type is one entry of a registry (fields/encoding_type.h) that reads, validates, writes
// and saves its own typed options (PositionalOptions in fields/positional_encoding.h, …),
// held type-erased in EncodingOptions::own, and creates its module.
//
// Sinusoids use sin only (cos z = sin(z + π/2)): W = [B; B], b = [0; π/2].
//
// The matrix B (or the rows e_a of a cusp encoding) is part of the field and saved with it;
// it is not trained.
#pragma once

#include <any>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "autodiff/elementwise.h"
#include "autodiff/module.h"

namespace nfield::fields {

// What every encoding has: its type and the box its inputs come from. The keys of one type
// live in that type's own struct (PositionalOptions, FourierOptions, CuspOptions,
// HashGridOptions, IntegratedPositionalOptions), held in `own` and read back with
// own_options<T>; encoding_options(T{…}) makes options of T's type.
struct EncodingOptions {
  std::string type = "identity";  // a registered name (encoding_names())
  // The box [lower, upper] the inputs come from (the field's domain), one bound per input
  // (per coordinate, for an encoding that reads variances beside them); both empty: [0, 1]^d.
  // Set by the program from the problem's domain (fit_encoding, fields/encoding_type.h), not
  // a config key; saved with the field. hash_grid reads it, and so do the field types that
  // tile the domain (bacon, acorn) whatever their encoding.
  std::vector<double> lower, upper;
  // The type's own options struct; empty: that struct's defaults. Set by the type's registry
  // entry (read, load) or by encoding_options().
  std::any own;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
  // validate(), then the rules that need the input dimension d (bounds, cusp axis).
  void validate(int input_dim) const;
};

// The options of an encoding type, as its own struct `Own`: `own` when it holds one, Own's
// defaults when it is empty; std::invalid_argument when it holds another type's struct.
template <class Own>
const Own& own_options(const EncodingOptions& options) {
  static const Own defaults{};
  if (!options.own.has_value()) return defaults;
  if (const Own* own = std::any_cast<Own>(&options.own)) return *own;
  throw std::invalid_argument("encoding.type = " + options.type +
                              ": its options hold another encoding's; set type and options "
                              "together (encoding_options)");
}

// Options of Own's type (Own::kType) holding `own`; lower and upper empty.
template <class Own>
EncodingOptions encoding_options(Own own) {
  EncodingOptions options;
  options.type = Own::kType;
  options.own = std::move(own);
  return options;
}

// The linear part W of γ for an input of dimension d: B for positional and Fourier (the 2π
// of Fourier features folded in; W = [B; B] in the module), the rows e_a for cusp, nothing
// for identity.
Eigen::MatrixXd encoding_matrix(const EncodingOptions& options, int input_dim);

// The encoding module for inputs of dimension d; nullptr for the identity. Its parameters
// (hash_grid's tables) come first in a field's parameter vector.
template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_encoding(const EncodingOptions& options,
                                                        int input_dim);

// The training stage at which the encoding's features enter (cusp's from_stage; 0: from the
// start). Before it they are switched off (FeatureEncoding::set_features_on).
int entry_stage(const EncodingOptions& options);

// γ(x) = [x if include_input, s ⊙ σ(x Wᵀ + b)] with a fixed W (m × d), b (m), σ and
// feature scales s (m; empty: all 1).
template <typename Scalar>
class FeatureEncoding final : public autodiff::Module<Scalar> {
 public:
  FeatureEncoding(const Eigen::MatrixXd& weights, const Eigen::VectorXd& offsets,
                  std::unique_ptr<autodiff::ElementwiseFunction<Scalar>> function,
                  bool include_input, const Eigen::VectorXd& scales = {});

  std::string name() const override { return "feature encoding"; }
  Eigen::Index input_width() const override { return weights_.cols(); }
  Eigen::Index output_width() const override {
    return (include_input_ ? weights_.cols() : 0) + weights_.rows();
  }

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;

  // Switched off, σ(x Wᵀ + b) is replaced by zeros in every stream (x itself is kept).
  void set_features_on(bool on) { features_on_ = on; }

 private:
  autodiff::Matrix<Scalar> weights_;  // m × d
  autodiff::Matrix<Scalar> offsets_;  // 1 × m
  autodiff::Matrix<Scalar> scales_;   // 1 × m, or empty
  std::shared_ptr<autodiff::ElementwiseFunction<Scalar>> function_;
  bool include_input_;
  bool features_on_ = true;
};

// γ(x) = [x if include_input, s ⊙ sin(x Bᵀ), s ⊙ cos(x Bᵀ)] as one FeatureEncoding, a sine
// over [B; B] with phases [0; π/2]; s (one per row of B) empty: all 1. Positional and Fourier
// features are this with their own B.
template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_sinusoids(const Eigen::MatrixXd& b, bool include_input,
                                                         const Eigen::VectorXd& scales = {});

std::vector<std::string> encoding_names();

}  // namespace nfield::fields
