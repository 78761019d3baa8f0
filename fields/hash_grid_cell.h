// SPDX-License-Identifier: MIT
// The per-point, per-level state that the hash grid's passes (hash_grid.cc) and its Taylor
// series (hash_grid_taylor.cc) share. Internal to those two files.
#pragma once

#include <cstdint>

#include "autodiff/streams.h"

namespace nfield::fields {
namespace hash_grid_detail {

constexpr int kMaxDim = 4;
constexpr int kMaxTaps = 4;                    // vertices per axis: 2, or 4 with cubic
constexpr int kMaxCorners = 1 << (2 * kMaxDim);  // 4^4

// out = a·b for series of n coefficients, truncated.
template <typename Scalar>
void series_product(const Scalar* a, const Scalar* b, Scalar* out, int n) {
  for (int k = 0; k < n; ++k) {
    Scalar sum = 0;
    for (int i = 0; i <= k; ++i) sum += a[i] * b[k - i];
    out[k] = sum;
  }
}

// The adjoint of out = a·b with respect to a: ā_i += Σ_{k ≥ i} ō_k b_{k−i}.
template <typename Scalar>
void series_product_adjoint(const Scalar* out_bar, const Scalar* b, Scalar* a_bar, int n) {
  for (int i = 0; i < n; ++i) {
    Scalar sum = 0;
    for (int k = i; k < n; ++k) sum += out_bar[k] * b[k - i];
    a_bar[i] += sum;
  }
}

// Corner v's tap on axis j (`bits` = log2 of the taps per axis).
inline int tap(int v, int j, int bits) { return (v >> (j * bits)) & ((1 << bits) - 1); }

// Derivative of order `order` of corner v's factor on axis j.
template <typename CellT>
auto factor(const CellT& cell, int v, int j, int order, int bits) {
  return cell.w[j][tap(v, j, bits)][order];
}

template <typename Scalar>
struct Cell {
  // Corner v's tap on axis j is digit j of v in base taps (bits j·b … j·b + b − 1, b = log2
  // taps): vertex c_j + tap (linear, smoothstep) or c_j − 1 + tap (cubic).
  std::uint32_t rows[kMaxCorners];  // table row of each corner
  // The tap weight on axis j and its derivatives of order 1–3 in x_j.
  Scalar w[kMaxDim][kMaxTaps][4];
  Scalar t[kMaxDim];                // t_j (held in [0, 1] where smoothstep holds it)
  Scalar scale[kMaxDim];            // ∂t_j/∂x_j: 0 where t_j is held
};

// A point's input streams, gathered into one contiguous run per point:
//   x (d) | tangents a⁽ⁱ⁾ (T·d) | operator inputs a^[q] (Q·d) | M_q = Σᵢⱼ Cᵢⱼ a⁽ⁱ⁾a⁽ʲ⁾ᵀ,
//   symmetrized (Q·d²) | Taylor inputs a_{p,k} (P·K·d)
// so that Σᵢⱼ Cᵢⱼ a⁽ⁱ⁾ᵀ ∇²W a⁽ʲ⁾ = ⟨∇²W, M_q⟩ costs d² per corner, whatever T is.
struct Offsets {
  Offsets(const autodiff::StreamLayout& layout, int d, int bits)
      : d(d),
        bits(bits),
        tangents(layout.tangents()),
        operators(layout.operators()),
        dirs(layout.taylor_dirs()),
        order(layout.taylor_order()),
        streams(layout.count()),
        corners(1 << (d * bits)) {
    a = d;
    b = a + tangents * d;
    m = b + operators * d;
    taylor = m + operators * d * d;
    stride = taylor + dirs * order * d;
  }
  int taylor_at(int p, int k) const { return taylor + (p * order + k - 1) * d; }

  int d, bits, tangents, operators, dirs, order, streams, corners;
  int a, b, m, taylor, stride;
};

}  // namespace hash_grid_detail
}  // namespace nfield::fields
