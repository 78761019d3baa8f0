// SPDX-License-Identifier: MIT
// The hash grid's reverse pass: the tables' gradient, per batch or per point, and the adjoint
// of the input streams (the math: hash_grid.h, "Streams").
#include <algorithm>
#include <vector>

#include "fields/hash_grid.h"
#include "fields/hash_grid_cell.h"

namespace nfield::fields {

using autodiff::Matrix;
using autodiff::StreamLayout;
using autodiff::Streams;
using namespace hash_grid_detail;

// T̄[row(v)] += Σ_s κ_{s,v} ȳ_s: into `gradient`, or into point n's row of `jacobian`.
template <typename Scalar>
void HashGridEncoding<Scalar>::table_adjoint(const Offsets& o, const Streams<Scalar>& in,
                                             const autodiff::SavedTensors<Scalar>& saved,
                                             const Streams<Scalar>& out_adjoint,
                                             Scalar* gradient,
                                             autodiff::JacobianRows<Scalar>* jacobian) const {
  const Eigen::Index n_points = in.points;
  const int corners = o.corners, streams = o.streams, f_count = features_;
  const auto level_count = static_cast<Eigen::Index>(grid_.size());
  if (saved.size() != 2 || saved[0].cols() != n_points * level_count)
    throw std::logic_error("hash_grid encoding: backward without a recording forward pass");
  thread_local std::vector<Scalar> y_bar;
  y_bar.resize(static_cast<size_t>(streams * f_count));
  constexpr Eigen::Index ahead = 8;  // points; see forward_values
  for (Eigen::Index l = 0; l < level_count; ++l) {
    const Eigen::Index first = grid_[l].info.first_row * f_count;
    const bool hashed = !grid_[l].info.dense && !jacobian;
    for (Eigen::Index n = 0; n < n_points; ++n) {
      if (hashed && n + ahead < n_points) {
        const Scalar* next = saved[0].data() + (l * n_points + n + ahead) * corners;
        for (int v = 0; v < corners; ++v)
          __builtin_prefetch(gradient + first + static_cast<Eigen::Index>(next[v]) * f_count, 1);
      }
      bool any = false;
      for (int s = 0; s < streams; ++s)
        for (int f = 0; f < f_count; ++f) {
          const Scalar y = out_adjoint.data(s * n_points + n, input_columns() + l * f_count + f);
          y_bar[s * f_count + f] = y;
          any = any || y != 0;
        }
      if (!any) continue;
      const Eigen::Index column = l * n_points + n;
      const Scalar* rows = saved[0].data() + column * corners;
      const Scalar* kappa = saved[1].data() + column * streams * corners;
      Scalar* base = (jacobian ? &(*jacobian)(n, 0) : gradient) + first;
      for (int v = 0; v < corners; ++v) {
        Scalar* entry = base + static_cast<Eigen::Index>(rows[v]) * f_count;
        for (int f = 0; f < f_count; ++f) {
          Scalar sum = 0;
          for (int s = 0; s < streams; ++s) sum += kappa[s * corners + v] * y_bar[s * f_count + f];
          entry[f] += sum;
        }
      }
    }
  }
}

template <typename Scalar>
void HashGridEncoding<Scalar>::backward(const StreamLayout& layout, const Scalar* params,
                                        const Streams<Scalar>& in,
                                        const autodiff::SavedTensors<Scalar>& saved,
                                        Streams<Scalar>& out_adjoint, Scalar* gradient,
                                        Streams<Scalar>* in_adjoint) const {
  const Offsets o(layout, dim_, bits_);
  if (gradient) table_adjoint(o, in, saved, out_adjoint, gradient, nullptr);
  if (in_adjoint) input_adjoint(layout, params, in, out_adjoint, *in_adjoint);
}

template <typename Scalar>
void HashGridEncoding<Scalar>::backward_per_point(const StreamLayout& layout, const Scalar* params,
                                                  const Streams<Scalar>& in,
                                                  const autodiff::SavedTensors<Scalar>& saved,
                                                  Streams<Scalar>& out_adjoint,
                                                  autodiff::JacobianRows<Scalar> jacobian,
                                                  Streams<Scalar>* in_adjoint) const {
  const Offsets o(layout, dim_, bits_);
  for (Eigen::Index n = 0; n < in.points; ++n) jacobian.row(n).setZero();
  table_adjoint(o, in, saved, out_adjoint, nullptr, &jacobian);
  if (in_adjoint) input_adjoint(layout, params, in, out_adjoint, *in_adjoint);
}

namespace {

// Summed over corners: g_s = Σ_v ω_{s,v} ∇W_v for the `plain` streams (those before the Taylor
// ones), H_s = Σ_v ω_{s,v} ∇²W_v for the tangent and operator streams, and
// I_q = Σ_v ω_{q,v} ∇³W_v for the operators; ∂^α W_v = Π_j (factor j differentiated α_j times).
template <typename Scalar>
void derivative_sums(const StreamLayout& layout, const Offsets& o, const Cell<Scalar>& cell, int plain,
                     const Scalar* omega, std::vector<Scalar>& grad, std::vector<Scalar>& hess,
                     std::vector<Scalar>& third) {
  const int d = o.d, corners = o.corners;
  std::fill(grad.begin(), grad.end(), Scalar(0));
  std::fill(hess.begin(), hess.end(), Scalar(0));
  std::fill(third.begin(), third.end(), Scalar(0));
  for (int v = 0; v < corners; ++v) {
    auto derivative = [&](const int* alpha) {
      Scalar p = 1;
      for (int j = 0; j < d; ++j) p *= factor(cell, v, j, alpha[j], o.bits);
      return p;
    };
    for (int j = 0; j < d; ++j) {
      int alpha[kMaxDim] = {0, 0, 0, 0};
      ++alpha[j];
      const Scalar g = derivative(alpha);
      for (int s = 0; s < plain; ++s) grad[s * d + j] += omega[s * corners + v] * g;
      if (plain == 1) continue;
      for (int k = 0; k < d; ++k) {
        ++alpha[k];
        const Scalar h = derivative(alpha);
        for (int s = 1; s < plain; ++s) hess[(s * d + j) * d + k] += omega[s * corners + v] * h;
        for (int m = 0; m < d && o.operators > 0; ++m) {
          ++alpha[m];
          const Scalar t3 = derivative(alpha);
          for (int q = 0; q < o.operators; ++q)
            third[((q * d + j) * d + k) * d + m] += omega[layout.op(q) * corners + v] * t3;
          --alpha[m];
        }
        --alpha[k];
      }
    }
  }
}

// x̄, ā⁽ⁱ⁾ and ā^[q] of one point (`bar`, laid out as its gathered `point`) from g, H and I.
template <typename Scalar>
void add_plain_adjoint(const StreamLayout& layout, const Offsets& o, const Scalar* point, const Scalar* grad,
                       const Scalar* hess, const Scalar* third, Scalar* bar) {
  const int d = o.d;
  // H v added to out.
  auto add_hess = [&](int s, const Scalar* vec, Scalar scale, Scalar* out) {
    for (int j = 0; j < d; ++j) {
      Scalar sum = 0;
      for (int k = 0; k < d; ++k) sum += hess[(s * d + j) * d + k] * vec[k];
      out[j] += scale * sum;
    }
  };
  for (int j = 0; j < d; ++j) bar[j] += grad[j];
  for (int i = 0; i < o.tangents; ++i) {
    const int s = layout.tangent(i);
    for (int j = 0; j < d; ++j) bar[o.a + i * d + j] += grad[s * d + j];
    add_hess(s, point + o.a + i * d, 1, bar);
  }
  for (int q = 0; q < o.operators; ++q) {
    const int s = layout.op(q);
    for (int j = 0; j < d; ++j) bar[o.b + q * d + j] += grad[s * d + j];
    add_hess(s, point + o.b + q * d, 1, bar);
    const Scalar* m = point + o.m + q * d * d;
    for (int j = 0; j < d; ++j)
      for (int k = 0; k < d; ++k)
        for (int r = 0; r < d; ++r) bar[r] += m[j * d + k] * third[((q * d + j) * d + k) * d + r];
    for (const autodiff::OperatorTerm& term : layout.terms(q)) {
      const auto c = static_cast<Scalar>(term.coefficient);
      add_hess(s, point + o.a + term.j * d, c, bar + o.a + term.i * d);
      add_hess(s, point + o.a + term.i * d, c, bar + o.a + term.j * d);
    }
  }
}

// The per-point adjoints, gathered as the inputs are (Offsets), into the input streams' rows.
template <typename Scalar>
void scatter_adjoint(const StreamLayout& layout, const Offsets& o, const std::vector<Scalar>& adjoint,
                     Eigen::Index n_points, Matrix<Scalar>& a) {
  const int d = o.d;
  for (Eigen::Index n = 0; n < n_points; ++n) {
    const Scalar* bar = adjoint.data() + n * o.stride;
    for (int j = 0; j < d; ++j) a(n, j) = bar[j];
    for (int i = 0; i < o.tangents; ++i)
      for (int j = 0; j < d; ++j) a(layout.tangent(i) * n_points + n, j) = bar[o.a + i * d + j];
    for (int q = 0; q < o.operators; ++q)
      for (int j = 0; j < d; ++j) a(layout.op(q) * n_points + n, j) = bar[o.b + q * d + j];
    for (int dir = 0; dir < o.dirs; ++dir)
      for (int k = 1; k <= o.order; ++k)
        for (int j = 0; j < d; ++j)
          a(layout.taylor(dir, k) * n_points + n, j) = bar[o.taylor_at(dir, k) + j];
  }
}

}  // namespace

// ∂L/∂(input streams). With ω_{s,v} = ȳ_s · T[row(v)] and, summed over corners,
// g_s = Σ_v ω_{s,v} ∇W_v, H_s = Σ_v ω_{s,v} ∇²W_v, I_s = Σ_v ω_{s,v} ∇³W_v:
//   x̄ = g_value + Σᵢ H_i a⁽ⁱ⁾ + Σ_q (H_q a^[q] + I_q : M_q)
//   ā⁽ⁱ⁾ = g_i + Σ_q Σ_terms c H_q a⁽ʲ⁾      ā^[q] = g_q
// and the Taylor streams through the adjoints of their series products.
template <typename Scalar>
void HashGridEncoding<Scalar>::input_adjoint(const StreamLayout& layout, const Scalar* params,
                                             const Streams<Scalar>& in,
                                             const Streams<Scalar>& out_adjoint,
                                             Streams<Scalar>& in_adjoint) const {
  const Offsets o(layout, dim_, bits_);
  const Eigen::Index n_points = in.points;
  const int d = dim_, corners = o.corners, streams = o.streams, f_count = features_;
  const int plain = 1 + o.tangents + o.operators;  // streams before the Taylor ones
  thread_local std::vector<Scalar> inputs, adjoint, omega, grad, hess, third;
  gather(layout, o, in, inputs);
  adjoint.assign(inputs.size(), Scalar(0));
  omega.resize(static_cast<size_t>(streams * corners));
  grad.resize(static_cast<size_t>(plain * d));
  hess.resize(static_cast<size_t>(plain * d * d));
  third.resize(static_cast<size_t>(std::max(o.operators, 1) * d * d * d));
  Cell cell;
  for (size_t l = 0; l < grid_.size(); ++l) {
    const Level& level = grid_[l];
    const Scalar* table = params + level.info.first_row * f_count;
    for (Eigen::Index n = 0; n < n_points; ++n) {
      const Scalar* point = inputs.data() + n * o.stride;
      Scalar* bar = adjoint.data() + n * o.stride;
      locate(level, point, cell);
      // ω_{s,v} = ȳ_s · T[row(v)]. (Kept here: as a function of its own, the compiler fused
      // its multiply-adds differently, and float results changed in the last bit.)
      for (int v = 0; v < corners; ++v) {
        const Scalar* entry = table + static_cast<Eigen::Index>(cell.rows[v]) * f_count;
        for (int s = 0; s < streams; ++s) {
          Scalar sum = 0;
          for (int f = 0; f < f_count; ++f)
            sum += out_adjoint.data(s * n_points + n,
                                    input_columns() + static_cast<Eigen::Index>(l) * f_count + f) *
                   entry[f];
          omega[s * corners + v] = sum;
        }
      }
      derivative_sums(layout, o, cell, plain, omega.data(), grad, hess, third);
      add_plain_adjoint(layout, o, point, grad.data(), hess.data(), third.data(), bar);
      if (o.dirs > 0) taylor_adjoint(layout, o, cell, point, omega.data(), bar);
    }
  }
  in_adjoint.resize(n_points, in.count, d);
  Matrix<Scalar>& a = in_adjoint.data;
  scatter_adjoint(layout, o, adjoint, n_points, a);
  if (include_input_) a += out_adjoint.data.leftCols(d);
}

#define NFIELD_HASH_GRID_REVERSE(Scalar)                                                                        \
  template void HashGridEncoding<Scalar>::table_adjoint(const Offsets&, const Streams<Scalar>&,                   \
                                                        const autodiff::SavedTensors<Scalar>&, const Streams<Scalar>&, \
                                                        Scalar*, autodiff::JacobianRows<Scalar>*) const;          \
  template void HashGridEncoding<Scalar>::backward(const StreamLayout&, const Scalar*, const Streams<Scalar>&,    \
                                                   const autodiff::SavedTensors<Scalar>&, Streams<Scalar>&, Scalar*, \
                                                   Streams<Scalar>*) const;                                       \
  template void HashGridEncoding<Scalar>::backward_per_point(                                                     \
      const StreamLayout&, const Scalar*, const Streams<Scalar>&, const autodiff::SavedTensors<Scalar>&,          \
      Streams<Scalar>&, autodiff::JacobianRows<Scalar>, Streams<Scalar>*) const;                                  \
  template void HashGridEncoding<Scalar>::input_adjoint(const StreamLayout&, const Scalar*, const Streams<Scalar>&, \
                                                        const Streams<Scalar>&, Streams<Scalar>&) const;
NFIELD_HASH_GRID_REVERSE(float)
NFIELD_HASH_GRID_REVERSE(double)
#undef NFIELD_HASH_GRID_REVERSE
}  // namespace nfield::fields
