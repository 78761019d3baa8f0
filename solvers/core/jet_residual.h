// SPDX-License-Identifier: MIT
//
// A nonlinear residual written once, templated on the scalar, with its adjoint from
// forward-mode dual numbers (ceres::Jet).
//
// A per-point residual reads N stream values of its point (the value, gradient components,
// an operator such as the Laplacian, each of one channel) and per-point constants (the
// point's coordinates, a speed, a normal), and gives K components:
//
//   r(xₙ) = f(zₙ, dₙ),   zₙ ∈ R^N the stream values of point n,   dₙ its constants.
//
// JetResidual<Functor> implements Residual from one templated function f:
//
//   evaluate   f in double, point by point;
//   backward   f in ceres::Jet<double, N>, seeded with zₙ,ᵢ + εᵢ (the i-th unit dual), so
//              that r_c.v = ∂r_c/∂zₙ, and adjoint[zₙ,ᵢ] += Σ_c r̄ₙ,c ∂r_c/∂zₙ,ᵢ
//              = ∂(Σ r̄ ⊙ r)/∂out, the contract of Residual::backward.
//
// The cost is one pass of f per point in N + 1 doubles per number, against the network's
// streams of hundreds of neurons per point (docs/design.md has the step times). Nothing is
// vectorized across points: f is a few dozen operations.
//
// The functor:
//
//   struct MyResidual {
//     static constexpr int kReads = 1 + 2;     // N: fixed at compile time, as Jet<double, N>
//     static constexpr int kComponents = 1;    // K
//     struct PointData { double slowness; };   // what f needs besides the streams
//     std::array<StreamRead, kReads> reads(const StreamLayout& layout) const;  // which streams
//     PointData point(Eigen::Index index) const;  // index: of the point set, first + row
//     template <typename T>
//     void operator()(const T* z, const PointData& data, T* r) const;  // z[kReads] → r[K]
//   };
//
// Layout: Streams::data is (count · points) × width and stream s of point n is row
// s · points + n; StreamRead {stream, channel} names the entry (row s · points + n, column
// channel) that z[i] is. A residual over several channels lists each channel's streams.
//
// Pitfalls, where f in Jet is not the derivative one wants:
//   - sqrt(x) at x = 0 has derivative v/(2·0): inf or NaN (0 · inf), which poisons the whole
//     adjoint of the point. |g| = sqrt(g·g) at g = 0, or sign(x)√|x| at 0: take the value
//     as a constant there (norm_or_flat, abs_or_flat below), i.e. the subgradient 0 the
//     hand-written adjoints took.
//   - abs(x) in Ceres has derivative copysign(1, x) at ±0, not 0; min/max/comparisons act on
//     the value only (x < y compares x.a < y.a), so min(0, x) written as x < 0 ? x : T(0)
//     differentiates as the branch taken, with the derivative 0 at x = 0.
//   - N is a template argument of Jet: a residual whose reads depend on the space dimension
//     is a template over it, instantiated for each dimension the problem allows; reads that a
//     form does not use (the value in an unfactored eikonal) cost one dual slot, nothing else.
//   - Branch on values with scalar_of(x), never on a Jet's derivative part; constants enter as
//     T(c) (zero derivative).
//   - f must take the same branch in double and in Jet at the same point: it does whenever it
//     branches on scalar_of(·) only.
#pragma once

#include <ceres/jet.h>

#include <array>
#include <cmath>
#include <utility>

#include "solvers/core/residual.h"

namespace nfield::solvers {

// One stream value a point reads: stream `stream` (StreamLayout index), channel `channel`.
struct StreamRead {
  int stream = 0;
  int channel = 0;
};

// The value part of a double or a Jet: for branching and guards.
inline double scalar_of(double x) { return x; }
template <typename T, int N>
double scalar_of(const ceres::Jet<T, N>& x) {
  return x.a;
}

// |v| of v[0..n), with derivative v/|v|, and a constant (derivative 0) where |v| ≤ floor:
// sqrt's derivative at 0 is not finite. The value is the same on both sides.
template <typename T>
T norm_or_flat(const T* v, int n, double floor = 1e-12) {
  T squares = v[0] * v[0];
  for (int i = 1; i < n; ++i) squares += v[i] * v[i];
  const double norm = std::sqrt(scalar_of(squares));
  if (norm > floor) {
    using std::sqrt;
    return sqrt(squares);
  }
  return T(norm);
}

// |x| with derivative sign(x), 0 at x = 0 (Ceres' abs gives ±1 there).
template <typename T>
T abs_or_flat(const T& x) {
  const double value = scalar_of(x);
  return value > 0 ? x : value < 0 ? T(-x) : T(0.0);
}

// min(0, x): the derivative of the branch taken, 0 at x = 0.
template <typename T>
T min_zero(const T& x) {
  return scalar_of(x) < 0 ? x : T(0.0);
}

// Residual from a functor templated on the scalar (see the top of this file).
template <class Functor>
class JetResidual final : public Residual {
 public:
  static constexpr int kReads = Functor::kReads;
  static constexpr int kComponents = Functor::kComponents;
  static_assert(kReads > 0 && kComponents > 0);

  explicit JetResidual(Functor functor) : functor_(std::move(functor)) {}

  const Functor& functor() const { return functor_; }
  int components() const override { return kComponents; }

  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override {
    const std::array<StreamRead, kReads> reads = functor_.reads(layout);
    const Eigen::Index n = out.points;
    r.resize(n, kComponents);
    double z[kReads], y[kComponents];
    for (Eigen::Index p = 0; p < n; ++p) {
      for (int i = 0; i < kReads; ++i) z[i] = out.data(reads[i].stream * n + p, reads[i].channel);
      functor_(z, functor_.point(first + p), y);
      for (int c = 0; c < kComponents; ++c) r(p, c) = y[c];
    }
  }

  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override {
    using Jet = ceres::Jet<double, kReads>;
    const std::array<StreamRead, kReads> reads = functor_.reads(layout);
    const Eigen::Index n = out.points;
    Jet z[kReads], y[kComponents];
    for (Eigen::Index p = 0; p < n; ++p) {
      for (int i = 0; i < kReads; ++i)
        z[i] = Jet(out.data(reads[i].stream * n + p, reads[i].channel), i);
      functor_(z, functor_.point(first + p), y);
      for (int i = 0; i < kReads; ++i) {
        double sum = 0;
        for (int c = 0; c < kComponents; ++c) sum += r_bar(p, c) * y[c].v[i];
        adjoint.data(reads[i].stream * n + p, reads[i].channel) += sum;
      }
    }
  }

 private:
  Functor functor_;
};

template <class Functor>
std::unique_ptr<Residual> make_jet_residual(Functor functor) {
  return std::make_unique<JetResidual<Functor>>(std::move(functor));
}

}  // namespace nfield::solvers
