// SPDX-License-Identifier: MIT
//
// Fields with closed-form streams for tests of what reads streams (pde symbols, functionals):
// sums of exponentials u_c(x) = Σ_m b_mc exp(c_m · x), every derivative along any direction
// closed-form, and the streams autodiff/streams.h defines for them.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "autodiff/streams.h"

namespace nfield::testutil {

// u_c(x) = Σ_m b_mc exp(c_m · x): every derivative is closed-form, along any direction.
struct Exponentials {
  std::vector<Eigen::VectorXd> rates;  // c_m
  Eigen::MatrixXd weights;             // b: terms × channels

  // Σ_m b_mc exp(c_m·x) f(c_m).
  template <class F>
  double sum(int channel, const Eigen::VectorXd& x, F f) const {
    double s = 0;
    for (std::size_t m = 0; m < rates.size(); ++m)
      s += weights(static_cast<Eigen::Index>(m), channel) * std::exp(rates[m].dot(x)) * f(rates[m]);
    return s;
  }
};

inline Exponentials random_exponentials(int input_dim, int channels, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Exponentials e;
  for (int m = 0; m < 3; ++m) e.rates.push_back(Eigen::VectorXd::NullaryExpr(input_dim, [&] { return u(rng); }));
  e.weights = Eigen::MatrixXd::NullaryExpr(3, channels, [&] { return u(rng); });
  return e;
}

// The streams a field equal to `f` gives for `layout` (autodiff/streams.h): values,
// tangents c·vᵢ, operators Σ Cᵢⱼ (c·vᵢ)(c·vⱼ), Taylor coefficients (c·w)ᵏ/k!, times the terms.
inline autodiff::Streams<double> exponential_streams(const autodiff::StreamLayout& layout, const Exponentials& f,
                                              const Eigen::MatrixXd& x, int channels) {
  const autodiff::StreamSpec& spec = layout.spec();
  autodiff::Streams<double> s;
  s.resize(x.rows(), layout.count(), channels);
  for (Eigen::Index n = 0; n < x.rows(); ++n)
    for (int c = 0; c < channels; ++c) {
      const Eigen::VectorXd p = x.row(n).transpose();
      s.stream(0)(n, c) = f.sum(c, p, [](const Eigen::VectorXd&) { return 1.0; });
      for (int i = 0; i < layout.tangents(); ++i)
        s.stream(layout.tangent(i))(n, c) = f.sum(c, p, [&](const Eigen::VectorXd& r) { return r.dot(spec.tangents.col(i)); });
      for (int q = 0; q < layout.operators(); ++q)
        s.stream(layout.op(q))(n, c) = f.sum(c, p, [&](const Eigen::VectorXd& r) {
          const Eigen::VectorXd g = spec.tangents.transpose() * r;
          return g.dot(spec.operators[static_cast<std::size_t>(q)] * g);
        });
      for (int d = 0; d < layout.taylor_dirs(); ++d)
        for (int k = 1; k <= layout.taylor_order(); ++k)
          s.stream(layout.taylor(d, k))(n, c) = f.sum(c, p, [&](const Eigen::VectorXd& r) {
            return std::pow(r.dot(spec.taylor_directions.col(d)), k) / std::tgamma(k + 1.0);
          });
    }
  return s;
}

}  // namespace nfield::testutil
