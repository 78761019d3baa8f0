// SPDX-License-Identifier: MIT
#include "io/bspline_image.h"

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

}  // namespace
}  // namespace nfield::io
