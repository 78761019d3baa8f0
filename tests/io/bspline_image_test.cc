// SPDX-License-Identifier: MIT
#include "io/bspline_image.h"

#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

namespace nfield::io {
namespace {

Eigen::MatrixXd random_picture(int height, int width, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(height, width);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) p(r, c) = u(rng);
  return p;
}

TEST(BSplineImage, PassesThroughEveryPixel) {
  const Eigen::MatrixXd p = random_picture(7, 9, 1);
  const BSplineImage s(p);
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(s.at(c, r).value, p(r, c), 1e-12) << r << ", " << c;
}

// Every derivative against central differences of the next lower one, at random points,
// near the border too (the mirror extension must be the one the prefilter assumed, else the
// spline is not C² there).
TEST(BSplineImage, DerivativesMatchCentralDifferences) {
  const BSplineImage s(random_picture(11, 13, 2));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uc(0.0, 12.0), ur(0.0, 10.0);
  const double h = 1e-5;
  for (int k = 0; k < 200; ++k) {
    const double c = uc(rng), r = ur(rng);
    const auto at = s.at(c, r);
    const double cp = std::min(c + h, 12.0), cm = std::max(c - h, 0.0);
    const double rp = std::min(r + h, 10.0), rm = std::max(r - h, 0.0);
    EXPECT_NEAR(at.d_column, (s.at(cp, r).value - s.at(cm, r).value) / (cp - cm), 1e-7);
    EXPECT_NEAR(at.d_row, (s.at(c, rp).value - s.at(c, rm).value) / (rp - rm), 1e-7);
    EXPECT_NEAR(at.dd_column, (s.at(cp, r).d_column - s.at(cm, r).d_column) / (cp - cm), 1e-6);
    EXPECT_NEAR(at.dd_row, (s.at(c, rp).d_row - s.at(c, rm).d_row) / (rp - rm), 1e-6);
  }
}

TEST(BSplineImage, IsEvenAboutTheBorderPixels) {
  const BSplineImage s(random_picture(6, 8, 4));
  for (double r : {0.0, 1.3, 5.0}) {
    EXPECT_NEAR(s.at(0.0, r).d_column, 0.0, 1e-12);
    EXPECT_NEAR(s.at(7.0, r).d_column, 0.0, 1e-12);
  }
  for (double c : {0.0, 2.7, 7.0}) {
    EXPECT_NEAR(s.at(c, 0.0).d_row, 0.0, 1e-12);
    EXPECT_NEAR(s.at(c, 5.0).d_row, 0.0, 1e-12);
  }
}

// Cubic B-splines reproduce cubics; the mirror border disturbs the coefficients only by a
// factor (2 − √3)^k at k pixels from it.
TEST(BSplineImage, ReproducesACubicAwayFromTheBorder) {
  const int n = 64;
  Eigen::MatrixXd p(n, n);
  const auto f = [](double c, double r) { return 0.3 * c * c - 0.2 * c * r + r * r * r / 500; };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) p(r, c) = f(c, r);
  const BSplineImage s(p);
  for (double c : {25.0, 30.4, 37.9})
    for (double r : {26.1, 32.0, 38.5}) {
      const auto at = s.at(c, r);
      EXPECT_NEAR(at.value, f(c, r), 1e-6);
      EXPECT_NEAR(at.d_column, 0.6 * c - 0.2 * r, 1e-6);
      EXPECT_NEAR(at.d_row, -0.2 * c + 3 * r * r / 500, 1e-6);
      EXPECT_NEAR(at.dd_column, 0.6, 1e-6);
      EXPECT_NEAR(at.dd_row, 6 * r / 500, 1e-6);
    }
}

TEST(BSplineImage, RejectsATooSmallPicture) {
  EXPECT_THROW(BSplineImage(Eigen::MatrixXd::Ones(1, 5)), std::invalid_argument);
}

// The zero-flux field of the Laplacian (BSplineLaplacianFlux) on a rough picture with
// unequal spacings, X = c·hx over 12 columns and Y = r·hy over 10 rows.
class LaplacianFlux : public ::testing::Test {
 protected:
  static constexpr int kWidth = 13, kHeight = 11;
  static constexpr double kHx = 2.0 / 12, kHy = 1.5 / 10;
  LaplacianFlux() : spline_(random_picture(kHeight, kWidth, 5)), q_(spline_, kHx, kHy) {}

  // ∫ from 0 to `to` of f(t) dt (pixel units) by 3-point Gauss–Legendre on 64 pieces of each
  // unit cell (f is smooth within a cell only), not the class's Simpson nodes.
  static double fine_integral(const std::function<double(double)>& f, double to) {
    const double nodes[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, weights[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
    double total = 0;
    for (int cell = 0; cell < to; ++cell) {
      const double end = std::min<double>(cell + 1, to);
      for (int p = 0; p < 64; ++p) {
        const double a = cell + (end - cell) * p / 64, b = cell + (end - cell) * (p + 1) / 64;
        for (int k = 0; k < 3; ++k) total += (b - a) / 2 * weights[k] * f((a + b) / 2 + (b - a) / 2 * nodes[k]);
      }
    }
    return total;
  }
  // The scale of g: its largest magnitude at the pixel centres.
  double g_scale() const {
    double m = 0;
    for (int r = 0; r < kHeight; ++r)
      for (int c = 0; c < kWidth; ++c) m = std::max(m, std::abs(q_.laplacian(c, r)));
    return m;
  }

  BSplineImage spline_;
  BSplineLaplacianFlux q_;
};

TEST_F(LaplacianFlux, LaplacianIsTheSplinesInTheScaledCoordinates) {
  const auto d = spline_.at(3.3, 4.6);
  EXPECT_DOUBLE_EQ(q_.laplacian(3.3, 4.6), d.dd_column / (kHx * kHx) + d.dd_row / (kHy * kHy));
}

// The mirrored spline has zero flux, so ∫∫g = 0 and the subtracted mean is rounding only.
TEST_F(LaplacianFlux, MeanOfTheLaplacianIsZero) {
  std::printf("g up to %.3g, mean %.3g\n", g_scale(), q_.mean());
  EXPECT_LT(std::abs(q_.mean()), 1e-12 * g_scale());
}

// ∇·q = g − m by central differences (step 1e-4 pixel) at random points: q is piecewise
// quartic, so the step's truncation error is about 1e-8 of g's scale, and a wrong spacing,
// sign or interpolation weight would be of order one.
TEST_F(LaplacianFlux, DivergenceIsTheLaplacian) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> uc(0.01, kWidth - 1.01), ur(0.01, kHeight - 1.01);
  const double h = 1e-4, scale = g_scale();
  double worst = 0;
  for (int k = 0; k < 300; ++k) {
    const double c = uc(rng), r = ur(rng);
    const double div = (q_.at(c + h, r)(0) - q_.at(c - h, r)(0)) / (2 * h * kHx) +
                       (q_.at(c, r + h)(1) - q_.at(c, r - h)(1)) / (2 * h * kHy);
    worst = std::max(worst, std::abs(div - (q_.laplacian(c, r) - q_.mean())));
  }
  std::printf("divergence: worst error %.2e of g's scale %.3g\n", worst, scale);
  EXPECT_LT(worst, 1e-6 * scale);
}

TEST_F(LaplacianFlux, NormalComponentIsZeroOnEverySide) {
  double worst = 0, typical = 0;
  for (int k = 0; k <= 40; ++k) {
    const double r = (kHeight - 1) * k / 40.0, c = (kWidth - 1) * k / 40.0;
    worst = std::max({worst, std::abs(q_.at(0, r)(0)), std::abs(q_.at(kWidth - 1, r)(0)), std::abs(q_.at(c, 0)(1)),
                      std::abs(q_.at(c, kHeight - 1)(1))});
    typical = std::max({typical, std::abs(q_.at(kWidth / 2.0, r)(0)), std::abs(q_.at(c, kHeight / 2.0)(1))});
  }
  std::printf("q.n on the border up to %.2e; q inside up to %.3g\n", worst, typical);
  EXPECT_GT(typical, 0.1);
  EXPECT_LT(worst, 1e-12 * typical);
}

// Simpson on the knot cells and the cubic interpolation in r are exact: a cell's row
// integral at rows between the tabulated ones, and the whole row's, equal a fine
// Gauss–Legendre quadrature of g.
TEST_F(LaplacianFlux, SimpsonIsExactForTheSplinesCubics) {
  for (double r : {0.0, 0.37, 4.81, 9.5, 10.0}) {
    double row = 0;
    for (int k = 0; k + 1 < kWidth; ++k) {
      const double cell = fine_integral([&](double c) { return q_.laplacian(k + c, r); }, 1.0);
      EXPECT_NEAR(q_.cell_row_integral(k, r), cell, 1e-12 * g_scale()) << k << ", " << r;
      row += q_.cell_row_integral(k, r);
    }
    EXPECT_NEAR(row, fine_integral([&](double c) { return q_.laplacian(c, r); }, kWidth - 1), 1e-11 * g_scale()) << r;
  }
}

// q is not the spline's gradient: they differ by a divergence-free field with zero flux, so
// ∫(∇s − q)·∇φ = −m ∫φ ≈ 0 for any smooth φ although ∇s − q is large. Integrals by 4-point
// Gauss–Legendre per pixel cell and axis (both factors are polynomials on a cell).
TEST_F(LaplacianFlux, DiffersFromTheGradientByAFieldOrthogonalToGradients) {
  const double nodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  const double weights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  using Gradient = std::function<Eigen::Vector2d(double, double)>;  // ∇φ at (X, Y)
  const std::vector<Gradient> phis = {
      [](double x, double y) { return Eigen::Vector2d(1.3 * std::cos(1.3 * x + 0.4) * std::cos(0.7 * y),
                                                      -0.7 * std::sin(1.3 * x + 0.4) * std::sin(0.7 * y)); },
      [](double x, double y) { return Eigen::Vector2d(2 * x * y, x * x); },
      [](double x, double y) { return Eigen::Vector2d(0.5 * std::exp(x / 2 - y), -std::exp(x / 2 - y)); }};
  double difference = 0, gradient = 0;
  std::vector<double> inner(phis.size(), 0.0), scale(phis.size(), 0.0);
  for (int i = 0; i + 1 < kHeight; ++i)
    for (int k = 0; k + 1 < kWidth; ++k)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
          const double c = k + 0.5 + 0.5 * nodes[a], r = i + 0.5 + 0.5 * nodes[b];
          const double w = weights[a] * weights[b] * 0.25 * kHx * kHy;
          const auto d = spline_.at(c, r);
          const Eigen::Vector2d grad_s(d.d_column / kHx, d.d_row / kHy);
          const Eigen::Vector2d e = grad_s - q_.at(c, r);
          difference += w * e.squaredNorm();
          gradient += w * grad_s.squaredNorm();
          for (std::size_t p = 0; p < phis.size(); ++p) {
            const Eigen::Vector2d gp = phis[p](c * kHx, r * kHy);
            inner[p] += w * e.dot(gp);
            scale[p] += w * e.norm() * gp.norm();
          }
        }
  std::printf("|grad s - q| / |grad s| = %.3f\n", std::sqrt(difference / gradient));
  EXPECT_GT(difference, 0.1 * gradient);
  for (std::size_t p = 0; p < phis.size(); ++p) {
    std::printf("phi %zu: <grad s - q, grad phi> = %.2e of %.3g\n", p, inner[p], scale[p]);
    EXPECT_LT(std::abs(inner[p]), 1e-10 * scale[p]) << p;
  }
}

}  // namespace
}  // namespace nfield::io
