// SPDX-License-Identifier: MIT
//
// Multiresolution hash-grid encoding (Müller, Evans, Schied and Keller, Instant Neural
// Graphics Primitives, 2022) with every derivative stream.
//
// Level l = 0 … L−1 has cells of width 1/N_l of the box [lower, upper] (the field's
// domain), N_l = ⌊N_min bˡ⌋, b = exp((ln N_max − ln N_min)/(L − 1)), offset by half a cell
// as in Instant NGP. At x, per axis j:
//   p_j = N_l (x_j − lower_j)/(upper_j − lower_j) + 1/2,  c_j = clamp(⌊p_j⌋, 0, N_l),
//   t_j = p_j − c_j,  φ_j = t_j (linear) or s(t_j) = t_j²(3 − 2t_j) (smoothstep),
// and the level's F features interpolate the table rows of the cell's 2^d corners v:
//   y_l(x) = Σ_v W_v(x) T_l[row(v)],  W_v = Π_j (φ_j if v_j = c_j + 1, else 1 − φ_j).
// The box touches N_l + 1 cells and N_l + 2 vertices per axis. row(v) = Σ_j v_j (N_l + 2)^j
// (dense) while (N_l + 2)^d ≤ T = 2^log2_table_size, else the spatial hash
// (⊕_j v_j π_j) mod T, π = (1, 2654435761, 805459861, 3674653429), in 32-bit arithmetic.
// γ(x) = [x if include_input, y_0, …, y_{L−1}]: L·F features, level-major.
//
// `cubic`: a uniform cubic B-spline per level. The table rows are B-spline coefficients
// (not values at the vertices; they are learned either way), and y_l sums over the 4^d
// vertices c − 1 … c + 2 around the cell, W_v = Π_j β_{v_j − c_j + 1}(t_j) with
//   β₀ = (1 − t)³/6,  β₁ = (3t³ − 6t² + 4)/6,  β₂ = (−3t³ + 3t² + 3t + 1)/6,  β₃ = t³/6,
// i.e. vertex i weighs B(p_j − i), B the centred cubic B-spline (support [−2, 2]). The level
// is then C² everywhere, and since Σ_i B(p − i) = 1, Σ_i i B(p − i) = p and
// Σ_i i² B(p − i) = p² + 1/3, it reproduces every quadratic: coefficients
// c_i = f(i) − f''/6 give f exactly. Coarse levels so carry a smooth, nonzero mean curvature
// (a Laplacian of one sign across many cells), which a smoothstep level cannot (below). The
// stencil reaches one vertex beyond the box's N_l + 2 per axis: the level's vertex grid is
// extended by one on each side, vertices −1 … N_l + 2 stored at index v + 1 (no clamping, so
// reproduction holds in the outer cells too), row(v) = Σ_j (v_j + 1)(N_l + 4)^j while
// (N_l + 4)^d ≤ T, else the same hash of v + 1. Cost: 4^d vertices per level and point
// instead of 2^d (16 in 2D, 64 in 3D, 256 in 4D), in the table gathers, their weights and
// the scatter of the reverse pass alike, so cubic levels are for where their curvature is
// needed (measured cost: docs/experiments.md).
//
// Why x may be kept: inside a cell a smoothstep feature's second derivative along an axis
// has zero mean (its slope vanishes on both faces), so mean curvature, such as a Poisson
// solution with a source of one sign needs everywhere, can only come from the network's own
// nonlinearity acting on the features; with x beside them the network forms it as an MLP of
// x does and the grid adds detail (configs/poisson_2d_hash_grid.yaml). A cubic level carries
// mean curvature itself.
//
// Why the half-cell offset: smoothstep has zero slope on cell faces, so a level with faces
// on the box boundary has ∂y_l/∂n = 0 there, and with every level so aligned the field is
// forced to ∂u/∂n = 0 on the whole boundary. A Dirichlet problem whose solution has a normal
// derivative there (configs/poisson_2d.yaml) then cannot be fitted.
// Offset, the boundary lies mid-cell on every level.
//
// Streams. Every output stream of a level is Σ_v κ_v T_l[row(v)], one scalar κ per corner
// and stream; W_v is a product of one factor per axis, so its derivatives in x are products
// of the factors' derivatives. With the general input streams a⁰ = x, a⁽ⁱ⁾, a^[C] (tangents
// need not be axes and may differ per point):
//   value     κ = W                     tangent i   κ = ∇W · a⁽ⁱ⁾
//   operator  κ = ∇W · a^[C] + Σᵢⱼ Cᵢⱼ a⁽ⁱ⁾ᵀ ∇²W a⁽ʲ⁾
//   Taylor    κ_k = coefficient k of W(a₀ + a₁τ + … + a_Kτᴷ): truncated products of the
//             per-axis series (φ and β are polynomials in t inside a cell)
// Every stream is linear in the tables, so the reverse pass to them is
// T̄_l[row(v)] += Σ_streams κ_v ȳ: tangent, operator and Taylor losses train the tables too.
// The input adjoint differentiates κ once more (∇²W, ∇³W, adjoints of series products).
//
// Smoothness: derivatives inside a cell are exact. Across cell faces the encoding is
// continuous; with `linear` its gradient jumps and ∂²/∂x_j² vanishes inside cells (only mixed
// second derivatives remain), so second-order residuals see little of it; with `smoothstep`
// the gradient is continuous (s' = 0 at 0 and 1) and all second derivatives are present,
// jumping across faces; with `cubic` second derivatives are continuous too, third ones
// (β''' = −1, 3, −3, 1 times N³) are constant in a cell and jump across faces, higher ones
// vanish inside cells. More than half a cell outside the box, `linear` extends the outer
// cells linearly, `smoothstep` holds t_j in [0, 1] (a constant extension, still C¹) and
// `cubic` continues the outer cells' cubics (C² at the switch, growing like the cube of the
// distance far out); nothing wraps around.
//
// Parameters: level after level, a table of R_l = min(T, (N_l + 2)^d) rows × F (cubic:
// (N_l + 4)^d), row-major
// (feature fastest): coarse dense levels hold exactly their vertices. Initialized
// U(−init_scale, init_scale), 10⁻⁴ by default as in Instant NGP. Inputs of dimension 1 to 4.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "autodiff/module.h"
#include "fields/encodings.h"

namespace nfield::fields {

class EncodingType;

// `field.encoding: {type: hash_grid, …}`, with its defaults (checkpoint attributes:
// encoding_KEY for each, and encoding_include_input). The box is EncodingOptions::lower/upper.
struct HashGridOptions {
  static constexpr std::string_view kType = "hash_grid";
  int levels = 16;                       // L, in [1, 32]
  int features_per_level = 2;            // F, in [1, 16]
  int log2_table_size = 19;              // T = 2^log2_table_size entries per level, 10…24
  int base_resolution = 16;              // N_min cells per axis on the coarsest level
  int finest_resolution = 512;           // N_max on the finest level, ≥ N_min
  std::string interpolation = "linear";  // linear | smoothstep | cubic
  bool include_input = true;             // keep x itself in γ(x)
  double init_scale = 1e-4;              // tables start U(−init_scale, init_scale)

  // std::invalid_argument naming the key, its value and the rule.
  void validate() const;
};

struct HashGridLevel {
  int resolution = 0;          // N_l: cells per box width
  bool dense = false;          // one row per vertex; else the spatial hash
  Eigen::Index first_row = 0;  // of this level's table, counting rows of all levels before
  Eigen::Index rows = 0;       // R_l
};

// The levels for validated options and input dimension d.
std::vector<HashGridLevel> hash_grid_levels(const EncodingOptions& options, int input_dim);

namespace hash_grid_detail {
template <typename Scalar>
struct Cell;     // one point's cell at one level (hash_grid_cell.h)
struct Offsets;  // where each input stream sits in a point's gathered inputs
}  // namespace hash_grid_detail

template <typename Scalar>
class HashGridEncoding final : public autodiff::Module<Scalar> {
 public:
  // `options` validated for input_dim (EncodingOptions::validate(int)).
  HashGridEncoding(const EncodingOptions& options, int input_dim);

  std::string name() const override { return "hash_grid encoding"; }
  Eigen::Index input_width() const override { return dim_; }
  Eigen::Index output_width() const override {
    return input_columns() + static_cast<Eigen::Index>(levels_.size()) * features_;
  }
  Eigen::Index parameter_count() const override { return rows_ * features_; }
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

  const std::vector<HashGridLevel>& levels() const { return levels_; }
  // Row of level l's table (0 … R_l − 1) holding grid vertex v (d integer coordinates, each
  // 0 … N_l + 1, or −1 … N_l + 2 with cubic).
  std::uint32_t row(int level, const int* vertex) const;

 private:
  using Cell = hash_grid_detail::Cell<Scalar>;
  using Offsets = hash_grid_detail::Offsets;
  struct Level {
    HashGridLevel info;
    Scalar scale[4];          // ∂t_j/∂x_j = N_l / (upper_j − lower_j)
    std::uint32_t stride[4];  // dense: (N_l + 2)^j, or (N_l + 4)^j with cubic
    std::uint32_t mask;       // hashed: T − 1
  };

  Eigen::Index input_columns() const { return include_input_ ? dim_ : 0; }
  void locate(const Level& level, const Scalar* x, Cell& cell) const;
  void gather(const autodiff::StreamLayout& layout, const Offsets& o,
              const autodiff::Streams<Scalar>& in, std::vector<Scalar>& inputs) const;
  void series(const Offsets& o, const Cell& cell, const Scalar* point, int dir, int axis,
              Scalar* t, Scalar* t2, Scalar* t3, Scalar* weights) const;
  void table_adjoint(const Offsets& o, const autodiff::Streams<Scalar>& in,
                     const autodiff::SavedTensors<Scalar>& saved,
                     const autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                     autodiff::JacobianRows<Scalar>* jacobian) const;
  template <int D, int Taps>
  void forward_values(const Scalar* params, const autodiff::Streams<Scalar>& in,
                      autodiff::Streams<Scalar>& out, Scalar* rows_out, Scalar* kappa_out) const;
  void corner_weights(const autodiff::StreamLayout& layout, const Offsets& o, const Cell& cell,
                      const Scalar* point, Scalar* kappa) const;
  void taylor_weights(const autodiff::StreamLayout& layout, const Offsets& o, const Cell& cell,
                      const Scalar* point, Scalar* kappa) const;
  void input_adjoint(const autodiff::StreamLayout& layout, const Scalar* params,
                     const autodiff::Streams<Scalar>& in, const autodiff::Streams<Scalar>& out_adjoint,
                     autodiff::Streams<Scalar>& in_adjoint) const;
  void taylor_adjoint(const autodiff::StreamLayout& layout, const Offsets& o, const Cell& cell,
                      const Scalar* point, const Scalar* omega, Scalar* point_adjoint) const;

  int dim_;
  int features_;
  bool smoothstep_;
  bool cubic_;
  int bits_;  // log2 of the vertices per axis of a point's stencil: 1, or 2 with cubic
  bool include_input_;
  double init_scale_;
  Scalar lower_[4];
  std::vector<HashGridLevel> levels_;
  std::vector<Level> grid_;
  Eigen::Index rows_ = 0;
};

// The registry entry of `hash_grid` (fields/encoding_type.h).
std::unique_ptr<const EncodingType> make_hash_grid_type();

}  // namespace nfield::fields
