// SPDX-License-Identifier: MIT
//
// Input encodings γ(x). Each is a fixed affine map z = W x + b followed by an elementwise
// function, so it reuses the elementwise stream rules of autodiff/elementwise.h:
//
//   positional  γ(x) = [x, sin(B x), cos(B x)], B = rows 2ˡ π eᵢ, l < L (NeRF; Mildenhall 2020)
//   fourier     γ(x) = [sin(2π B x), cos(2π B x)], B ~ N(0, σ²), m × d (Tancik et al. 2020);
//               with `scales`, B stacks one m × d block per scale, column a of block g drawn
//               N(0, σ_ga²): several scales, and a different one per axis (x slow, t fast:
//               the closest to DeepXDE's spatio-temporal multi-scale Fourier features, whose
//               x and t features go through the network apart and are multiplied after it)
//   cusp        γ(x) = [x, |x_a − c₁|, …, |x_a − c_k|] for planes x_a = c_k
//   identity    γ(x) = x (no module)
//   hash_grid   trainable multiresolution grids (Müller et al. 2022), fields/hash_grid.h
//   integrated_positional  E[γ(x)] for x ~ N(μ, diag σ²): the positional encoding damped
//               by e^{−½ω²σ²}, input [μ, σ²] (mip-NeRF; Barron 2021), fields/integrated_positional.h
//
// Each type is one entry of a registry (fields/encoding_type.h) that validates its options,
// reads and writes its config keys and checkpoint attributes, and creates its module.
//
// Sinusoids use sin only (cos z = sin(z + π/2)): W = [B; B], b = [0; π/2].
//
// Cusp features (Tseng, Lin, Hu and Lai 2023, cusp-capturing PINNs) let a smooth network
// represent a function that is continuous across a plane but whose normal derivative jumps
// there, as travel times in a layered medium or potentials across a material interface do.
// With f₋, f₊ smooth on either side and equal on the plane, f₊ − f₋ = (x_a − c) h, so
//   f = (f₊ + f₋)/2 + |x_a − c| h/2,
// a smooth function of [x, |x_a − c|]. A network of x alone has to round the kink off over
// a width that only shrinks with the network's size.
// Pitfall: |·| has derivative sign(z) (0 on the plane) and no higher ones in the streams; the
// δ of the second derivative on the plane is not there. Residuals of first order (eikonal)
// are exact on both sides; a second-order residual must not be asked across the plane.
//
// Cusp features that enter late (`from_stage: k`): the first layer's weights on the cusp
// features start at zero, and in the training stages before k the features are switched off
// (zero in every stream), so those weights get zero gradients and zero Jacobian columns from
// every optimizer and stay at zero; at stage k the features are switched on, with the field
// unchanged at that moment. A network that can form a kink on the plane from the start can
// also form the wrong one: on the two-layer Eikonal example (configs/accuracy_eikonal_layered
// .yaml) Adam with cusp features put a steep layer on the fast side of the interface in place
// of the head wave below it, which features entering for the Levenberg–Marquardt stages
// avoid (figures: docs/experiments.md).
//
// The matrix B (or the rows e_a of a cusp encoding) is part of the field and saved with it;
// it is not trained.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "autodiff/elementwise.h"
#include "autodiff/module.h"

namespace nfield::fields {

struct EncodingOptions {
  std::string type = "identity";  // a registered name (encoding_names())
  int frequencies = 6;            // positional, integrated_positional: L, frequencies 2⁰π … 2^(L−1)π per axis
  bool include_input = true;      // positional, integrated_positional, hash_grid: keep x itself in γ(x)
  bool normalize = false;         // positional: octave l scaled by 2⁻ˡ (derivatives bounded)
  int features = 128;             // fourier: m
  double scale = 10.0;            // fourier: σ
  // fourier: one block of `features` rows per entry, σ per axis (one value: every axis);
  // empty: one block at `scale`
  std::vector<std::vector<double>> scales;
  std::uint64_t seed = 0;         // fourier: draws B
  int axis = 0;                   // cusp: the input a normal to the planes
  std::vector<double> at;         // cusp: the planes x_a = c, at least one
  int from_stage = 0;             // cusp: the training stage at which the features enter
  int levels = 16;                // hash_grid: L
  int features_per_level = 2;     // hash_grid: F
  int log2_table_size = 19;       // hash_grid: T = 2^log2_table_size entries per level, 10…24
  int base_resolution = 16;       // hash_grid: N_min cells per axis on the coarsest level
  int finest_resolution = 512;    // hash_grid: N_max on the finest level
  std::string interpolation = "linear";  // hash_grid: linear | smoothstep | cubic
  double init_scale = 1e-4;       // hash_grid: tables start U(−init_scale, init_scale)
  // The box [lower, upper] the inputs come from (the field's domain), one bound per input
  // (per coordinate, for an encoding that reads variances beside them);
  // both empty: [0, 1]^d. Set by the program from the problem's domain, not a config key;
  // saved with the field. Only hash_grid reads it.
  std::vector<double> lower, upper;

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
  // validate(), then the rules that need the input dimension d (bounds, cusp axis).
  void validate(int input_dim) const;
};

// The linear part W of γ for an input of dimension d: B for positional and Fourier (the 2π
// of Fourier features folded in; W = [B; B] in the module), the rows e_a for cusp, nothing
// for identity.
Eigen::MatrixXd encoding_matrix(const EncodingOptions& options, int input_dim);

// The encoding module for inputs of dimension d; nullptr for the identity. Its parameters
// (hash_grid's tables) come first in a field's parameter vector.
template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_encoding(const EncodingOptions& options,
                                                        int input_dim);

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

std::vector<std::string> encoding_names();

}  // namespace nfield::fields
