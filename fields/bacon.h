// SPDX-License-Identifier: MIT
//
// BACON: a band-limited multiplicative filter network with one output per scale (Lindell,
// Martel, Wetzstein et al., "BACON: Band-limited Coordinate Networks for Multiscale Scene
// Representation", CVPR 2022; the multiplicative filter network is Fathony et al., ICLR 2021).
//
//   z₀ = g₀(x),   zᵢ = gᵢ(x) ⊙ (Wᵢ zᵢ₋₁ + bᵢ),   gᵢ(x) = sin(Ωᵢ x + φᵢ),   i = 1 … L
//   y_s = H_s z_{l_s} + c_s                              one linear head per scale s
//
// Layer i has width hᵢ = hidden[i] (L + 1 = hidden.size() filter layers); the heads read
// layers l₀ < l₁ < … (`output_layers`, by default the last ones).
//
// Why each head is band-limited. A filter row is one sinusoid of frequency ω (a row of Ωᵢ).
// sin a · sin b = ½[cos(a − b) − cos(a + b)]: a product of sinusoids of frequencies ω, ω′
// holds the frequencies ω ± ω′, so along each axis k the frequencies of a product add in
// absolute value. Wᵢ zᵢ₋₁ + bᵢ mixes units of the same layer (a constant bᵢ has frequency
// 0), and a linear head mixes the units of its layer; neither makes a frequency. By
// induction every unit of zᵢ is a sum of sinusoids with |ω_k| ≤ Σ_{j ≤ i} B_{j,k}, B_{j,k}
// the largest |frequency| of layer j's filters along axis k, and head s is band-limited to
// Σ_{j ≤ l_s} B_{j,k} per axis: exactly, for any weights, during and after training. Only
// Ωᵢ is fixed; Wᵢ, bᵢ, φᵢ and the heads train.
//
// The lattice and periodicity. Let the box be [lower_k, upper_k] (the problem's domain, kept
// in FieldOptions::encoding.lower/upper; [−1, 1] when unset) and D_k = upper_k − lower_k.
// Every filter frequency is on the lattice (2π/D_k)·n_k, n_k an integer: then every unit
// and every head is periodic with period D_k along axis k (a sum of sinusoids of whole
// periods over the box), so a signal sampled on a periodic grid of the box is represented
// without a seam, and the band limit is a statement about the Fourier series on the box.
// `period` p > 1 makes the period p·D_k instead (lattice 2π/(p D_k)): the box is then a part
// of one period, so a field on it need not be periodic over the box (a PDE solution such as
// sin(πx) on [0, 1], half a period over the box, is out of reach with p = 1); the cut-offs
// in cycles per unit stay as given, in p times as many lattice steps.
// Scale s has a cut-off F_s in cycles per unit of the domain, `max_frequency`, or the
// Nyquist limit of `resolution` N samples across each axis, F = N/(2 D_k); in lattice steps
// K_{s,k} = ⌊F_s p D_k⌋ (p N/2 for a resolution). The layers 0 … l₀ share K₀ (their bounds
// M_{j,k}, integers, differ by at most one and sum to K₀), layers l₀ + 1 … l₁ share
// K₁ − K₀, and so on, so Σ_{j ≤ l_s} M_{j,k} = K_{s,k} exactly. Layers after the last head
// are not allowed (they would only cost time).
//
// Initialization (BACON's, after the MFN paper): each filter frequency component
// n_k ~ uniform over the integers {−M_{j,k}, …, M_{j,k}}, drawn once from the field's seed
// when the field is built and fixed (not a parameter; a checkpoint rebuilds it from the
// seed and options); phases φ ~ U(−π, π); Wᵢ and the heads' H_s ~ U(−√(6/n), √(6/n)), bᵢ
// and c_s ~ U(−1/√n, 1/√n), n the fan-in (PyTorch's default bias). With E[sin²] = ½ and
// Var(W z) = 2 E[z²], the units stay of order one through the layers.
//
// Streams. Every rule is one the library already has: the filter's argument u = x Ωᵀ + φ is
// affine in x (its streams are the input streams times Ωᵀ, φ on the value rows), gᵢ = sin u
// is elementwise (autodiff/elementwise.h), the linear maps are affine, and the product is
// Leibniz's rule (product_forward). The reverse pass applies their adjoints layer by layer:
// z̄ from the heads, then per layer the product's adjoint to ḡᵢ and v̄ᵢ (vᵢ = Wᵢ zᵢ₋₁ + bᵢ),
// W̄ᵢ += v̄ᵀ zᵢ₋₁ over all streams, z̄ᵢ₋₁ += v̄ Wᵢ, the sine's adjoint to ū, φ̄ += Σₙ ū⁰ₙ
// and x̄ += ū Ωᵢ. Tangent, operator and Taylor losses so train every parameter. The tape
// keeps u, g, v, z and the sine's derivative tables of every layer (a recording pass holds
// about (5 + order) × the streams of one layer per layer).
//
// Parameters, in order: per layer i, for i ≥ 1 Wᵢ (hᵢ × hᵢ₋₁, column-major) and bᵢ, then φᵢ
// (layer 0: φ₀ only); then per head s, H_s (m × h_{l_s}, column-major) and c_s. The module's
// output is the S heads side by side, S·m columns, scale 0 first; fields::Field shows the
// problems one scale of them (fields/field.h). A checkpoint keeps this vector as
// /field/encoding_parameters (fields/field_io.h keeps every non-dense module's parameters
// there) and the keys as bacon_* attributes; the filter frequencies are rebuilt from the seed.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "autodiff/module.h"
#include "fields/field_options.h"

namespace nfield::fields {

class FieldType;

// `field.type: bacon`'s own keys (FieldOptions::extension).
struct BaconOptions {
  std::vector<double> max_frequency;  // per scale, cycles per unit of the domain, increasing
  std::vector<int> resolution;        // or per scale N: the Nyquist limit of N samples an axis
  std::vector<int> output_layers;     // per scale, increasing, in [0, L]; empty: the last ones
  bool train_all_scales = true;       // the loss sums over every scale (BACON); else only
                                      // output_scale's
  int output_scale = -1;              // what outputs, metrics and problems see; −1: the finest
  int period = 1;                     // the filters' period along each axis, in box widths

  int scales() const {
    return static_cast<int>(resolution.empty() ? max_frequency.size() : resolution.size());
  }
  int chosen_scale() const { return output_scale < 0 ? scales() - 1 : output_scale; }
  // The head layers for `layers` filter layers (output_layers, or the last scales()).
  std::vector<int> head_layers(int layers) const;
  // Throws std::invalid_argument "field.KEY = VALUE: rule".
  void validate(int layers) const;
};

// The options of a bacon field (its extension; defaults when empty).
const BaconOptions& bacon_options(const FieldOptions& options);

// Per axis k, the lattice steps K_{s,k} of each scale's cut-off (above): scales × d.
Eigen::MatrixXi bacon_cutoff_steps(const FieldOptions& options);
// Per axis, the period p D_k of the filters.
Eigen::VectorXd bacon_periods(const FieldOptions& options);
// The bounds M_{j,k} of each filter layer: layers × d, Σ_{j ≤ l_s} M_j = K_s.
Eigen::MatrixXi bacon_layer_bounds(const FieldOptions& options);
// The fixed filter frequencies Ωᵢ (hᵢ × d, radians per unit) drawn from the options' seed.
std::vector<Eigen::MatrixXd> bacon_filter_frequencies(const FieldOptions& options);

template <typename Scalar>
class BaconNetwork final : public autodiff::Module<Scalar> {
 public:
  // `options` validated (FieldOptions::validate).
  explicit BaconNetwork(const FieldOptions& options);

  std::string name() const override { return "bacon"; }
  Eigen::Index input_width() const override { return dim_; }
  Eigen::Index output_width() const override {
    return static_cast<Eigen::Index>(heads_.size()) * outputs_;
  }
  Eigen::Index parameter_count() const override { return parameter_count_; }
  bool initialize(Scalar* params, std::mt19937_64& rng) const override;

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;
  bool has_per_point_gradients() const override { return true; }
  void backward_per_point(const autodiff::StreamLayout& layout, const Scalar* params,
                          const autodiff::Streams<Scalar>& in,
                          const autodiff::SavedTensors<Scalar>& saved,
                          autodiff::Streams<Scalar>& out_adjoint,
                          autodiff::JacobianRows<Scalar> jacobian,
                          autodiff::Streams<Scalar>* in_adjoint) const override;

  const std::vector<Eigen::MatrixXd>& frequencies() const { return omega_; }

 private:
  struct Layer {
    Eigen::Index width = 0;
    Eigen::Index weight = -1;  // offset of Wᵢ (then bᵢ); −1 for layer 0
    Eigen::Index phase = 0;    // offset of φᵢ
  };
  struct Head {
    int layer = 0;
    Eigen::Index offset = 0;  // of H_s, then c_s
  };
  // Where the reverse pass puts parameter gradients: summed, or per point into Jacobian rows.
  struct Sink;

  void run_forward(const autodiff::StreamLayout& layout, const Scalar* params,
                   const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
                   autodiff::SavedTensors<Scalar>& tape, int table_order) const;
  void run_backward(const autodiff::StreamLayout& layout, const Scalar* params,
                    const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                    const autodiff::Streams<Scalar>& out_adjoint, Sink& sink,
                    autodiff::Streams<Scalar>* in_adjoint) const;
  int tape_stride(const autodiff::StreamLayout& layout) const { return 4 + layout.forward_order() + 2; }

  int dim_;
  Eigen::Index outputs_;
  std::vector<Layer> layers_;
  std::vector<Head> heads_;
  std::vector<Eigen::MatrixXd> omega_;                   // per layer, hᵢ × d, radians per unit
  std::vector<autodiff::Matrix<Scalar>> omega_scalar_;  // the same in Scalar
  Eigen::Index parameter_count_ = 0;
};

// The registry entry of `bacon` (fields/field_type.h).
std::unique_ptr<const FieldType> make_bacon_type();

}  // namespace nfield::fields
