// SPDX-License-Identifier: MIT
// The hash grid's Taylor streams: each corner's weight as a truncated series along a Taylor
// direction, and its reverse (the math: hash_grid.h, "Streams").
#include <algorithm>
#include <vector>

#include "fields/hash_grid.h"
#include "fields/hash_grid_cell.h"

namespace nfield::fields {

using autodiff::StreamLayout;
using namespace hash_grid_detail;

namespace {

// Scratch series of one point and level: the taps' weights w_{j,k}(τ) per axis, t_j(τ), t²,
// t³ and two rows of corner products.
template <typename Scalar>
struct SeriesScratch {
  void size(int d, int taps, int corners, int n) {
    this->n = n;
    data.resize(static_cast<size_t>(((taps + 3) * d + 2 * corners + 3) * n));
    weights = data.data();
    t = weights + taps * d * n;
    t2 = t + d * n;
    t3 = t2 + d * n;
    products = t3 + d * n;
    next = products + corners * n;
    tmp = next + corners * n;
    bar = tmp + n;
    bar2 = bar + n;
  }
  int n = 0;
  std::vector<Scalar> data;
  Scalar *weights, *t, *t2, *t3, *products, *next, *tmp, *bar, *bar2;
};

}  // namespace

// w_{j,k}(t_j(τ)) with t_j(τ) = t_j + s_j Σ_k a_{p,k,j} τᵏ; then every corner's product.
template <typename Scalar>
void HashGridEncoding<Scalar>::taylor_weights(const StreamLayout& layout, const Offsets& o,
                                              const Cell& cell, const Scalar* point,
                                              Scalar* kappa) const {
  const int d = dim_, corners = o.corners, order = o.order, n = order + 1, taps = 1 << bits_;
  thread_local SeriesScratch<Scalar> w;
  w.size(d, taps, corners, n);
  for (int dir = 0; dir < o.dirs; ++dir) {
    for (int j = 0; j < d; ++j) series(o, cell, point, dir, j, w.t + j * n, w.t2 + j * n,
                                       w.t3 + j * n, w.weights + j * taps * n);
    std::fill(w.products, w.products + n, Scalar(0));
    w.products[0] = 1;
    for (int j = 0, count = 1; j < d; ++j, count *= taps) {
      const Scalar* axis = w.weights + j * taps * n;
      for (int v = 0; v < count; ++v)
        for (int k = 0; k < taps; ++k)
          series_product(w.products + v * n, axis + k * n, w.next + (v + k * count) * n, n);
      std::swap(w.products, w.next);
    }
    for (int v = 0; v < corners; ++v)
      for (int k = 1; k <= order; ++k)
        kappa[layout.taylor(dir, k) * corners + v] = w.products[v * n + k];
  }
}

// The series of t_j and of axis j's tap weights along Taylor direction `dir` (n = K + 1
// coefficients each; `weights` holds taps · n, tap after tap).
template <typename Scalar>
void HashGridEncoding<Scalar>::series(const Offsets& o, const Cell& cell, const Scalar* point,
                                      int dir, int j, Scalar* t, Scalar* t2, Scalar* t3,
                                      Scalar* weights) const {
  const int n = o.order + 1;
  t[0] = cell.t[j];
  for (int k = 1; k < n; ++k) t[k] = cell.scale[j] * point[o.taylor_at(dir, k) + j];
  if (cubic_) {
    series_product(t, t, t2, n);
    series_product(t2, t, t3, n);
    constexpr Scalar sixth = Scalar(1) / 6;
    for (int k = 0; k < n; ++k) {
      const Scalar one = k == 0 ? Scalar(1) : Scalar(0);
      weights[k] = (one - 3 * t[k] + 3 * t2[k] - t3[k]) * sixth;
      weights[n + k] = (4 * one - 6 * t2[k] + 3 * t3[k]) * sixth;
      weights[2 * n + k] = (one + 3 * t[k] + 3 * t2[k] - 3 * t3[k]) * sixth;
      weights[3 * n + k] = t3[k] * sixth;
    }
    for (int k = 0; k < 4; ++k) weights[k * n] = cell.w[j][k][0];
    return;
  }
  Scalar* phi = weights + n;
  if (!smoothstep_) {
    std::copy(t, t + n, phi);
  } else {
    series_product(t, t, t2, n);
    series_product(t2, t, t3, n);
    for (int k = 0; k < n; ++k) phi[k] = 3 * t2[k] - 2 * t3[k];
  }
  phi[0] = cell.w[j][1][0];
  for (int k = 0; k < n; ++k) weights[k] = (k == 0 ? 1 : 0) - phi[k];
}

namespace {

// w̄_{j,tap} = Σ_v W̄_v ⋆ Π_{m≠j} (corner v's factor m) along Taylor direction `dir`, with
// W̄_v = (0, ω_{(dir,1),v}, …, ω_{(dir,K),v}) and the taps' weight series in w.weights.
// Linear and smoothstep keep φ̄_j alone (w̄ = φ̄ for tap 1, −φ̄ for tap 0); cubic each tap's.
template <typename Scalar>
void weights_adjoint(const StreamLayout& layout, const Offsets& o, int dir, const Scalar* omega, bool cubic,
                     SeriesScratch<Scalar>& w, std::vector<Scalar>& weights_bar) {
  const int d = o.d, corners = o.corners, order = o.order, n = order + 1, taps = 1 << o.bits;
  std::fill(weights_bar.begin(), weights_bar.end(), Scalar(0));
  for (int v = 0; v < corners; ++v) {
    Scalar* w_bar = w.bar;
    w_bar[0] = 0;
    bool any = false;
    for (int k = 1; k <= order; ++k) {
      w_bar[k] = omega[layout.taylor(dir, k) * corners + v];
      any = any || w_bar[k] != 0;
    }
    if (!any) continue;
    for (int j = 0; j < d; ++j) {
      // Π_{m≠j} of corner v's factor series.
      Scalar* others = w.products;
      std::fill(others, others + n, Scalar(0));
      others[0] = 1;
      for (int m = 0; m < d; ++m) {
        if (m == j) continue;
        series_product(others, w.weights + (m * taps + tap(v, m, o.bits)) * n, w.tmp, n);
        std::copy(w.tmp, w.tmp + n, others);
      }
      std::fill(w.bar2, w.bar2 + n, Scalar(0));
      series_product_adjoint(w_bar, others, w.bar2, n);
      const int k_tap = tap(v, j, o.bits);
      if (cubic) {
        Scalar* out = weights_bar.data() + (j * taps + k_tap) * n;
        for (int k = 0; k < n; ++k) out[k] += w.bar2[k];
      } else {
        const Scalar sign = k_tap ? Scalar(1) : Scalar(-1);
        for (int k = 0; k < n; ++k) weights_bar[j * n + k] += sign * w.bar2[k];
      }
    }
  }
}

// t̄_j (into w.bar) from axis j's w̄ (`b`: one series per tap with cubic, φ̄ otherwise), through
// the tap weights as polynomials in t_j; w.bar2 and w.tmp hold t̄² and t̄³.
template <typename Scalar>
void t_adjoint(const Scalar* b, const Scalar* t, const Scalar* t2, int n, bool cubic, bool smoothstep,
               SeriesScratch<Scalar>& w) {
  Scalar* t_bar = w.bar;
  std::fill(t_bar, t_bar + n, Scalar(0));
  Scalar* t2_bar = w.bar2;
  Scalar* t3_bar = w.tmp;
  if (cubic) {
    // w₀ = (1 − 3t + 3t² − t³)/6, w₁ = (4 − 6t² + 3t³)/6, w₂ = (1 + 3t + 3t² − 3t³)/6,
    // w₃ = t³/6, read off per power of t.
    for (int k = 0; k < n; ++k) {
      const Scalar b0 = b[k], b1 = b[n + k], b2 = b[2 * n + k], b3 = b[3 * n + k];
      t_bar[k] = Scalar(0.5) * (b2 - b0);
      t2_bar[k] = Scalar(0.5) * (b0 + b2) - b1;
      t3_bar[k] = (b3 - b0) / 6 + Scalar(0.5) * (b1 - b2);
    }
  } else if (!smoothstep) {
    std::copy(b, b + n, t_bar);
    return;
  } else {
    for (int k = 0; k < n; ++k) {
      t2_bar[k] = 3 * b[k];
      t3_bar[k] = -2 * b[k];
    }
  }
  series_product_adjoint(t3_bar, t, t2_bar, n);  // t³ = t² · t
  series_product_adjoint(t3_bar, t2, t_bar, n);
  series_product_adjoint(t2_bar, t, t_bar, n);   // t² = t · t, both factors
  series_product_adjoint(t2_bar, t, t_bar, n);
}

}  // namespace

// Reverse of taylor_weights: W̄_v = (0, ω_{(p,1),v}, …, ω_{(p,K),v}) → w̄_{j,tap} = Σ_v W̄_v ⋆
// Π_{m≠j} (corner factor m) → t̄_j → x̄_j += s_j t̄_{j,0}, ā_{p,k,j} += s_j t̄_{j,k}.
template <typename Scalar>
void HashGridEncoding<Scalar>::taylor_adjoint(const StreamLayout& layout, const Offsets& o,
                                              const Cell& cell, const Scalar* point,
                                              const Scalar* omega, Scalar* point_adjoint) const {
  const int d = dim_, corners = o.corners, order = o.order, n = order + 1, taps = 1 << bits_;
  thread_local SeriesScratch<Scalar> w;
  thread_local std::vector<Scalar> weights_bar;
  w.size(d, taps, corners, n);
  const int bar_taps = cubic_ ? taps : 1;
  weights_bar.resize(static_cast<size_t>(d * bar_taps * n));
  for (int dir = 0; dir < o.dirs; ++dir) {
    for (int j = 0; j < d; ++j) series(o, cell, point, dir, j, w.t + j * n, w.t2 + j * n,
                                       w.t3 + j * n, w.weights + j * taps * n);
    weights_adjoint(layout, o, dir, omega, cubic_, w, weights_bar);
    for (int j = 0; j < d; ++j) {
      // weights[0] is the cell's own weight, whose derivative in t_j is that of the series.
      t_adjoint(weights_bar.data() + j * bar_taps * n, w.t + j * n, w.t2 + j * n, n, cubic_, smoothstep_, w);
      const Scalar* t_bar = w.bar;
      const Scalar s = cell.scale[j];
      point_adjoint[j] += s * t_bar[0];
      for (int k = 1; k <= order; ++k) point_adjoint[o.taylor_at(dir, k) + j] += s * t_bar[k];
    }
  }
}

#define NFIELD_HASH_GRID_TAYLOR(Scalar)                                                                     \
  template void HashGridEncoding<Scalar>::taylor_weights(const StreamLayout&, const Offsets&, const Cell&,      \
                                                         const Scalar*, Scalar*) const;                         \
  template void HashGridEncoding<Scalar>::series(const Offsets&, const Cell&, const Scalar*, int, int, Scalar*, \
                                                 Scalar*, Scalar*, Scalar*) const;                              \
  template void HashGridEncoding<Scalar>::taylor_adjoint(const StreamLayout&, const Offsets&, const Cell&,      \
                                                         const Scalar*, const Scalar*, Scalar*) const;
NFIELD_HASH_GRID_TAYLOR(float)
NFIELD_HASH_GRID_TAYLOR(double)
#undef NFIELD_HASH_GRID_TAYLOR

}  // namespace nfield::fields
