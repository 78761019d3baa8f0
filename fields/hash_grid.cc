// SPDX-License-Identifier: MIT
#include "fields/hash_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fields/hash_grid_cell.h"
#include "io/text.h"

namespace nfield::fields {

using autodiff::Matrix;
using autodiff::StreamLayout;
using autodiff::Streams;
using namespace hash_grid_detail;

namespace {

constexpr std::uint32_t kPrimes[kMaxDim] = {1u, 2654435761u, 805459861u, 3674653429u};

bool is_smoothstep(const HashGridOptions& o) {
  return io::to_lower(o.interpolation) == "smoothstep";
}

bool is_cubic(const HashGridOptions& o) { return io::to_lower(o.interpolation) == "cubic"; }

}  // namespace

std::vector<HashGridLevel> hash_grid_levels(const EncodingOptions& options, int input_dim) {
  const HashGridOptions& o = own_options<HashGridOptions>(options);
  const double table = std::ldexp(1.0, o.log2_table_size);
  const double growth =
      o.levels > 1 ? std::exp((std::log(static_cast<double>(o.finest_resolution)) -
                               std::log(static_cast<double>(o.base_resolution))) /
                              (o.levels - 1))
                   : 1.0;
  std::vector<HashGridLevel> levels(o.levels);
  Eigen::Index first = 0;
  for (int l = 0; l < o.levels; ++l) {
    // The relative nudge keeps ⌊N_min b^(L−1)⌋ at N_max against rounding in exp and log.
    const double n = std::floor(o.base_resolution * std::pow(growth, l) * (1 + 1e-9));
    HashGridLevel& level = levels[l];
    level.resolution = static_cast<int>(std::clamp(n, 1.0, static_cast<double>(o.finest_resolution)));
    // Vertices 0 … N + 1 per axis, or −1 … N + 2 with cubic's four taps.
    const double vertices = std::pow(level.resolution + (is_cubic(o) ? 4.0 : 2.0), input_dim);
    level.dense = vertices <= table;
    level.rows = static_cast<Eigen::Index>(level.dense ? vertices : table);
    level.first_row = first;
    first += level.rows;
  }
  return levels;
}

template <typename Scalar>
HashGridEncoding<Scalar>::HashGridEncoding(const EncodingOptions& options, int input_dim)
    : dim_(input_dim),
      features_(own_options<HashGridOptions>(options).features_per_level),
      smoothstep_(is_smoothstep(own_options<HashGridOptions>(options))),
      cubic_(is_cubic(own_options<HashGridOptions>(options))),
      bits_(cubic_ ? 2 : 1),
      include_input_(own_options<HashGridOptions>(options).include_input),
      init_scale_(own_options<HashGridOptions>(options).init_scale) {
  if (input_dim < 1 || input_dim > kMaxDim)
    throw std::invalid_argument("hash_grid encoding: input_dim = " + std::to_string(input_dim) +
                                ": must be in [1, 4]");
  levels_ = hash_grid_levels(options, input_dim);
  double range[kMaxDim];
  for (int j = 0; j < dim_; ++j) {
    const double lo = options.lower.empty() ? 0.0 : options.lower[j];
    const double hi = options.upper.empty() ? 1.0 : options.upper[j];
    lower_[j] = static_cast<Scalar>(lo);
    range[j] = hi - lo;
  }
  for (const HashGridLevel& info : levels_) {
    Level level{};
    level.info = info;
    std::uint64_t stride = 1;
    for (int j = 0; j < dim_; ++j) {
      level.scale[j] = static_cast<Scalar>(info.resolution / range[j]);
      level.stride[j] = info.dense ? static_cast<std::uint32_t>(stride) : 0u;
      stride *= static_cast<std::uint64_t>(info.resolution) + (cubic_ ? 4 : 2);
    }
    level.mask = static_cast<std::uint32_t>((std::uint64_t{1} << own_options<HashGridOptions>(options).log2_table_size) - 1);
    grid_.push_back(level);
  }
  rows_ = levels_.back().first_row + levels_.back().rows;
}

template <typename Scalar>
std::uint32_t HashGridEncoding<Scalar>::row(int level, const int* vertex) const {
  const Level& g = grid_.at(level);
  std::uint32_t r = 0;
  for (int j = 0; j < dim_; ++j) {
    // Cubic's vertices start at −1: stored one further.
    const auto v = static_cast<std::uint32_t>(vertex[j] + (cubic_ ? 1 : 0));
    if (g.info.dense)
      r += v * g.stride[j];
    else
      r ^= v * kPrimes[j];
  }
  return g.info.dense ? r : (r & g.mask);
}

template <typename Scalar>
bool HashGridEncoding<Scalar>::initialize(Scalar* params, std::mt19937_64& rng) const {
  // From the raw engine, like the dense layers: independent of library distributions.
  for (Eigen::Index i = 0; i < parameter_count(); ++i)
    params[i] = static_cast<Scalar>(
        init_scale_ * (2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0));
  return true;
}

namespace {

// The four uniform cubic B-spline weights of vertices c − 1 … c + 2 at t ∈ [0, 1) and their
// derivatives of order 1–3 in x (s = ∂t/∂x): w[tap][order].
template <typename Scalar>
void cubic_weights(Scalar t, Scalar s, Scalar (*w)[4]) {
  const Scalar u = 1 - t, t2 = t * t, s2 = s * s, s3 = s2 * s;
  constexpr Scalar sixth = Scalar(1) / 6;
  w[0][0] = u * u * u * sixth;
  w[0][1] = -Scalar(0.5) * u * u * s;
  w[0][2] = u * s2;
  w[0][3] = -s3;
  w[1][0] = (3 * t2 * t - 6 * t2 + 4) * sixth;
  w[1][1] = (Scalar(1.5) * t2 - 2 * t) * s;
  w[1][2] = (3 * t - 2) * s2;
  w[1][3] = 3 * s3;
  w[2][0] = (-3 * t2 * t + 3 * t2 + 3 * t + 1) * sixth;
  w[2][1] = (-Scalar(1.5) * t2 + t + Scalar(0.5)) * s;
  w[2][2] = (1 - 3 * t) * s2;
  w[2][3] = -3 * s3;
  w[3][0] = t2 * t * sixth;
  w[3][1] = Scalar(0.5) * t2 * s;
  w[3][2] = t * s2;
  w[3][3] = s3;
}

}  // namespace

template <typename Scalar>
void HashGridEncoding<Scalar>::locate(const Level& level, const Scalar* x, Cell& cell) const {
  const Scalar last = static_cast<Scalar>(level.info.resolution);
  const int taps = 1 << bits_;
  std::uint32_t term[kMaxDim][kMaxTaps];
  for (int j = 0; j < dim_; ++j) {
    const Scalar s = level.scale[j];
    const Scalar p = (x[j] - lower_[j]) * s + Scalar(0.5);
    Scalar c = std::floor(p);
    if (!(c >= 0)) c = 0;  // NaN too
    if (c > last) c = last;
    Scalar t = p - c;
    cell.scale[j] = s;
    if (cubic_) {
      // Outside [0, 1) (beyond the box's outer half cells) the outer cell's cubic continues.
      cubic_weights(t, s, cell.w[j]);
    } else {
      Scalar f[4];
      if (!smoothstep_) {
        f[0] = t;
        f[1] = s;
        f[2] = f[3] = 0;
      } else if (t >= 0 && t <= 1) {
        f[0] = t * t * (3 - 2 * t);
        f[1] = 6 * s * t * (1 - t);
        f[2] = 6 * s * s * (1 - 2 * t);
        f[3] = -12 * s * s * s;
      } else {
        t = t < 0 ? Scalar(0) : Scalar(1);
        f[0] = t;
        f[1] = f[2] = f[3] = 0;
        cell.scale[j] = 0;
      }
      // Vertex c_j weighs 1 − φ_j, vertex c_j + 1 weighs φ_j.
      cell.w[j][0][0] = 1 - f[0];
      cell.w[j][1][0] = f[0];
      for (int k = 1; k < 4; ++k) {
        cell.w[j][0][k] = -f[k];
        cell.w[j][1][k] = f[k];
      }
    }
    cell.t[j] = t;
    // The first tap's vertex is c_j, or c_j − 1 stored one further (cubic): c_j either way.
    const auto v = static_cast<std::uint32_t>(static_cast<int>(c));
    const std::uint32_t weight = level.info.dense ? level.stride[j] : kPrimes[j];
    for (int k = 0; k < taps; ++k) term[j][k] = (v + k) * weight;
  }
  const int corners = 1 << (dim_ * bits_);
  for (int v = 0; v < corners; ++v) {
    std::uint32_t r = 0;
    if (level.info.dense) {
      for (int j = 0; j < dim_; ++j) r += term[j][tap(v, j, bits_)];
    } else {
      for (int j = 0; j < dim_; ++j) r ^= term[j][tap(v, j, bits_)];
      r &= level.mask;
    }
    cell.rows[v] = r;
  }
}

template <typename Scalar>
void HashGridEncoding<Scalar>::gather(const StreamLayout& layout, const Offsets& o,
                                      const Streams<Scalar>& in, std::vector<Scalar>& inputs) const {
  const Eigen::Index n_points = in.points;
  const int d = dim_;
  const Matrix<Scalar>& a = in.data;
  inputs.resize(static_cast<size_t>(n_points * o.stride));
  for (Eigen::Index n = 0; n < n_points; ++n) {
    Scalar* p = inputs.data() + n * o.stride;
    for (int j = 0; j < d; ++j) p[j] = a(n, j);
    for (int i = 0; i < o.tangents; ++i)
      for (int j = 0; j < d; ++j) p[o.a + i * d + j] = a(layout.tangent(i) * n_points + n, j);
    for (int q = 0; q < o.operators; ++q) {
      for (int j = 0; j < d; ++j) p[o.b + q * d + j] = a(layout.op(q) * n_points + n, j);
      Scalar* m = p + o.m + q * d * d;
      std::fill(m, m + d * d, Scalar(0));
      for (const autodiff::OperatorTerm& term : layout.terms(q)) {
        const Scalar* ai = p + o.a + term.i * d;
        const Scalar* aj = p + o.a + term.j * d;
        const Scalar half = static_cast<Scalar>(term.coefficient / 2);
        for (int j = 0; j < d; ++j)
          for (int k = 0; k < d; ++k) m[j * d + k] += half * (ai[j] * aj[k] + aj[j] * ai[k]);
      }
    }
    for (int dir = 0; dir < o.dirs; ++dir)
      for (int k = 1; k <= o.order; ++k)
        for (int j = 0; j < d; ++j)
          p[o.taylor_at(dir, k) + j] = a(layout.taylor(dir, k) * n_points + n, j);
  }
}

// κ[s·C + v] for every stream s and corner v (the header's table).
template <typename Scalar>
void HashGridEncoding<Scalar>::corner_weights(const StreamLayout& layout, const Offsets& o,
                                              const Cell& cell, const Scalar* point,
                                              Scalar* kappa) const {
  const int d = dim_, corners = o.corners;
  const bool first = o.tangents > 0 || o.operators > 0, second = o.operators > 0;
  for (int v = 0; v < corners; ++v) {
    Scalar g[kMaxDim][3];
    for (int j = 0; j < d; ++j)
      for (int k = 0; k <= (second ? 2 : first ? 1 : 0); ++k) g[j][k] = factor(cell, v, j, k, o.bits);
    Scalar w = 1;
    for (int j = 0; j < d; ++j) w *= g[j][0];
    kappa[v] = w;
    if (!first) continue;
    Scalar grad[kMaxDim], hess[kMaxDim][kMaxDim];
    for (int j = 0; j < d; ++j) {
      Scalar p = g[j][1];
      for (int m = 0; m < d; ++m)
        if (m != j) p *= g[m][0];
      grad[j] = p;
    }
    if (second)
      for (int j = 0; j < d; ++j)
        for (int k = j; k < d; ++k) {
          Scalar p = j == k ? g[j][2] : g[j][1] * g[k][1];
          for (int m = 0; m < d; ++m)
            if (m != j && m != k) p *= g[m][0];
          hess[j][k] = hess[k][j] = p;
        }
    for (int i = 0; i < o.tangents; ++i) {
      const Scalar* a = point + o.a + i * d;
      Scalar sum = 0;
      for (int j = 0; j < d; ++j) sum += grad[j] * a[j];
      kappa[layout.tangent(i) * corners + v] = sum;
    }
    for (int q = 0; q < o.operators; ++q) {
      const Scalar* b = point + o.b + q * d;
      const Scalar* m = point + o.m + q * d * d;
      Scalar sum = 0;
      for (int j = 0; j < d; ++j) sum += grad[j] * b[j];
      for (int j = 0; j < d; ++j)
        for (int k = 0; k < d; ++k) sum += hess[j][k] * m[j * d + k];
      kappa[layout.op(q) * corners + v] = sum;
    }
  }
  if (o.dirs > 0) taylor_weights(layout, o, cell, point, kappa);
}

// ---------------------------------------------------------------------------------------
// Passes.

template <typename Scalar>
void HashGridEncoding<Scalar>::forward(const StreamLayout& layout, const Scalar* params,
                                       const Streams<Scalar>& in, Streams<Scalar>& out,
                                       autodiff::SavedTensors<Scalar>* saved) const {
  const Offsets o(layout, dim_, bits_);
  const Eigen::Index n_points = in.points;
  const int corners = o.corners, streams = o.streams, f_count = features_;
  const auto level_count = static_cast<Eigen::Index>(grid_.size());
  thread_local std::vector<Scalar> inputs, kappa, acc;
  kappa.resize(static_cast<size_t>(streams * corners));
  acc.resize(static_cast<size_t>(streams * f_count));
  const Eigen::Index first_column = input_columns();
  out.resize(n_points, in.count, first_column + level_count * f_count);
  if (first_column > 0) out.data.leftCols(first_column) = in.data;
  Scalar *rows_out = nullptr, *kappa_out = nullptr;
  if (saved) {
    // Rows are below 2^24, so even a float holds them exactly.
    saved->resize(2);
    (*saved)[0].resize(corners, n_points * level_count);
    (*saved)[1].resize(streams * corners, n_points * level_count);
    rows_out = (*saved)[0].data();
    kappa_out = (*saved)[1].data();
  }
  if (streams == 1) {
    switch (dim_) {
      case 1: return cubic_ ? forward_values<1, 4>(params, in, out, rows_out, kappa_out)
                            : forward_values<1, 2>(params, in, out, rows_out, kappa_out);
      case 2: return cubic_ ? forward_values<2, 4>(params, in, out, rows_out, kappa_out)
                            : forward_values<2, 2>(params, in, out, rows_out, kappa_out);
      case 3: return cubic_ ? forward_values<3, 4>(params, in, out, rows_out, kappa_out)
                            : forward_values<3, 2>(params, in, out, rows_out, kappa_out);
      default: return cubic_ ? forward_values<4, 4>(params, in, out, rows_out, kappa_out)
                             : forward_values<4, 2>(params, in, out, rows_out, kappa_out);
    }
  }
  gather(layout, o, in, inputs);
  Cell cell;
  // Level by level: one table at a time stays in cache.
  for (Eigen::Index l = 0; l < level_count; ++l) {
    const Level& level = grid_[l];
    const Scalar* table = params + level.info.first_row * f_count;
    for (Eigen::Index n = 0; n < n_points; ++n) {
      const Scalar* point = inputs.data() + n * o.stride;
      locate(level, point, cell);
      corner_weights(layout, o, cell, point, kappa.data());
      std::fill(acc.begin(), acc.end(), Scalar(0));
      for (int v = 0; v < corners; ++v) {
        const Scalar* entry = table + static_cast<Eigen::Index>(cell.rows[v]) * f_count;
        for (int s = 0; s < streams; ++s) {
          const Scalar k = kappa[s * corners + v];
          for (int f = 0; f < f_count; ++f) acc[s * f_count + f] += k * entry[f];
        }
      }
      for (int s = 0; s < streams; ++s)
        for (int f = 0; f < f_count; ++f)
          out.data(s * n_points + n, first_column + l * f_count + f) = acc[s * f_count + f];
      if (saved) {
        const Eigen::Index column = l * n_points + n;
        for (int v = 0; v < corners; ++v)
          rows_out[column * corners + v] = static_cast<Scalar>(cell.rows[v]);
        std::copy(kappa.begin(), kappa.end(), kappa_out + column * streams * corners);
      }
    }
  }
}

// The value stream alone (radiance fields, fits of values), the common case: the same
// weights and rows as locate and corner_weights (bit for bit: the same products in the same
// order), the Taps^D weights by multiplying out axis after axis, with loops of fixed length. Per level,
// a first pass finds every point's rows and weights, and the second gathers the table rows,
// prefetching a few points ahead: hashed rows are scattered over megabytes, and the loads of
// several points then overlap instead of waiting one after the other.
template <typename Scalar>
template <int D, int Taps>
void HashGridEncoding<Scalar>::forward_values(const Scalar* params, const Streams<Scalar>& in,
                                              Streams<Scalar>& out, Scalar* rows_out,
                                              Scalar* kappa_out) const {
  constexpr int corners = Taps == 2 ? 1 << D : 1 << (2 * D);
  constexpr Eigen::Index ahead = 8;  // points
  const Eigen::Index n_points = in.points, in_rows = in.data.rows(), out_rows = out.data.rows();
  const int f_count = features_;
  const Scalar* x = in.data.data();
  thread_local std::vector<std::uint32_t> rows;
  thread_local std::vector<Scalar> weights;
  rows.resize(static_cast<size_t>(n_points * corners));
  weights.resize(static_cast<size_t>(n_points * corners));
  for (size_t l = 0; l < grid_.size(); ++l) {
    const Level& level = grid_[l];
    const bool dense = level.info.dense;
    const Scalar last = static_cast<Scalar>(level.info.resolution);
    for (Eigen::Index n = 0; n < n_points; ++n) {
      Scalar* w = weights.data() + n * corners;
      std::uint32_t* r = rows.data() + n * corners;
      w[0] = 1;
      r[0] = 0;
      for (int j = 0; j < D; ++j) {
        const Scalar p = (x[j * in_rows + n] - lower_[j]) * level.scale[j] + Scalar(0.5);
        Scalar c = std::floor(p);
        if (!(c >= 0)) c = 0;
        if (c > last) c = last;
        const Scalar t = p - c;
        const auto v = static_cast<std::uint32_t>(static_cast<int>(c));
        const std::uint32_t weight = dense ? level.stride[j] : kPrimes[j];
        if constexpr (Taps == 2) {
          const Scalar phi = !smoothstep_              ? t
                             : (t >= 0 && t <= 1)      ? t * t * (3 - 2 * t)
                             : t < 0                   ? Scalar(0)
                                                       : Scalar(1);
          const std::uint32_t a0 = v * weight, a1 = (v + 1) * weight;
          for (int k = 0; k < (1 << j); ++k) {
            w[k + (1 << j)] = w[k] * phi;
            w[k] *= 1 - phi;
            r[k + (1 << j)] = dense ? r[k] + a1 : r[k] ^ a1;
            r[k] = dense ? r[k] + a0 : r[k] ^ a0;
          }
        } else {
          Scalar b[4][4];
          cubic_weights(t, Scalar(0), b);
          const int count = 1 << (2 * j);
          for (int k = 0; k < count; ++k) {
            for (int tap = 3; tap >= 0; --tap) {
              const std::uint32_t a = (v + tap) * weight;
              w[k + tap * count] = w[k] * b[tap][0];
              r[k + tap * count] = dense ? r[k] + a : r[k] ^ a;
            }
          }
        }
      }
      if (!dense)
        for (int v = 0; v < corners; ++v) r[v] &= level.mask;
    }
    const Scalar* table = params + level.info.first_row * f_count;
    Scalar* y = out.data.data() + (input_columns() + static_cast<Eigen::Index>(l) * f_count) * out_rows;
    for (Eigen::Index n = 0; n < n_points; ++n) {
      if (!dense && n + ahead < n_points)
        for (int v = 0; v < corners; ++v)
          __builtin_prefetch(table + static_cast<Eigen::Index>(rows[(n + ahead) * corners + v]) * f_count);
      const Scalar* w = weights.data() + n * corners;
      const std::uint32_t* r = rows.data() + n * corners;
      for (int f = 0; f < f_count; ++f) {
        Scalar sum = 0;
        for (int v = 0; v < corners; ++v) sum += w[v] * table[static_cast<Eigen::Index>(r[v]) * f_count + f];
        y[f * out_rows + n] = sum;
      }
    }
    if (rows_out) {
      const Eigen::Index first = static_cast<Eigen::Index>(l) * n_points * corners;
      for (Eigen::Index i = 0; i < n_points * corners; ++i) {
        rows_out[first + i] = static_cast<Scalar>(rows[i]);
        kappa_out[first + i] = weights[i];
      }
    }
  }
}

template class HashGridEncoding<float>;
template class HashGridEncoding<double>;

}  // namespace nfield::fields
