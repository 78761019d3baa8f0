// SPDX-License-Identifier: MIT
#include "autodiff/elementwise.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace nfield::autodiff {
namespace {

template <typename Scalar>
using Column = Eigen::Array<Scalar, Eigen::Dynamic, 1>;

void require_tables(size_t have, int need, const char* pass) {
  if (static_cast<int>(have) < need)
    throw std::logic_error(std::string(pass) + ": " + std::to_string(have) +
                           " derivative tables given, the streams need " + std::to_string(need));
}

// Powers P[m][k] = (δᵐ)_k of one column's Taylor series, m = 1..K, k = m..K.
template <typename Scalar>
class TaylorPowers {
 public:
  TaylorPowers(int order, Eigen::Index n) : order_(order), powers_((order + 1) * (order + 1)) {
    for (auto& p : powers_) p.resize(n);
  }
  Column<Scalar>& at(int m, int k) { return powers_[m * (order_ + 1) + k]; }

  // delta[k] = δ_k for k = 1..K (delta[0] unused).
  void compute(const std::vector<Column<Scalar>>& delta) {
    for (int k = 1; k <= order_; ++k) at(1, k) = delta[k];
    for (int m = 2; m <= order_; ++m)
      for (int k = m; k <= order_; ++k) {
        Column<Scalar>& p = at(m, k);
        p = delta[1] * at(m - 1, k - 1);
        for (int j = 2; j <= k - m + 1; ++j) p += delta[j] * at(m - 1, k - j);
      }
  }

 private:
  int order_;
  std::vector<Column<Scalar>> powers_;
};

template <typename Scalar>
std::vector<Scalar> inverse_factorials(int n) {
  std::vector<Scalar> f(n + 1, Scalar(1));
  double value = 1;
  for (int m = 1; m <= n; ++m) f[m] = static_cast<Scalar>(1.0 / (value *= m));
  return f;
}

// Columns per pass: the rules run over a few columns of every stream at a time, so that a
// chunk's streams, tables and adjoints (a dozen arrays for a Laplacian) stay in L1/L2 across
// the rules' passes instead of streaming each whole array from L3 once per pass.
inline Eigen::Index chunk_columns(Eigen::Index points) {
  return std::max<Eigen::Index>(1, 4096 / std::max<Eigen::Index>(points, 1));
}

// acc ← Σᵢⱼ Cᵢⱼ z⁽ⁱ⁾ ⊙ z⁽ʲ⁾ of operator stream q (its terms non-empty), on the chunk `part` selects.
template <typename Scalar, typename Part, typename Scratch>
void quadratic_terms(const StreamLayout& layout, int q, const Part& part, const Streams<Scalar>& z,
                     Scratch& acc) {
  const auto& terms = layout.terms(q);
  acc = Scalar(terms[0].coefficient) * part(z.stream(layout.tangent(terms[0].i))) *
        part(z.stream(layout.tangent(terms[0].j)));
  for (size_t t = 1; t < terms.size(); ++t)
    acc += Scalar(terms[t].coefficient) * part(z.stream(layout.tangent(terms[t].i))) *
           part(z.stream(layout.tangent(terms[t].j)));
}

// The reverse rule of operator stream q, on one chunk of columns (`part` selects it).
template <typename Scalar, typename Part, typename Chunk, typename Accumulator, typename Scratch>
void operator_backward(const StreamLayout& layout, int q, const Chunk& d1, const Chunk& d2,
                       const Chunk& d3, const Part& part, const Streams<Scalar>& z,
                       const Streams<Scalar>& y_adjoint, Accumulator& z0_bar,
                       Streams<Scalar>& z_adjoint, Scratch acc) {
  const auto yq_bar = part(y_adjoint.stream(layout.op(q)));
  part(z_adjoint.stream(layout.op(q))) = d1 * yq_bar;
  z0_bar += d2 * yq_bar * part(z.stream(layout.op(q)));
  if (layout.terms(q).empty()) return;
  quadratic_terms(layout, q, part, z, acc);
  z0_bar += d3 * yq_bar * acc;
  acc = d2 * yq_bar;  // g = σ'' ȳ^[C], reused by every term
  auto tangent_bar = [&](int i) { return part(z_adjoint.stream(layout.tangent(i))); };
  auto tangent = [&](int i) { return part(z.stream(layout.tangent(i))); };
  for (const OperatorTerm& term : layout.terms(q)) {
    const Scalar c = Scalar(term.coefficient);
    if (term.i == term.j) {
      tangent_bar(term.i) += (Scalar(2) * c) * acc * tangent(term.i);
    } else {
      tangent_bar(term.i) += c * acc * tangent(term.j);
      tangent_bar(term.j) += c * acc * tangent(term.i);
    }
  }
}

}  // namespace

template <typename Scalar>
void elementwise_forward(const StreamLayout& layout, const std::vector<Matrix<Scalar>>& tables,
                         const Streams<Scalar>& z, Streams<Scalar>& y) {
  require_tables(tables.size(), layout.forward_order() + 1, "elementwise_forward");
  const Eigen::Index n = z.points, width = z.width(), chunk = chunk_columns(n);
  y.resize(n, z.count, width);
  Matrix<Scalar> quadratic(n, layout.operators() > 0 ? std::min(chunk, width) : 0);
  for (Eigen::Index c0 = 0; c0 < width; c0 += chunk) {
    const Eigen::Index w = std::min(chunk, width - c0);
    auto part = [c0, w](auto&& m) { return m.middleCols(c0, w).array(); };
    part(y.values()) = part(tables[0]);
    if (layout.count() == 1) continue;
    const auto d1 = part(tables[1]);
    for (int i = 0; i < layout.tangents(); ++i)
      part(y.stream(layout.tangent(i))) = d1 * part(z.stream(layout.tangent(i)));
    for (int q = 0; q < layout.operators(); ++q) {
      auto yq = part(y.stream(layout.op(q)));
      yq = d1 * part(z.stream(layout.op(q)));
      if (layout.terms(q).empty()) continue;
      auto acc = quadratic.leftCols(w).array();
      quadratic_terms(layout, q, part, z, acc);
      yq += part(tables[2]) * acc;
    }
  }
  const int order = layout.taylor_order();
  if (layout.taylor_dirs() == 0) return;
  const std::vector<Scalar> inv_fact = inverse_factorials<Scalar>(order);
  TaylorPowers<Scalar> powers(order, n);
  std::vector<Column<Scalar>> delta(order + 1);
  for (int p = 0; p < layout.taylor_dirs(); ++p)
    for (Eigen::Index c = 0; c < width; ++c) {
      for (int k = 1; k <= order; ++k) delta[k] = z.stream(layout.taylor(p, k)).col(c).array();
      powers.compute(delta);
      for (int k = 1; k <= order; ++k) {
        auto yk = y.stream(layout.taylor(p, k)).col(c).array();
        yk = tables[1].col(c).array() * powers.at(1, k);
        for (int m = 2; m <= k; ++m) yk += (inv_fact[m] * tables[m].col(c).array()) * powers.at(m, k);
      }
    }
}

template <typename Scalar>
void elementwise_backward(const StreamLayout& layout, const std::vector<Matrix<Scalar>>& tables,
                          const Streams<Scalar>& z, const Streams<Scalar>& y_adjoint,
                          Streams<Scalar>& z_adjoint) {
  require_tables(tables.size(), layout.forward_order() + 2, "elementwise_backward");
  const Eigen::Index n = z.points, width = z.width(), chunk = chunk_columns(n);
  z_adjoint.resize(n, z.count, width);
  Matrix<Scalar> scratch(n, layout.operators() > 0 ? std::min(chunk, width) : 0);
  for (Eigen::Index c0 = 0; c0 < width; c0 += chunk) {
    const Eigen::Index w = std::min(chunk, width - c0);
    auto part = [c0, w](auto&& m) { return m.middleCols(c0, w).array(); };
    const auto d1 = part(tables[1]);
    auto z0_bar = part(z_adjoint.values());
    z0_bar = d1 * part(y_adjoint.values());
    if (layout.count() == 1) continue;
    const auto d2 = part(tables[2]);
    for (int i = 0; i < layout.tangents(); ++i) {
      const auto yi_bar = part(y_adjoint.stream(layout.tangent(i)));
      part(z_adjoint.stream(layout.tangent(i))) = d1 * yi_bar;
      z0_bar += d2 * yi_bar * part(z.stream(layout.tangent(i)));
    }
    for (int q = 0; q < layout.operators(); ++q)
      operator_backward(layout, q, d1, d2, part(tables[3]), part, z, y_adjoint, z0_bar, z_adjoint,
                        scratch.leftCols(w).array());
  }
  const int order = layout.taylor_order();
  if (layout.taylor_dirs() == 0) return;
  const std::vector<Scalar> inv_fact = inverse_factorials<Scalar>(order);
  TaylorPowers<Scalar> powers(order, n), power_bars(order, n);
  std::vector<Column<Scalar>> delta(order + 1), delta_bar(order + 1);
  for (int p = 0; p < layout.taylor_dirs(); ++p)
    for (Eigen::Index c = 0; c < width; ++c) {
      for (int k = 1; k <= order; ++k) {
        delta[k] = z.stream(layout.taylor(p, k)).col(c).array();
        delta_bar[k].setZero(n);
      }
      powers.compute(delta);
      auto z0c_bar = z_adjoint.values().col(c).array();
      for (int m = 1; m <= order; ++m)
        for (int k = m; k <= order; ++k) {
          const auto yk_bar = y_adjoint.stream(layout.taylor(p, k)).col(c).array();
          z0c_bar += (inv_fact[m] * tables[m + 1].col(c).array()) * yk_bar * powers.at(m, k);
          power_bars.at(m, k) = (inv_fact[m] * tables[m].col(c).array()) * yk_bar;
        }
      for (int m = order; m >= 2; --m)
        for (int k = m; k <= order; ++k)
          for (int j = 1; j <= k - m + 1; ++j) {
            delta_bar[j] += power_bars.at(m, k) * powers.at(m - 1, k - j);
            power_bars.at(m - 1, k - j) += power_bars.at(m, k) * delta[j];
          }
      for (int k = 1; k <= order; ++k)
        z_adjoint.stream(layout.taylor(p, k)).col(c).array() = delta_bar[k] + power_bars.at(1, k);
    }
}

namespace {

// Stream index of Taylor coefficient m along direction p; m = 0 is the value.
int taylor_stream(const StreamLayout& layout, int p, int m) { return m == 0 ? 0 : layout.taylor(p, m); }

}  // namespace

template <typename Scalar>
void product_forward(const StreamLayout& layout, const Streams<Scalar>& a, const Streams<Scalar>& b,
                     Streams<Scalar>& y) {
  if (a.width() != b.width() || a.points != b.points || a.count != b.count)
    throw std::logic_error("product_forward: the factors' streams differ in shape");
  y.resize(a.points, a.count, a.width());
  const auto a0 = a.values().array();
  const auto b0 = b.values().array();
  y.values().array() = a0 * b0;
  for (int i = 0; i < layout.tangents(); ++i) {
    const int s = layout.tangent(i);
    y.stream(s).array() = a.stream(s).array() * b0 + a0 * b.stream(s).array();
  }
  for (int q = 0; q < layout.operators(); ++q) {
    const int s = layout.op(q);
    auto yq = y.stream(s).array();
    yq = a.stream(s).array() * b0 + a0 * b.stream(s).array();
    for (const OperatorTerm& term : layout.terms(q)) {
      const int i = layout.tangent(term.i), j = layout.tangent(term.j);
      yq += Scalar(term.coefficient) *
            (a.stream(i).array() * b.stream(j).array() + a.stream(j).array() * b.stream(i).array());
    }
  }
  for (int p = 0; p < layout.taylor_dirs(); ++p)
    for (int k = 1; k <= layout.taylor_order(); ++k) {
      auto yk = y.stream(layout.taylor(p, k)).array();
      yk = a0 * b.stream(layout.taylor(p, k)).array();
      for (int m = 1; m <= k; ++m)
        yk += a.stream(taylor_stream(layout, p, m)).array() * b.stream(taylor_stream(layout, p, k - m)).array();
    }
}

template <typename Scalar>
void product_backward(const StreamLayout& layout, const Streams<Scalar>& a, const Streams<Scalar>& b,
                      const Streams<Scalar>& y_adjoint, Streams<Scalar>& a_adjoint,
                      Streams<Scalar>& b_adjoint) {
  a_adjoint.resize(a.points, a.count, a.width());
  b_adjoint.resize(b.points, b.count, b.width());
  a_adjoint.data.setZero();
  b_adjoint.data.setZero();
  // Every rule is a sum of products a_s b_t; each adds ȳ b_t to ā_s and ȳ a_s to b̄_t.
  auto add = [&](const auto& y_bar, int s, int t, Scalar c) {
    a_adjoint.stream(s).array() += c * y_bar * b.stream(t).array();
    b_adjoint.stream(t).array() += c * y_bar * a.stream(s).array();
  };
  add(y_adjoint.values().array(), 0, 0, Scalar(1));
  for (int i = 0; i < layout.tangents(); ++i) {
    const int s = layout.tangent(i);
    const auto y_bar = y_adjoint.stream(s).array();
    add(y_bar, s, 0, Scalar(1));
    add(y_bar, 0, s, Scalar(1));
  }
  for (int q = 0; q < layout.operators(); ++q) {
    const int s = layout.op(q);
    const auto y_bar = y_adjoint.stream(s).array();
    add(y_bar, s, 0, Scalar(1));
    add(y_bar, 0, s, Scalar(1));
    for (const OperatorTerm& term : layout.terms(q)) {
      const int i = layout.tangent(term.i), j = layout.tangent(term.j);
      add(y_bar, i, j, Scalar(term.coefficient));
      add(y_bar, j, i, Scalar(term.coefficient));
    }
  }
  for (int p = 0; p < layout.taylor_dirs(); ++p)
    for (int k = 1; k <= layout.taylor_order(); ++k) {
      const auto y_bar = y_adjoint.stream(layout.taylor(p, k)).array();
      for (int m = 0; m <= k; ++m) add(y_bar, taylor_stream(layout, p, m), taylor_stream(layout, p, k - m), Scalar(1));
    }
}

#define NFIELD_INSTANTIATE(Scalar)                                                           \
  template void elementwise_forward<Scalar>(const StreamLayout&,                             \
                                            const std::vector<Matrix<Scalar>>&,              \
                                            const Streams<Scalar>&, Streams<Scalar>&);       \
  template void elementwise_backward<Scalar>(const StreamLayout&,                            \
                                             const std::vector<Matrix<Scalar>>&,             \
                                             const Streams<Scalar>&, const Streams<Scalar>&, \
                                             Streams<Scalar>&);      \
  template void product_forward<Scalar>(const StreamLayout&, const Streams<Scalar>&,         \
                                        const Streams<Scalar>&, Streams<Scalar>&);           \
  template void product_backward<Scalar>(const StreamLayout&, const Streams<Scalar>&,        \
                                         const Streams<Scalar>&, const Streams<Scalar>&,     \
                                         Streams<Scalar>&, Streams<Scalar>&);
NFIELD_INSTANTIATE(float)
NFIELD_INSTANTIATE(double)
#undef NFIELD_INSTANTIATE

}  // namespace nfield::autodiff
