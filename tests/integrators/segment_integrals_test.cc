// SPDX-License-Identifier: MIT
#include "integrators/segment_integrals.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace nfield::integrators {
namespace {

TEST(AdaptiveGaussKronrod, OneRoundIsExactForPolynomialsUpToDegree22) {
  // K15 integrates degree 3·7+1 = 22 exactly; G7 only up to 13, so the estimate is not 0
  // but the returned K15 value is exact.
  const auto f = [](const Eigen::MatrixXd& x) -> Eigen::VectorXd { return x.col(0).array().pow(22); };
  Eigen::MatrixXd a(1, 1), b(1, 1);
  a << -1;
  b << 1;
  const auto result = adaptive_gauss_kronrod(f, a, b, {.tolerance = 1e3});
  EXPECT_EQ(result.rounds, 1);
  EXPECT_EQ(result.evaluations, 15);
  EXPECT_NEAR(result.integrals(0), 2.0 / 23.0, 1e-15);
}

TEST(AdaptiveGaussKronrod, MeetsTheToleranceOnOscillatingIntegrandsAlongSegments) {
  // f(x, y) = cos(40 x + 3 y) along segments of the plane: the exact line integral is
  // L · [sin(φ(b)) − sin(φ(a))] / (φ(b) − φ(a)) with φ linear along the segment.
  const auto f = [](const Eigen::MatrixXd& p) -> Eigen::VectorXd {
    return (40 * p.col(0) + 3 * p.col(1)).array().cos();
  };
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(50, 2), b = Eigen::MatrixXd::Random(50, 2);
  const auto result = adaptive_gauss_kronrod(f, a, b, {.tolerance = 1e-10});
  EXPECT_EQ(result.unconverged, 0);
  EXPECT_GT(result.rounds, 1);
  for (Eigen::Index k = 0; k < a.rows(); ++k) {
    const double phi_a = 40 * a(k, 0) + 3 * a(k, 1), phi_b = 40 * b(k, 0) + 3 * b(k, 1);
    const double length = (b.row(k) - a.row(k)).norm();
    const double exact = length * (std::sin(phi_b) - std::sin(phi_a)) / (phi_b - phi_a);
    EXPECT_NEAR(result.integrals(k), exact, 1e-10) << "segment " << k;
    EXPECT_LE(result.error_estimates(k), 1e-10);
  }
}

TEST(AdaptiveGaussKronrod, CountsPiecesLeftAtMaximumDepth) {
  // |x|^-0.9 near 0 cannot meet 1e-14 within two bisections.
  const auto f = [](const Eigen::MatrixXd& x) -> Eigen::VectorXd { return x.col(0).array().abs().pow(-0.9); };
  Eigen::MatrixXd a(1, 1), b(1, 1);
  a << 0;
  b << 1;
  const auto result = adaptive_gauss_kronrod(f, a, b, {.tolerance = 1e-14, .max_depth = 2});
  EXPECT_GT(result.unconverged, 0);
  EXPECT_EQ(result.rounds, 3);
}

TEST(AdaptiveGaussKronrod, StopsAtTheRoundingOfItsIntegrand) {
  // cos(x) rounded to float: a tolerance of 1e-15 lies below what the values resolve. With
  // the float epsilon the pieces stop where |K15 − G7| is rounding, within a few rounds and
  // still accurate to float precision; with double's they bisect to max_depth.
  const auto f = [](const Eigen::MatrixXd& x) -> Eigen::VectorXd {
    return x.col(0).array().cos().cast<float>().cast<double>();
  };
  Eigen::MatrixXd a(1, 1), b(1, 1);
  a << 0;
  b << 100;
  AdaptiveQuadratureOptions options;
  options.tolerance = 1e-15;
  options.max_depth = 16;
  options.epsilon = std::numeric_limits<float>::epsilon();
  const auto rounded = adaptive_gauss_kronrod(f, a, b, options);
  EXPECT_LT(rounded.rounds, 10);
  EXPECT_NEAR(rounded.integrals(0), std::sin(100.0), 1e-5);
  options.epsilon = std::numeric_limits<double>::epsilon();
  const auto bisected = adaptive_gauss_kronrod(f, a, b, options);
  EXPECT_EQ(bisected.rounds, 17);
  EXPECT_GT(bisected.evaluations, 100 * rounded.evaluations);
}

TEST(AdaptiveGaussKronrod, RejectsBadOptionsNamingTheField) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(1, 1), b = Eigen::MatrixXd::Ones(1, 1);
  const auto f = [](const Eigen::MatrixXd& x) -> Eigen::VectorXd { return x.col(0); };
  try {
    adaptive_gauss_kronrod(f, a, b, {.tolerance = 0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tolerance"), std::string::npos) << e.what();
  }
  EXPECT_THROW(adaptive_gauss_kronrod(f, a, b, {.max_depth = 0}), std::invalid_argument);
  EXPECT_THROW(adaptive_gauss_kronrod(f, a, b, {.epsilon = 0}), std::invalid_argument);
}

TEST(AntiderivativeDifferences, GiveTheIntegralOfTheDirectionalDerivative) {
  // Φ(x, y) = x² y: along a segment, ∫ ∂ᵤΦ ds = Φ(b) − Φ(a), checked by quadrature of
  // ∂ᵤΦ = ∇Φ · u.
  const auto phi = [](const Eigen::MatrixXd& p) -> Eigen::VectorXd {
    return p.col(0).array().square() * p.col(1).array();
  };
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(20, 2), b = Eigen::MatrixXd::Random(20, 2);
  const Eigen::VectorXd differences = antiderivative_differences(phi, a, b);
  for (Eigen::Index k = 0; k < a.rows(); ++k) {
    const Eigen::RowVector2d u = (b.row(k) - a.row(k)).normalized();
    const auto derivative = [&u](const Eigen::MatrixXd& p) -> Eigen::VectorXd {
      return (2 * p.col(0).array() * p.col(1).array() * u(0) + p.col(0).array().square() * u(1)).matrix();
    };
    const auto quadrature = adaptive_gauss_kronrod(derivative, a.row(k), b.row(k), {.tolerance = 1e-12});
    EXPECT_NEAR(differences(k), quadrature.integrals(0), 1e-12);
  }
}

}  // namespace
}  // namespace nfield::integrators
