// SPDX-License-Identifier: MIT
//
// Taylor coefficients (order 1–4) and operator streams of fields with known closed forms,
// to 1e-10 relative:
//   * one hidden unit, f = α σ(ω (a·x + b)) + β, σ = sine (mlp and SIREN), tanh, softplus,
//     whose derivatives are written out by hand here;
//   * an encoding followed by an identity network, f = Σᵣ cᵣ γᵣ(x) + const, γ the
//     positional or Fourier features;
//   * mixed partials by polarization: u_xxyy, u_xxy and Δ²u of f = Σᵤ αᵤ sin(aᵤ·x + bᵤ),
//     reconstructed from Taylor series along eᵢ and eᵢ ± eⱼ.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "autodiff/streams.h"
#include "fields/field.h"
#include "tests/testing/stream_checks.h"

namespace nfield::testutil {
namespace {

constexpr double kTolerance = 1e-10;

double factorial(int k) { return k <= 1 ? 1.0 : k * factorial(k - 1); }

// σ⁽ᵏ⁾(u), k = 0…4, written out by hand.
using Derivatives = std::function<double(double u, int k)>;

double sine_derivative(double u, int k) { return std::sin(u + k * std::numbers::pi / 2); }

double tanh_derivative(double u, int k) {
  const double t = std::tanh(u), s = 1 - t * t;
  switch (k) {
    case 0: return t;
    case 1: return s;
    case 2: return -2 * t * s;
    case 3: return s * (6 * t * t - 2);
    default: return 8 * t * s * (2 - 3 * t * t);
  }
}

double softplus_derivative(double u, int k) {
  const double s = 1 / (1 + std::exp(-u));
  switch (k) {
    case 0: return std::log1p(std::exp(u));
    case 1: return s;
    case 2: return s * (1 - s);
    case 3: return s * (1 - s) * (1 - 2 * s);
    default: return s * (1 - s) * (1 - 6 * s + 6 * s * s);
  }
}

struct OneUnit {
  std::string type, activation;
  double omega;
  Derivatives sigma;
};

// Compares a stream with its exact values, relative to the largest exact magnitude.
void expect_close(const Eigen::Ref<const Eigen::MatrixXd>& actual, const Eigen::MatrixXd& exact,
                  const std::string& check, const std::string& where, double scale = 0) {
  const double err = relative_error(actual, exact, scale);
  WorstErrors::get().record("closed form: " + check, err, where);
  EXPECT_LE(err, kTolerance) << check << ", " << where;
}

TEST(TaylorClosedForm, OneHiddenUnit) {
  const std::vector<OneUnit> units = {{"mlp", "sine", 1.0, sine_derivative},
                                      {"mlp", "sine", 3.0, sine_derivative},
                                      {"siren", "sine", 30.0, sine_derivative},
                                      {"mlp", "tanh", 1.0, tanh_derivative},
                                      {"mlp", "softplus", 1.0, softplus_derivative}};
  std::mt19937_64 rng(42);
  for (const OneUnit& unit : units)
    for (int d = 1; d <= 4; ++d) {
      fields::FieldOptions o;
      o.type = unit.type;
      o.activation = unit.activation;
      o.input_dim = d;
      o.output_dim = 1;
      o.hidden = {1};
      o.first_omega = unit.omega;  // SIREN: the only hidden layer is the first
      o.hidden_omega = unit.omega;
      fields::Field<double> field(o);
      // θ = [a (1 × d), b, α, β]
      const Eigen::VectorXd a = random_matrix(d, 1, rng);
      const double b = uniform(rng), alpha = uniform(rng, 0.5, 2), beta = uniform(rng);
      ASSERT_EQ(field.parameter_count(), d + 3);
      field.parameters() << a, b, alpha, beta;

      const Eigen::MatrixXd x = random_matrix(5, d, rng);
      const Eigen::MatrixXd w = random_matrix(d, 3, rng);
      StreamSpec spec = StreamSpec::laplacian(d);
      spec.set_taylor(w, 4);
      const StreamLayout layout(spec);
      Streams<double> out;
      field.evaluate(layout, x, out);

      const double omega = unit.omega;
      const Eigen::VectorXd u = omega * ((x * a).array() + b).matrix();
      const std::string where = unit.type + " " + unit.activation + " ω=" +
                                std::to_string(unit.omega) + " d=" + std::to_string(d);
      auto sigma = [&](int k) {
        Eigen::MatrixXd s(x.rows(), 1);
        for (Eigen::Index n = 0; n < x.rows(); ++n) s(n, 0) = unit.sigma(u[n], k);
        return s;
      };
      expect_close(out.stream(0), (alpha * sigma(0)).array() + beta, "value", where);
      for (int i = 0; i < d; ++i)
        expect_close(out.stream(layout.tangent(i)), alpha * omega * a[i] * sigma(1), "gradient",
                     where);
      expect_close(out.stream(layout.op(0)), alpha * omega * omega * a.squaredNorm() * sigma(2),
                   "laplacian", where);
      for (int p = 0; p < w.cols(); ++p) {
        const double slope = omega * a.dot(w.col(p));
        for (int k = 1; k <= 4; ++k)
          expect_close(out.stream(layout.taylor(p, k)),
                       alpha * std::pow(slope, k) / factorial(k) * sigma(k),
                       "taylor order " + std::to_string(k), where,
                       std::abs(alpha * std::pow(slope, k)) / factorial(k) * 1e-3);
      }
    }
}

// f = c_x·x + Σᵣ (sᵣ sin(Bᵣ·x) + cᵣ cos(Bᵣ·x)) + const after an identity network.
TEST(TaylorClosedForm, EncodingsThroughIdentityNetwork) {
  std::mt19937_64 rng(7);
  for (const char* type_name : {"positional", "fourier"})
    for (int d = 1; d <= 3; ++d) {
      const std::string type = type_name;
      fields::FieldOptions o;
      o.type = "mlp";
      o.activation = "identity";
      o.input_dim = d;
      o.hidden = {1};
      o.encoding = testutil::encoding_of(type, {.frequencies = 3, .features = 5, .scale = 0.7, .seed = 11});
      fields::Field<double> field(o);
      field.parameters() = random_matrix(field.parameter_count(), 1, rng);
      const Eigen::MatrixXd& bm = field.encoding_matrix();
      const Eigen::Index m = bm.rows();
      const bool include = type == "positional";
      const Eigen::Index width = (include ? d : 0) + 2 * m;
      // Effective linear coefficients of γ: c = W₂ W₁ (W₁ 1 × width, W₂ 1 × 1).
      const Eigen::VectorXd& theta = field.parameters();
      const Eigen::VectorXd c = theta[width + 1] * theta.head(width);

      const Eigen::MatrixXd x = random_matrix(4, d, rng);
      const Eigen::MatrixXd w = random_matrix(d, 2, rng);
      StreamSpec spec = StreamSpec::laplacian(d);
      spec.set_taylor(w, 4);
      const StreamLayout layout(spec);
      Streams<double> out;
      field.evaluate(layout, x, out);
      const std::string where = type + " d=" + std::to_string(d);

      const Eigen::MatrixXd phase = x * bm.transpose();  // N × m
      for (int p = 0; p < w.cols(); ++p) {
        const Eigen::VectorXd slope = bm * w.col(p);  // m
        for (int k = 1; k <= 4; ++k) {
          Eigen::MatrixXd exact = Eigen::MatrixXd::Zero(x.rows(), 1);
          double scale = 0;
          if (include && k == 1) exact.col(0).array() += c.head(d).dot(w.col(p));
          for (Eigen::Index r = 0; r < m; ++r) {
            const double sk = std::pow(slope[r], k) / factorial(k);
            const double cs = c[(include ? d : 0) + r], cc = c[(include ? d : 0) + m + r];
            for (Eigen::Index n = 0; n < x.rows(); ++n)
              exact(n, 0) += sk * (cs * std::sin(phase(n, r) + k * std::numbers::pi / 2) +
                                   cc * std::cos(phase(n, r) + k * std::numbers::pi / 2));
            scale += std::abs(sk) * (std::abs(cs) + std::abs(cc));
          }
          expect_close(out.stream(layout.taylor(p, k)), exact, "encoding taylor order " +
                       std::to_string(k), where, scale);
        }
      }
      // Laplacian: −Σᵣ |Bᵣ|² (sᵣ sin + cᵣ cos).
      Eigen::MatrixXd lap = Eigen::MatrixXd::Zero(x.rows(), 1);
      double scale = 0;
      for (Eigen::Index r = 0; r < m; ++r) {
        const double b2 = bm.row(r).squaredNorm();
        const double cs = c[(include ? d : 0) + r], cc = c[(include ? d : 0) + m + r];
        for (Eigen::Index n = 0; n < x.rows(); ++n)
          lap(n, 0) -= b2 * (cs * std::sin(phase(n, r)) + cc * std::cos(phase(n, r)));
        scale += b2 * (std::abs(cs) + std::abs(cc));
      }
      expect_close(out.stream(layout.op(0)), lap, "encoding laplacian", where, scale);
    }
}

// f = Σᵤ αᵤ sin(aᵤ·x + bᵤ) + β (mlp, sine with ω = 1, three hidden units). From Taylor
// series along eᵢ and eᵢ ± eⱼ (D^k = k! z_k):
//   D⁴(eᵢ + eⱼ) + D⁴(eᵢ − eⱼ) = 2 f_iiii + 12 f_iijj + 2 f_jjjj
//     ⇒ f_iijj = 2 (z₄(eᵢ+eⱼ) + z₄(eᵢ−eⱼ) − 2 z₄(eᵢ) − 2 z₄(eⱼ))
//   D³(eᵢ + eⱼ) − D³(eᵢ − eⱼ) = 6 f_iij + 2 f_jjj  ⇒  f_iij = z₃(eᵢ+eⱼ) − z₃(eᵢ−eⱼ) − 2 z₃(eⱼ)
//   Δ²f = Σᵢ f_iiii + 2 Σ_{i<j} f_iijj,  f_iiii = 24 z₄(eᵢ),  f_iii = 6 z₃(eᵢ).
TEST(TaylorClosedForm, MixedPartialsByPolarization) {
  std::mt19937_64 rng(99);
  for (int d = 2; d <= 4; ++d) {
    fields::FieldOptions o;
    o.type = "mlp";
    o.activation = "sine";
    o.hidden_omega = 1.0;
    o.input_dim = d;
    o.hidden = {3};
    fields::Field<double> field(o);
    field.parameters() = 1.5 * random_matrix(field.parameter_count(), 1, rng);
    const Eigen::VectorXd& theta = field.parameters();
    const Eigen::Map<const Eigen::MatrixXd> a(theta.data(), 3, d);  // rows aᵤ
    const Eigen::VectorXd bias = theta.segment(3 * d, 3);
    const Eigen::VectorXd alpha = theta.segment(3 * d + 3, 3);

    // Directions: e₀ … e_{d−1}, then eᵢ + eⱼ and eᵢ − eⱼ for each pair i < j.
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < d; ++i)
      for (int j = i + 1; j < d; ++j) pairs.push_back({i, j});
    const int np = static_cast<int>(pairs.size());
    Eigen::MatrixXd dirs = Eigen::MatrixXd::Zero(d, d + 2 * np);
    dirs.leftCols(d).setIdentity();
    for (int q = 0; q < np; ++q) {
      const auto [i, j] = pairs[q];
      dirs(i, d + 2 * q) = dirs(j, d + 2 * q) = 1;
      dirs(i, d + 2 * q + 1) = 1;
      dirs(j, d + 2 * q + 1) = -1;
    }
    StreamSpec spec = StreamSpec::values(d);
    spec.set_taylor(dirs, 4);
    const StreamLayout layout(spec);
    const Eigen::MatrixXd x = random_matrix(6, d, rng);
    Streams<double> out;
    field.evaluate(layout, x, out);
    auto z = [&](int dir, int k) -> Eigen::MatrixXd { return out.stream(layout.taylor(dir, k)); };

    const Eigen::MatrixXd phase = (x * a.transpose()).rowwise() + bias.transpose();  // N × 3
    // Σᵤ αᵤ Πᵢ aᵤᵢ^pᵢ · g(phase) with g = sin or −cos, and its magnitude scale.
    auto exact = [&](const Eigen::VectorXi& powers, bool cosine, double* scale) {
      Eigen::MatrixXd e = Eigen::MatrixXd::Zero(x.rows(), 1);
      *scale = 0;
      for (int u = 0; u < 3; ++u) {
        double coef = alpha[u];
        for (int i = 0; i < d; ++i) coef *= std::pow(a(u, i), powers[i]);
        for (Eigen::Index n = 0; n < x.rows(); ++n)
          e(n, 0) += coef * (cosine ? -std::cos(phase(n, u)) : std::sin(phase(n, u)));
        *scale += std::abs(alpha[u]) * std::pow(a.row(u).norm(), powers.sum());
      }
      return e;
    };
    const std::string where = "d=" + std::to_string(d);
    double scale = 0;
    Eigen::MatrixXd biharmonic = Eigen::MatrixXd::Zero(x.rows(), 1);
    for (int i = 0; i < d; ++i) {
      const Eigen::MatrixXd e = exact(4 * Eigen::VectorXi::Unit(d, i), false, &scale);
      expect_close(24 * z(i, 4), e, "u_iiii", where, scale);
      expect_close(6 * z(i, 3), exact(3 * Eigen::VectorXi::Unit(d, i), true, &scale), "u_iii",
                   where, scale);
      biharmonic += 24 * z(i, 4);
    }
    Eigen::MatrixXd biharmonic_exact = Eigen::MatrixXd::Zero(x.rows(), 1);
    double biharmonic_scale = 0;
    for (int u = 0; u < 3; ++u) {
      const double a2 = a.row(u).squaredNorm();
      for (Eigen::Index n = 0; n < x.rows(); ++n)
        biharmonic_exact(n, 0) += alpha[u] * a2 * a2 * std::sin(phase(n, u));
      biharmonic_scale += std::abs(alpha[u]) * a2 * a2;
    }
    for (int q = 0; q < np; ++q) {
      const auto [i, j] = pairs[q];
      const int plus = d + 2 * q, minus = d + 2 * q + 1;
      const Eigen::MatrixXd iijj = 2 * (z(plus, 4) + z(minus, 4) - 2 * z(i, 4) - 2 * z(j, 4));
      Eigen::VectorXi p22 = Eigen::VectorXi::Zero(d);
      p22[i] = p22[j] = 2;
      expect_close(iijj, exact(p22, false, &scale), "u_iijj by polarization", where, scale);
      Eigen::VectorXi p21 = Eigen::VectorXi::Zero(d);
      p21[i] = 2;
      p21[j] = 1;
      expect_close(z(plus, 3) - z(minus, 3) - 2 * z(j, 3), exact(p21, true, &scale),
                   "u_iij by polarization", where, scale);
      biharmonic += 2 * iijj;
    }
    expect_close(biharmonic, biharmonic_exact, "biharmonic by polarization", where,
                 biharmonic_scale);
    if (d == 2) {
      // Three directions 60° apart carry Δ² exactly: 13 streams instead of 17.
      StreamSpec spec3 = StreamSpec::values(2);
      spec3.set_taylor(autodiff::biharmonic_directions_2d(), 4);
      const StreamLayout layout3(spec3);
      Streams<double> out3;
      field.evaluate(layout3, x, out3);
      Eigen::MatrixXd from_three = Eigen::MatrixXd::Zero(x.rows(), 1);
      for (int p = 0; p < 3; ++p) from_three += autodiff::kBiharmonic2dWeight * out3.stream(layout3.taylor(p, 4));
      EXPECT_EQ(layout3.count(), 13);
      expect_close(from_three, biharmonic_exact, "biharmonic from three directions", where,
                   biharmonic_scale);
    }
  }
}

}  // namespace
}  // namespace nfield::testutil
