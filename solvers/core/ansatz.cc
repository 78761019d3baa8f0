// SPDX-License-Identifier: MIT
#include "solvers/core/ansatz.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "io/text.h"

namespace nfield::solvers {

Jet Jet::constant(Eigen::Index n, int d, double c) {
  Jet j;
  j.value = Eigen::VectorXd::Constant(n, c);
  j.gradient = Eigen::MatrixXd::Zero(n, d);
  j.hessian.assign(static_cast<size_t>(d) * d, Eigen::VectorXd::Zero(n));
  return j;
}

Jet Jet::operator*(const Jet& g) const {
  const Jet& f = *this;
  const Eigen::Index d = f.gradient.cols();
  Jet out;
  out.value = f.value.cwiseProduct(g.value);
  out.gradient = f.gradient.array().colwise() * g.value.array() +
                 g.gradient.array().colwise() * f.value.array();
  if (!f.hessian.empty() && !g.hessian.empty()) {
    out.hessian.resize(f.hessian.size());
    for (Eigen::Index a = 0; a < d; ++a)
      for (Eigen::Index b = 0; b < d; ++b) {
        const size_t k = static_cast<size_t>(a * d + b);
        out.hessian[k] = f.hessian[k].cwiseProduct(g.value) + f.value.cwiseProduct(g.hessian[k]) +
                         f.gradient.col(a).cwiseProduct(g.gradient.col(b)) +
                         f.gradient.col(b).cwiseProduct(g.gradient.col(a));
      }
  }
  return out;
}

Jet Jet::operator+(const Jet& g) const {
  Jet out;
  out.value = value + g.value;
  out.gradient = gradient + g.gradient;
  if (!hessian.empty() && !g.hessian.empty()) {
    out.hessian.resize(hessian.size());
    for (size_t k = 0; k < hessian.size(); ++k) out.hessian[k] = hessian[k] + g.hessian[k];
  }
  return out;
}

Ansatz::Ansatz(const Domain& domain, int channels, std::optional<Dirichlet> dirichlet,
               std::optional<Initial> initial)
    : domain_(domain), channels_(channels), dirichlet_(std::move(dirichlet)),
      initial_(std::move(initial)) {
  if (initial_ && !domain_.has_time())
    throw std::invalid_argument("Ansatz: hard initial conditions need a time interval");
}

Eigen::VectorXd Ansatz::fade_weights(const Eigen::MatrixXd& x) const {
  const geometry::Geometry& g = *domain_.geometry();
  Eigen::VectorXd w(x.rows());
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    geometry::Vec3 y = geometry::Vec3::Zero();
    for (int a = 0; a < g.dim(); ++a) y(a) = x(r, a);
    w(r) = std::exp(-g.distance(y, *dirichlet_->parts).v / dirichlet_->fade);
  }
  return w;
}

Jet Ansatz::expression_jet(const io::Expression& e, const Eigen::MatrixXd& x,
                           const std::vector<bool>& hessian, bool frozen_time, bool fade) const {
  const Eigen::Index n = x.rows();
  const int d = domain_.input_dim();
  const bool second = !hessian.empty();
  auto needed = [&](int a, int b) {
    return hessian[static_cast<size_t>(a * d + b)] || hessian[static_cast<size_t>(b * d + a)];
  };
  Eigen::MatrixXd base = x;
  if (frozen_time) base.col(domain_.time_column()).setConstant(domain_.time().first);
  Jet jet = Jet::constant(n, d, 0.0);
  if (!second) jet.hessian.clear();
  const auto evaluate = [&](const Eigen::MatrixXd& points) {
    return fade ? Eigen::VectorXd(e.evaluate(points).cwiseProduct(fade_weights(points))) : e.evaluate(points);
  };
  jet.value = evaluate(base);
  if (e.is_constant() && !fade) return jet;

  const std::vector<std::string> names = domain_.input_names();
  const Eigen::VectorXd extent = domain_.input_upper() - domain_.input_lower();
  std::vector<int> axes;
  for (int a = 0; a < d; ++a)
    if ((e.uses(names[a]) || (fade && a < domain_.space_dim())) && !(frozen_time && a == domain_.time_column()))
      axes.push_back(a);
  const Eigen::VectorXd h = 1e-3 * extent;
  // Offsets −2, −1, 1, 2 and the 4th-order first-derivative weights (× 1/12h).
  static constexpr int kOffsets[4] = {-2, -1, 1, 2};
  static constexpr double kFirst[4] = {1.0 / 12, -8.0 / 12, 8.0 / 12, -1.0 / 12};
  static constexpr double kSecond[4] = {-1.0 / 12, 16.0 / 12, 16.0 / 12, -1.0 / 12};
  Eigen::MatrixXd shifted(n, base.cols());
  for (int a : axes) {
    Eigen::VectorXd first = Eigen::VectorXd::Zero(n), diag = -2.5 * jet.value;  // −30/12 f0
    for (int k = 0; k < 4; ++k) {
      shifted = base;
      shifted.col(a).array() += kOffsets[k] * h(a);
      const Eigen::VectorXd f = evaluate(shifted);
      first += kFirst[k] * f;
      diag += kSecond[k] * f;
    }
    jet.gradient.col(a) = first / h(a);
    if (second && needed(a, a)) jet.hessian[static_cast<size_t>(a * d + a)] = diag / (h(a) * h(a));
  }
  if (second)
    for (size_t p = 0; p < axes.size(); ++p)
      for (size_t q = p + 1; q < axes.size(); ++q) {
        const int a = axes[p], b = axes[q];
        if (!needed(a, b)) continue;  // 16 evaluations no operator of the layout reads
        Eigen::VectorXd mixed = Eigen::VectorXd::Zero(n);
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) {
            shifted = base;
            shifted.col(a).array() += kOffsets[i] * h(a);
            shifted.col(b).array() += kOffsets[j] * h(b);
            mixed += (kFirst[i] * kFirst[j]) * evaluate(shifted);
          }
        mixed /= h(a) * h(b);
        jet.hessian[static_cast<size_t>(a * d + b)] = mixed;
        jet.hessian[static_cast<size_t>(b * d + a)] = mixed;
      }
  return jet;
}

namespace {

// The linear function s·(x_a − c) as a jet.
Jet linear_jet(const Eigen::MatrixXd& x, int d, int axis, double c, double s, bool second) {
  Jet j = Jet::constant(x.rows(), d, 0.0);
  if (!second) j.hessian.clear();
  j.value = s * (x.col(axis).array() - c).matrix();
  j.gradient.col(axis).setConstant(s);
  return j;
}

}  // namespace

std::vector<Jet> Ansatz::base_jets(const Eigen::MatrixXd& x, bool second) const {
  const size_t d = static_cast<size_t>(domain_.input_dim());
  return base_jets(x, std::vector<bool>(second ? d * d : 0, true));
}

std::vector<Jet> Ansatz::base_jets(const Eigen::MatrixXd& x, const std::vector<bool>& hessian) const {
  std::vector<Jet> out;
  const int d = domain_.input_dim();
  const bool second = !hessian.empty();
  for (int c = 0; c < channels_; ++c) {
    if (initial_) {
      Jet jet = expression_jet(initial_->value[c], x, hessian, true);
      if (initial_->velocity) {
        const Jet tau = linear_jet(x, d, domain_.time_column(), domain_.time().first, 1.0, second);
        jet = jet + tau * expression_jet((*initial_->velocity)[c], x, hessian, true);
      }
      out.push_back(std::move(jet));
    } else if (dirichlet_) {
      out.push_back(expression_jet(dirichlet_->values[c], x, hessian, false, dirichlet_->fade > 0));
    } else {
      Jet zero = Jet::constant(x.rows(), d, 0.0);
      if (!second) zero.hessian.clear();
      out.push_back(std::move(zero));
    }
  }
  return out;
}

namespace {
// φ of the geometry's parts at the rows of x (space columns first; 0 derivatives in t).
Jet distance_jet(const geometry::Geometry& g, const geometry::Selection& parts, double saturate,
                 const Eigen::MatrixXd& x, int d, bool second) {
  Jet jet = Jet::constant(x.rows(), d, 0.0);
  if (!second) jet.hessian.clear();
  const int space = g.dim();
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    geometry::Vec3 p = geometry::Vec3::Zero();
    for (int a = 0; a < space; ++a) p(a) = x(r, a);
    geometry::Scalar2 phi = g.distance(p, parts);
    if (saturate > 0) {  // s·tanh(φ/s): derivatives sech² and −2 tanh sech² / s
      const double th = std::tanh(phi.v / saturate), sech2 = 1 - th * th;
      phi = phi.chain(saturate * th, sech2, -2 * th * sech2 / saturate);
    }
    jet.value(r) = phi.v;
    for (int a = 0; a < space; ++a) {
      jet.gradient(r, a) = phi.g(a);
      if (second)
        for (int b = 0; b < space; ++b) jet.hessian[static_cast<size_t>(a * d + b)](r) = phi.h(a, b);
    }
  }
  return jet;
}
}  // namespace

Jet Ansatz::factor_jet(const Eigen::MatrixXd& x, bool second) const {
  const int d = domain_.input_dim();
  Jet jet = Jet::constant(x.rows(), d, 1.0);
  if (!second) jet.hessian.clear();
  if (dirichlet_ && dirichlet_->parts) jet = jet * distance_jet(*domain_.geometry(), *dirichlet_->parts, dirichlet_->saturate, x, d, second);
  if (dirichlet_)
    for (const Face& f : dirichlet_->faces) {
      const double lo = domain_.lower()[f.axis], hi = domain_.upper()[f.axis];
      jet = jet * (f.upper ? linear_jet(x, d, f.axis, hi, -1.0 / (hi - lo), second)
                           : linear_jet(x, d, f.axis, lo, 1.0 / (hi - lo), second));
    }
  if (initial_) {
    const auto [t0, t1] = domain_.time();
    const int t = domain_.time_column();
    if (initial_->time_scale > 0) {
      // ψ = tanh(τ/s): ψ' = (1 − ψ²)/s, ψ'' = −2ψ(1 − ψ²)/s².
      const double s = initial_->time_scale;
      Jet psi = Jet::constant(x.rows(), d, 0.0);
      if (!second) psi.hessian.clear();
      psi.value = ((x.col(t).array() - t0) / s).tanh().matrix();
      const Eigen::ArrayXd q = psi.value.array(), one_minus = 1.0 - q.square();
      psi.gradient.col(t) = (one_minus / s).matrix();
      if (second) psi.hessian[static_cast<size_t>(t * d + t)] = (-2.0 * q * one_minus / (s * s)).matrix();
      jet = jet * psi;
      if (initial_->velocity) jet = jet * psi;
    } else {
      const Jet tau = linear_jet(x, d, t, t0, 1.0 / (t1 - t0), second);
      jet = jet * tau;
      if (initial_->velocity) jet = jet * tau;
    }
  }
  return jet;
}

namespace {

void fill_streams(const StreamLayout& layout, const std::vector<Eigen::MatrixXd>& kernels,
                  const Jet& jet, int channel, Streams<double>& s) {
  const Eigen::MatrixXd& v = layout.spec().tangents;
  const Eigen::Index d = jet.gradient.cols();
  s.stream(layout.value()).col(channel) = jet.value;
  for (int i = 0; i < layout.tangents(); ++i)
    s.stream(layout.tangent(i)).col(channel) = jet.gradient * v.col(i);
  for (int q = 0; q < layout.operators(); ++q) {
    auto col = s.stream(layout.op(q)).col(channel);
    col.setZero();
    for (Eigen::Index a = 0; a < d; ++a)
      for (Eigen::Index b = 0; b < d; ++b)
        if (kernels[q](a, b) != 0) col += kernels[q](a, b) * jet.hessian[static_cast<size_t>(a * d + b)];
  }
}

}  // namespace

AnsatzStreams Ansatz::streams(const StreamLayout& layout, const Eigen::MatrixXd& x) const {
  if (layout.taylor_dirs() > 0)
    throw std::invalid_argument(
        "hard conditions (enforce: hard) do not support Taylor streams (derivatives of order > "
        "2); use enforce: soft for this problem");
  if (layout.input_dim() != domain_.input_dim() || x.cols() != domain_.input_dim())
    throw std::invalid_argument("Ansatz: points have " + std::to_string(x.cols()) +
                                " columns, the domain " + std::to_string(domain_.input_dim()));
  const bool second = layout.operators() > 0;
  const Eigen::MatrixXd& v = layout.spec().tangents;
  std::vector<Eigen::MatrixXd> kernels;  // V C Vᵀ: the operator in input coordinates
  for (int q = 0; q < layout.operators(); ++q)
    kernels.push_back(v * layout.spec().operators[q] * v.transpose());
  // The Hessian entries fill_streams reads (none without operators).
  const int d = domain_.input_dim();
  std::vector<bool> hessian(second ? static_cast<size_t>(d) * d : 0, false);
  for (const Eigen::MatrixXd& k : kernels)
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b)
        if (k(a, b) != 0) hessian[static_cast<size_t>(a * d + b)] = true;
  AnsatzStreams s;
  const Eigen::Index n = x.rows();
  s.base.resize(n, layout.count(), channels_);
  s.factor.resize(n, layout.count(), 1);
  const std::vector<Jet> base = base_jets(x, hessian);
  for (int c = 0; c < channels_; ++c) fill_streams(layout, kernels, base[c], c, s.base);
  fill_streams(layout, kernels, factor_jet(x, second), 0, s.factor);
  s.terms = bilinear_terms(layout);
  return s;
}

namespace {

// ansatz_product_rule on points [begin, end) of n, `Lanes` at a time: the rule on
// Eigen::Array<double, Lanes, 1> packs (Lanes = 1: plain doubles). Stream k of point p is
// row k · points + p, so a pack of consecutive points is a contiguous segment.
template <int Lanes>
void apply_packs(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
                 const Streams<double>& n, Streams<double>& u, Eigen::Index begin,
                 Eigen::Index end) {
  using Pack = std::conditional_t<Lanes == 1, double, Eigen::Array<double, Lanes, 1>>;
  auto load = [](const auto& column, Eigen::Index row) -> Pack {
    if constexpr (Lanes == 1) return column(row);
    else return column.template segment<Lanes>(row).array();
  };
  if (end - begin < Lanes) return;
  const Eigen::Index points = n.points, rows = s.factor.points;
  const int count = layout.count();
  // Scratch kept per thread: training calls this once a block of 128 points, where four
  // allocations would cost as much as the arithmetic.
  static thread_local std::vector<Pack> scratch;
  scratch.resize(4 * static_cast<size_t>(count));
  Pack *a = scratch.data(), *d = a + count, *np = d + count, *up = np + count;
  for (Eigen::Index p = begin; p + Lanes <= end; p += Lanes) {
    for (int k = 0; k < count; ++k) d[k] = load(s.factor.data.col(0), k * rows + first + p);
    for (Eigen::Index c = 0; c < n.width(); ++c) {
      for (int k = 0; k < count; ++k) {
        a[k] = load(s.base.data.col(c), k * rows + first + p);
        np[k] = load(n.data.col(c), k * points + p);
      }
      ansatz_product_rule(layout, a, d, np, up);
      for (int k = 0; k < count; ++k) {
        if constexpr (Lanes == 1) u.data(k * points + p, c) = up[k];
        else u.data.col(c).template segment<Lanes>(k * points + p) = up[k].matrix();
      }
    }
  }
}

}  // namespace

void Ansatz::apply(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
                   const Streams<double>& n, Streams<double>& u) const {
  constexpr int kLanes = 16;  // two AVX-512 registers, four AVX2 ones; divides the block of 128
  u.resize(n.points, n.count, n.width());
  const Eigen::Index packed = n.points / kLanes * kLanes;
  apply_packs<kLanes>(layout, s, first, n, u, 0, packed);
  apply_packs<1>(layout, s, first, n, u, packed, n.points);
}

std::vector<AnsatzTerm> Ansatz::bilinear_terms(const StreamLayout& layout) {
  constexpr int kChunk = 8;  // duals per pass: S ≤ 8 in one (see the header)
  using Dual = ceres::Jet<double, kChunk>;
  const int count = layout.count();
  // A enters the rule as a constant: zeros give the same derivatives.
  const std::vector<double> a(count, 0.0);
  std::vector<double> d(count, 0.0);
  std::vector<Dual> n(count), u(count);
  std::vector<AnsatzTerm> terms;
  for (int k = 0; k < count; ++k) {
    d.assign(count, 0.0);
    d[k] = 1;  // D = e_k: u − A = Σ_j M_ijk N_j
    for (int start = 0; start < count; start += kChunk) {
      // u − A is linear in N: the value part (0) does not matter, the duals pick the chunk.
      for (int j = 0; j < count; ++j)
        n[j] = j >= start && j < start + kChunk ? Dual(0.0, j - start) : Dual(0.0);
      ansatz_product_rule(layout, a.data(), d.data(), n.data(), u.data());
      for (int i = 0; i < count; ++i)
        for (int j = start; j < std::min(count, start + kChunk); ++j)
          if (u[i].v[j - start] != 0) terms.push_back({i, j, k, u[i].v[j - start]});
    }
  }
  return terms;
}

void Ansatz::adjoint(const StreamLayout& layout, const AnsatzStreams& s, Eigen::Index first,
                     const Streams<double>& u_bar, Streams<double>& n_bar) const {
  const Eigen::Index p = u_bar.points;
  std::vector<AnsatzTerm> computed;  // only for streams built without Ansatz::streams
  if (s.terms.empty()) computed = bilinear_terms(layout);
  const std::vector<AnsatzTerm>& terms = s.terms.empty() ? computed : s.terms;
  // N̄_n += M D_d ⊙ ū_u, for every channel at once.
  for (const AnsatzTerm& t : terms) {
    const auto d = s.factor.stream(t.d).col(0).segment(first, p).array();
    n_bar.stream(t.n).array() += t.coefficient * (u_bar.stream(t.u).array().colwise() * d);
  }
}

Eigen::MatrixXd Ansatz::values(const Eigen::MatrixXd& x, const Eigen::MatrixXd& network_values) const {
  const StreamLayout layout(autodiff::StreamSpec::values(domain_.input_dim()));
  const AnsatzStreams s = streams(layout, x);
  Streams<double> n, u;
  n.points = x.rows();
  n.count = 1;
  n.data = network_values;
  apply(layout, s, 0, n, u);
  return u.data;
}

AnsatzResidual::AnsatzResidual(std::shared_ptr<const Ansatz> ansatz, std::unique_ptr<Residual> inner,
                               const StreamLayout& layout, const Eigen::MatrixXd& points)
    : ansatz_(std::move(ansatz)), inner_(std::move(inner)), streams_(ansatz_->streams(layout, points)) {}

void AnsatzResidual::evaluate(Eigen::Index first, const StreamLayout& layout,
                              const Streams<double>& out, Eigen::MatrixXd& r) const {
  Streams<double> u;
  ansatz_->apply(layout, streams_, first, out, u);
  inner_->evaluate(first, layout, u, r);
}

void AnsatzResidual::backward(Eigen::Index first, const StreamLayout& layout,
                              const Streams<double>& out, const Eigen::MatrixXd& r_bar,
                              Streams<double>& adjoint) const {
  Streams<double> u, u_bar;
  ansatz_->apply(layout, streams_, first, out, u);
  u_bar.points = u.points;
  u_bar.count = u.count;
  u_bar.data.setZero(u.data.rows(), u.data.cols());
  inner_->backward(first, layout, u, r_bar, u_bar);
  ansatz_->adjoint(layout, streams_, first, u_bar, adjoint);
}

std::vector<LossTerm> with_ansatz(std::vector<LossTerm> terms, std::shared_ptr<const Ansatz> ansatz) {
  if (!ansatz) return terms;
  for (LossTerm& term : terms) {
    if (term.spec.taylor_order > 0)
      throw std::invalid_argument("loss term '" + term.name +
                                  "' uses Taylor streams (derivatives of order > 2), which hard "
                                  "conditions (enforce: hard) do not support; use enforce: soft");
    auto inner = std::move(term.residual);
    term.residual = [ansatz, inner = std::move(inner), spec = term.spec](const TermPoints& points) {
      // Groups are fine (u = A + D N point by point; a periodic pair reads two such points);
      // per-point tangent directions are not: A and D's streams follow the spec's tangents.
      if (points.tangents.size() > 0)
        throw std::invalid_argument("hard conditions (enforce: hard) do not apply to loss terms with "
                                    "per-point tangents");
      return std::make_unique<AnsatzResidual>(ansatz, inner(points), StreamLayout(spec), points.x);
    };
  }
  return terms;
}

NetworkStreams with_ansatz(NetworkStreams network, std::shared_ptr<const Ansatz> ansatz) {
  if (!ansatz) return network;
  return [network = std::move(network), ansatz](const StreamLayout& layout, const Eigen::MatrixXd& x) {
    const Streams<double> n = network(layout, x);
    Streams<double> u;
    ansatz->apply(layout, ansatz->streams(layout, x), 0, n, u);
    return u;
  };
}

}  // namespace nfield::solvers
