// SPDX-License-Identifier: MIT
//
// From the derivative symbols a residual of `problem: pde` reads to the derivative streams
// the field computes (autodiff/streams.h), and from those streams back to each symbol.
//
// Symbols, for an output u and the domain's inputs (x, y, z in space, t in time):
//
//   u                the value                          stream 0
//   u_x, u_t         a first derivative                 a tangent along the axis
//   u_xx, u_xy, u_tt a second derivative ∂a∂b u          an operator stream tr(C ∇²u),
//                                                        C = (e_a e_bᵀ + e_b e_aᵀ)/2
//   lap(u)           Δu over the space axes             one operator stream, C = I (space)
//   u_xxx, u_xxyt …  order 3 or 4                        Taylor series, see below
//   bilap(u)         Δ²u over the space axes            Taylor series of order 4
//   Σ c_i (u_ab | lap u)  a constant-coefficient sum     one operator stream, C = Σ c_i C_i
//
// The last row is no symbol a user writes: where a residual's chain of + and − has two or
// more second derivatives of one output with constant coefficients, each read nowhere else
// (`u_tt - c^2*u_xx`), the expression compiler folds them (io::ExpressionScope::fold) into
// one weighted symbol, read from one operator stream tr(W ∇²u) with W = Σ c_i C_i, as the
// built-in wave does; two streams would cost one more forward pass of the operator's size.
//
// Tangents are the axes some first or second derivative needs, in axis order; operator
// streams are shared by all outputs and by every symbol with the same C (u_xx and v_xx are
// two channels of one stream), so a residual reading lap(u) costs 1 + d + 1 streams, as the
// built-in Poisson does.
//
// Orders 3 and 4, by polarization. With a_{w,k} = (1/k!) dᵏ/dτᵏ u(x + τw) at τ = 0 (the
// Taylor coefficient of order k along w) and M = Dᵏu the symmetric k-linear form,
//
//   ∂^α u = M[e_α₁, …, e_αₖ] = Σ_{S ⊆ {1..k}} (−1)^{k−|S|} a_{w_S,k},   w_S = Σ_{i∈S} e_αᵢ,
//
// exact for every multi-index α (the polarization identity; M[w, …, w] = k! a_{w,k}). A pure
// derivative reduces to its axis (u_xxx = 6 a_{e_x,3}); the directions w_S are integer
// vectors, brought to one representative w' = w / (±gcd) with its first nonzero entry
// positive, using a_{s w',k} = sᵏ a_{w',k}, so that symbols share directions (u_xxyy reads
// e_x, e_y, e_x + e_y, 2e_x + e_y, e_x + 2e_y). All directions carry the highest order any
// symbol needs. bilap(u) is Σ_a ∂_a⁴ + 2 Σ_{a<b} ∂_a²∂_b² by the same rule, except in 2D,
// where the three directions 60° apart give Δ²u = (64/3) Σ_p a_{p,4} (streams.h). The
// coefficients reach 2⁴ · 6 in size with alternating signs: a Taylor stream's rounding error
// is amplified by up to a few hundred in a mixed fourth derivative, harmless in double and
// visible in float.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "autodiff/streams.h"
#include "io/compiled_expression.h"

namespace nfield::solvers {

struct DerivativeSymbol {
  enum class Kind { kPartial, kLaplacian, kBilaplacian, kWeighted };
  Kind kind = Kind::kPartial;
  int output = 0;
  std::vector<int> axes;  // kPartial: the input columns differentiated, sorted; empty: the value
  // kWeighted: the symmetric W of tr(W ∇²u) over all inputs, row-major (input_dim²)
  std::vector<double> weights;

  int order() const;
  bool operator==(const DerivativeSymbol&) const = default;
};

inline constexpr int kMaxDerivativeOrder = 4;

// `u`, `u_x`, `u_xxt`, `lap(u)`, `bilap(u)` for `outputs` over the domain's `inputs` (names
// of single letters, space ones first). nullopt when `name` is no symbol of these outputs
// (an unknown name); std::invalid_argument, with the reason, when it is one that the domain
// cannot have: a variable it lacks, an order above 4, lap of a domain without space axes.
std::optional<DerivativeSymbol> parse_derivative_symbol(std::string_view name,
                                                        const std::vector<std::string>& outputs,
                                                        const std::vector<std::string>& inputs,
                                                        int space_dim);

// Σ c_i s_i as one kWeighted symbol, where every s_i is a second derivative (u_xx, u_xy,
// lap(u)) of one output; nullopt otherwise (the terms stay as written).
std::optional<DerivativeSymbol> weighted_second_derivative(const std::vector<std::pair<DerivativeSymbol, double>>& terms,
                                                           int input_dim, int space_dim);

// Sets `scope`'s fold callbacks (io::ExpressionScope::fold) for the symbols of `outputs`
// over `inputs`: second derivatives of one output group together; `slot_of` gives the slot
// of a symbol (the weighted one included).
void set_second_derivative_folds(io::ExpressionScope& scope, const std::vector<std::string>& outputs,
                                 const std::vector<std::string>& inputs, int space_dim,
                                 std::function<int(const DerivativeSymbol&)> slot_of);

// One symbol's value: Σ coefficient · out[stream][channel] over its terms.
struct SymbolTerm {
  int stream = 0;
  int channel = 0;
  double coefficient = 1;
};

struct StreamPlan {
  autodiff::StreamSpec spec;
  std::vector<std::vector<SymbolTerm>> symbols;  // one per symbol planned, in order
};

// The fewest streams (as above) that give every symbol, over `input_dim` inputs of which the
// first `space_dim` are space.
StreamPlan plan_streams(const std::vector<DerivativeSymbol>& symbols, int input_dim, int space_dim);

}  // namespace nfield::solvers
