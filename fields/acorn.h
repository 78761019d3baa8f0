// SPDX-License-Identifier: MIT
//
// ACORN, an adaptive coordinate network (Martel, Lindell, Lin, Chan, Monteiro and Wetzstein,
// SIGGRAPH 2021): the domain is tiled by the blocks of a quadtree/octree
// (fields/acorn_tree.h); one coordinate encoder maps each block to a grid of features, and
// one small decoder reads that grid at each point.
//
//   block b (level l, lower corner o_b, edge h_b = 2^−l in the unit cube [0, 1]^d)
//   encoder   z_b = [q, sin(2^k π q), cos(2^k π q)]_{k<K},  q = (2 (o_b + h_b/2) − 1, 2l/L − 1)
//             (the block's centre in [−1, 1]^d and its level; d + 1 numbers, K octaves), then
//             an MLP with ReLU hidden layers `encoder_hidden` and a linear output of
//             C · G^d numbers: the feature grid Φ_b[v, c] at G vertices per axis
//   local     u = (x − lower)/(upper − lower) scaled into the box, t = (u − o_b)/h_b ∈ [0, 1]^d,
//             p_j = t_j (G − 1), cell c_j = min(⌊p_j⌋, G − 2), s_j = p_j − c_j
//   features  γ_c(x) = Σ_v W_v Φ_b[v, c],  W_v = Π_j (s_j if v_j = c_j + 1 else 1 − s_j)
//             (bilinear in 2-D, trilinear in 3-D): the module's C outputs
//   decoder   the field's Dense layers after this module (`hidden`, `activation`, as an mlp)
// So the encoder runs once per block that a pass touches, not once per point: a pass over
// points sorted by block (the allocation's sampler, solvers/training/block_allocation.h)
// evaluates it a few times per 128-point block of the pass, and the decoder is small.
//
// Streams: the value and tangent streams (the gradient ∂u/∂x along any direction): inside a
// grid cell ∂γ/∂x_j = Σ_v ∂W_v/∂s_j Φ_b[v] · (G − 1)/(h_b (upper_j − lower_j)). Operator and
// Taylor streams are not provided (check_layout throws std::invalid_argument naming them): the
// second derivatives of a multilinear interpolation are mixed ones only, and the field is
// not even continuous across block faces — two neighbouring blocks have their own grids,
// which agree on the shared face only as far as training made them (ACORN shares this; its
// paper shows the seams are below the fitting error). Inside one block the field is C⁰
// (multilinear across grid cells, then the decoder's smooth or ReLU layers), C^∞ inside a cell
// for a smooth decoder activation. So ACORN fits signals (images, occupancy), not PDEs.
//
// Frozen blocks (training's freeze_below, solvers/training/block_allocation.h) read the grid
// they had when they froze (Block::grid), not the encoder, and pass no gradient to it.
//
// Reverse pass: the feature adjoint of each point scatters into its block's grid adjoint
// (W_v, and ∂W_v/∂x · a for tangent streams), then one reverse pass of the encoder per block.
// No input adjoint (the module is a field's first; Sequential asks none of it) and no
// per-point Jacobian rows (Levenberg–Marquardt refuses the field by has_per_point_gradients).
//
// Parameters: the encoder's layers in order, each W (out × in, column-major) then b. Initial
// weights He-uniform U(±√(6/in)) for hidden layers, U(±√(6/(in + out))) for the output layer,
// zero biases, drawn from the field's engine as the dense layers are.
#pragma once

#include <memory>
#include <random>
#include <vector>

#include "autodiff/module.h"
#include "fields/acorn_tree.h"
#include "fields/field_options.h"

namespace nfield::fields {

// `field.type: acorn`'s own keys (fields/acorn_type.cc), in FieldOptions::extension.
struct AcornOptions {
  int features = 8;                       // C, channels of the feature grid
  int grid = 16;                          // G, vertices per axis (≥ 2)
  std::vector<int> encoder_hidden{64, 64};
  int encoder_octaves = 6;                // K
  int initial_level = 2;                  // the uniform tiling at the start: 2^(d·level) blocks
  int max_level = 6;                      // finest level a split may reach
  int max_blocks = 256;                   // the budget of blocks (frozen ones count)
  int allocate_every = 100;               // steps between allocations (0: the tree stays)
  double split_factor = 0.25;             // β of fields/acorn_allocation.h
  double freeze_below = 0;                // a block's mean squared error below this freezes it
  std::shared_ptr<BlockTree> tree;        // the layout: state, shared by the field's casts

  // std::invalid_argument naming `field.KEY = VALUE: rule`.
  void validate(int input_dim) const;
  // The encoder's input width (d + 1)(1 + 2K).
  int encoder_inputs(int input_dim) const { return (input_dim + 1) * (1 + 2 * encoder_octaves); }
};

// The options of an acorn field (the defaults when it has none, e.g. a bare FieldOptions).
const AcornOptions& acorn_options(const FieldOptions& o);
// The tree of an acorn field, made at the initial level when the options carry none.
std::shared_ptr<BlockTree> acorn_tree(FieldOptions& o);
// Resuming: the blocks of `saved` (a field loaded from a checkpoint) into the tree of `live`
// (the field built from the config), when both are acorn fields; std::invalid_argument when
// the config's max_level cannot hold them.
void restore_block_tree(const FieldOptions& saved, const FieldOptions& live);

template <typename Scalar>
class AcornEncoding final : public autodiff::Module<Scalar> {
 public:
  // `options` validated; its tree (acorn_options(options).tree) must be set.
  explicit AcornEncoding(const FieldOptions& options);

  std::string name() const override { return "acorn encoding"; }
  Eigen::Index input_width() const override { return dim_; }
  Eigen::Index output_width() const override { return features_; }
  Eigen::Index parameter_count() const override { return parameters_; }
  bool initialize(Scalar* params, std::mt19937_64& rng) const override;
  void check_layout(const autodiff::StreamLayout& layout) const override;

  void forward(const autodiff::StreamLayout& layout, const Scalar* params,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override;
  void backward(const autodiff::StreamLayout& layout, const Scalar* params,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                autodiff::Streams<Scalar>* in_adjoint) const override;
  bool has_per_point_gradients() const override { return false; }

  // The feature grid of block b (C · G^d, vertex-major: Φ[v·C + c], v = Σ_j v_j G^j).
  autodiff::Vector<Scalar> block_grid(const Scalar* params, int block) const;

 private:
  struct Located;  // a point's block slot, cell and interpolation weights
  // The encoder's input for block b.
  autodiff::Vector<Scalar> encoder_input(int block) const;
  // Per unique block of a pass: the encoder's activations (one matrix per layer, width × U:
  // the input, then each layer's output after its activation); the last is the grids.
  void encode(const Scalar* params, const std::vector<int>& blocks,
              std::vector<autodiff::Matrix<Scalar>>& activations) const;
  void locate(const Scalar* x, int& block, int* cell, Scalar* s) const;

  int dim_, features_, grid_, octaves_, max_level_;
  std::vector<int> widths_;  // encoder: input, hidden…, C·G^d
  Eigen::Index parameters_ = 0;
  double lower_[3], range_[3];
  std::shared_ptr<const BlockTree> tree_;
};

class FieldType;
// The registry entry of `acorn` (fields/acorn_type.cc).
std::unique_ptr<const FieldType> make_acorn_type();

}  // namespace nfield::fields
