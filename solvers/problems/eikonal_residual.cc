// SPDX-License-Identifier: MIT
//
// The eikonal residuals (eikonal_residual.h) as functors of JetResidual: each is written
// once, templated on the scalar, and its adjoint comes from Jets. They read, per point,
//   z[0] = u or τ (value),  z[1 + a] = ∂/∂x_a (tangent a),  z[1 + D] = Δ (operator 0),
// the last only for the viscous eikonal term. D (2 or 3) is a template argument: the Jet's
// size is fixed at compile time.
#include "solvers/problems/eikonal_residual.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "solvers/core/jet_residual.h"

namespace nfield::solvers {
namespace {

// Per-point constants: T₀ and ∇T₀ of the factored form (∇T₀ = 0 at x₀ itself, where it is
// undefined), and the slowness (in per_point[0]) or the normal.
template <int D>
struct EikonalPoint {
  double t0 = 0;
  double distance = 0;  // |x − x₀|
  double grad_t0[D] = {};
  double per_point[D] = {};
};

template <int D>
class EikonalBase {
 public:
  using PointData = EikonalPoint<D>;

  EikonalBase(Eigen::MatrixXd points, Eigen::MatrixXd per_point, EikonalSetup setup)
      : points_(std::move(points)), per_point_(std::move(per_point)), setup_(std::move(setup)) {}

  PointData point(Eigen::Index index) const {
    PointData data;
    for (Eigen::Index a = 0; a < per_point_.cols() && a < D; ++a)
      data.per_point[a] = per_point_(index, a);
    if (!setup_.factored) return data;
    double e[D], squares = 0;
    for (int a = 0; a < D; ++a) {
      e[a] = points_(index, a) - setup_.x0(a);
      squares += e[a] * e[a];
    }
    data.distance = std::sqrt(squares);
    data.t0 = data.distance / setup_.v0;
    if (data.distance > 0)
      for (int a = 0; a < D; ++a) data.grad_t0[a] = e[a] / (data.distance * setup_.v0);
    return data;
  }

 protected:
  // ∇u: the tangents (plain), or (1 + τ) ∇T₀ + T₀ ∇τ (factored).
  template <typename T>
  void gradient(const T* z, const PointData& data, T* g) const {
    if (!setup_.factored) {
      for (int a = 0; a < D; ++a) g[a] = z[1 + a];
      return;
    }
    const T tau = T(1.0) + z[0];
    for (int a = 0; a < D; ++a) g[a] = tau * data.grad_t0[a] + data.t0 * z[1 + a];
  }

  // ∇u · n with the point's normal n (its per-point constants).
  template <typename T>
  static T normal_component(const T* g, const PointData& data) {
    T s = data.per_point[0] * g[0];
    for (int a = 1; a < D; ++a) s += data.per_point[a] * g[a];
    return s;
  }

  // u: the value (plain) or T₀ (1 + τ) (factored).
  template <typename T>
  T value(const T* z, const PointData& data) const {
    return setup_.factored ? T(data.t0 * (T(1.0) + z[0])) : z[0];
  }

  template <int N>
  static std::array<StreamRead, N> value_and_gradient(const StreamLayout& layout) {
    std::array<StreamRead, N> reads{};
    reads[0] = {StreamLayout::value(), 0};
    for (int a = 0; a < D; ++a) reads[1 + a] = {layout.tangent(a), 0};
    return reads;
  }

  Eigen::MatrixXd points_;
  Eigen::MatrixXd per_point_;
  EikonalSetup setup_;
};

// r = |∇u| − s − ε (viscous term); kViscous: the Laplacian stream is read (ε > 0).
template <int D, bool kViscous>
class EikonalPde : public EikonalBase<D> {
 public:
  using Base = EikonalBase<D>;
  using typename Base::PointData;
  static constexpr int kReads = 1 + D + (kViscous ? 1 : 0);
  static constexpr int kComponents = 1;
  using Base::Base;

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    auto reads = Base::template value_and_gradient<kReads>(layout);
    if constexpr (kViscous) reads[1 + D] = {layout.op(0), 0};
    return reads;
  }

  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    T g[D];
    this->gradient(z, data, g);
    // |∇u| is not differentiable at 0: subgradient 0 there.
    r[0] = norm_or_flat(g, D) - data.per_point[0];
    if constexpr (kViscous) r[0] -= this->setup_.viscosity * viscous_laplacian(z, data);
  }

 private:
  // Plain: Δu, or min(0, Δu) (concave). Factored, Δu = (1 + τ) ΔT₀ + 2 ∇T₀·∇τ + T₀ Δτ: the
  // `laplacian` form leaves out the curvature ΔT₀ = (d − 1)/(v₀ |x − x₀|) of the analytic
  // factor, the concave form keeps it (near x₀ it makes Δu > 0, which the form drops). See
  // the header of eikonal.cc.
  template <typename T>
  T viscous_laplacian(const T* z, const PointData& data) const {
    const EikonalSetup& setup = this->setup_;
    const T& lap = z[1 + D];
    if (!setup.factored) return setup.concave ? min_zero(lap) : lap;
    if (!(data.distance > 0)) return T(0.0);
    T grad_dot = T(0.0);
    for (int a = 0; a < D; ++a) grad_dot += data.grad_t0[a] * z[1 + a];
    if (!setup.concave) return T(2.0) * grad_dot + data.t0 * lap;
    const T factor_curvature = (T(1.0) + z[0]) * double(D - 1) / (data.distance * setup.v0);
    return min_zero(T(T(2.0) * grad_dot + data.t0 * lap + factor_curvature));
  }
};

// r = [min(0, ∇u·n), min(0, u)/L].
template <int D>
class EikonalOutflow : public EikonalBase<D> {
 public:
  using Base = EikonalBase<D>;
  using typename Base::PointData;
  static constexpr int kReads = 1 + D;
  static constexpr int kComponents = 2;
  using Base::Base;

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return Base::template value_and_gradient<kReads>(layout);
  }

  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    T g[D];
    this->gradient(z, data, g);
    r[0] = min_zero(Base::normal_component(g, data));
    r[1] = min_zero(this->value(z, data)) / this->setup_.length;
  }
};

// r = max(0, −∇u·n) (1/v_far − |∇u − (∇u·n) n|).
template <int D>
class EikonalInterface : public EikonalBase<D> {
 public:
  using Base = EikonalBase<D>;
  using typename Base::PointData;
  static constexpr int kReads = 1 + D;
  static constexpr int kComponents = 1;
  using Base::Base;

  std::array<StreamRead, kReads> reads(const StreamLayout& layout) const {
    return Base::template value_and_gradient<kReads>(layout);
  }

  template <typename T>
  void operator()(const T* z, const PointData& data, T* r) const {
    T g[D];
    this->gradient(z, data, g);
    const double* normal = data.per_point;
    const T s = Base::normal_component(g, data);
    if (!(scalar_of(s) < 0)) {
      r[0] = T(0.0);
      return;
    }
    T tangential[D];
    for (int a = 0; a < D; ++a) tangential[a] = g[a] - s * normal[a];
    // |∇_t u| is not differentiable at 0: subgradient 0 there.
    r[0] = -s * (this->setup_.far_slowness - norm_or_flat(tangential, D));
  }
};

// r = the value (u or τ) at x₀.
class EikonalSource {
 public:
  struct PointData {};
  static constexpr int kReads = 1;
  static constexpr int kComponents = 1;

  std::array<StreamRead, kReads> reads(const StreamLayout&) const {
    return {StreamRead{StreamLayout::value(), 0}};
  }
  PointData point(Eigen::Index) const { return {}; }
  template <typename T>
  void operator()(const T* z, const PointData&, T* r) const {
    r[0] = z[0];
  }
};

template <int D>
std::unique_ptr<Residual> make_of_dimension(EikonalKind kind, Eigen::MatrixXd points,
                                            Eigen::MatrixXd per_point, EikonalSetup setup) {
  switch (kind) {
    case EikonalKind::kEikonal:
      if (setup.viscosity > 0)
        return make_jet_residual(
            EikonalPde<D, true>(std::move(points), std::move(per_point), std::move(setup)));
      return make_jet_residual(
          EikonalPde<D, false>(std::move(points), std::move(per_point), std::move(setup)));
    case EikonalKind::kOutflow:
      return make_jet_residual(
          EikonalOutflow<D>(std::move(points), std::move(per_point), std::move(setup)));
    case EikonalKind::kInterface:
      return make_jet_residual(
          EikonalInterface<D>(std::move(points), std::move(per_point), std::move(setup)));
    case EikonalKind::kSource:
      return make_jet_residual(EikonalSource{});
  }
  throw std::logic_error("make_eikonal_residual: unknown kind");
}

}  // namespace

std::unique_ptr<Residual> make_eikonal_residual(EikonalKind kind, Eigen::MatrixXd points,
                                                Eigen::MatrixXd per_point, EikonalSetup setup) {
  switch (points.cols()) {
    case 2:
      return make_of_dimension<2>(kind, std::move(points), std::move(per_point), std::move(setup));
    case 3:
      return make_of_dimension<3>(kind, std::move(points), std::move(per_point), std::move(setup));
    default:
      throw std::invalid_argument("make_eikonal_residual: expected 2 or 3 space dimensions, got " +
                                  std::to_string(points.cols()));
  }
}

}  // namespace nfield::solvers
