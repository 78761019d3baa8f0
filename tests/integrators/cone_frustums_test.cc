// SPDX-License-Identifier: MIT
//
// Conical frustums as Gaussians (integrators/cone_frustums.h) and the cone radius of camera
// rays (integrators/camera.h):
//   * the Gaussian of sample_gaussians (mean, diagonal variances in world axes) against a
//     Monte Carlo estimate over points uniform in the frustum, within 5 standard errors of the
//     estimate, for thin and thick frustums, one at the apex;
//   * the closed forms against the direct ratios of moments, and their limits;
//   * a camera ray's radius is 2/√12 times the distance between neighbouring pixels' unit
//     directions (the pixel's width at unit distance), carried by subset and cast.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "integrators/camera.h"
#include "integrators/cone_frustums.h"
#include "integrators/random_bits.h"

namespace nfield::integrators {
namespace {

double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

struct Case {
  double t0, t1, radius;
};

// Points uniform in the frustum: t with density ∝ t² (inverse CDF), the offset uniform on the
// disc of radius r·t across the ray.
TEST(ConeFrustums, GaussianMatchesMonteCarlo) {
  std::mt19937_64 rng(42);
  const Eigen::Vector3d origin(0.3, -1.2, 2.5);
  const Eigen::Vector3d direction = Eigen::Vector3d(-0.4, 0.7, -0.6).normalized();
  // Two unit vectors across the ray.
  const Eigen::Vector3d u = direction.unitOrthogonal(), v = direction.cross(u);
  for (const Case c : {Case{3.9, 4.0, 0.05}, Case{1.0, 3.0, 0.2}, Case{0.0, 1.0, 0.5}, Case{2.0, 2.5, 0.0}}) {
    Rays<double> rays;
    rays.resize(1);
    rays.origins.row(0) = origin.transpose();
    rays.directions.row(0) = direction.transpose();
    rays.radius(0) = c.radius;
    RaySamples<double> samples;
    samples.offsets = {0, 1};
    samples.t.setConstant(1, 0.5 * (c.t0 + c.t1));  // the stretch of length δ centred on t
    samples.delta.setConstant(1, c.t1 - c.t0);
    const SampleGaussians<double> g = sample_gaussians(rays, samples);

    const int n = 400000;
    Eigen::MatrixXd points(n, 3);
    Eigen::VectorXd along(n), across(n);
    const double c0 = c.t0 * c.t0 * c.t0, c1 = c.t1 * c.t1 * c.t1;
    for (int i = 0; i < n; ++i) {
      const double t = std::cbrt(c0 + unit(rng) * (c1 - c0));
      const double rho = c.radius * t * std::sqrt(unit(rng)), phi = 2 * std::numbers::pi * unit(rng);
      const Eigen::Vector3d offset = rho * (std::cos(phi) * u + std::sin(phi) * v);
      points.row(i) = (origin + t * direction + offset).transpose();
      along(i) = t;
      across(i) = offset.dot(u);
    }
    const Eigen::RowVector3d mean = points.colwise().mean();
    const Eigen::MatrixXd centred = points.rowwise() - mean;
    const Eigen::RowVector3d variance = centred.array().square().colwise().mean();
    const Eigen::RowVector3d fourth = centred.array().pow(4).colwise().mean();
    const std::string where = "[" + std::to_string(c.t0) + ", " + std::to_string(c.t1) + "], r " +
                              std::to_string(c.radius);
    for (int a = 0; a < 3; ++a) {
      const double mean_error = std::sqrt(variance(a) / n);
      const double variance_error = std::sqrt((fourth(a) - variance(a) * variance(a)) / n);
      EXPECT_NEAR(g.mean(0, a), mean(a), 5 * mean_error + 1e-15) << where << " axis " << a;
      EXPECT_NEAR(g.variance(0, a), variance(a), 5 * variance_error + 1e-15) << where << " axis " << a;
    }
    // In the ray's frame: the variance along it and across it.
    const FrustumMoments f = frustum_moments(c.t0, c.t1, c.radius);
    const double along_mean = along.mean();
    const double along_variance = (along.array() - along_mean).square().mean();
    const double across_variance = across.array().square().mean();
    EXPECT_NEAR(f.mean, along_mean, 5 * std::sqrt(along_variance / n)) << where;
    EXPECT_NEAR(f.along, along_variance,
                5 * std::sqrt(((along.array() - along_mean).pow(4).mean() - along_variance * along_variance) / n))
        << where;
    EXPECT_NEAR(f.across, across_variance,
                5 * std::sqrt((across.array().pow(4).mean() - across_variance * across_variance) / n) + 1e-15)
        << where;
  }
}

TEST(ConeFrustums, ClosedFormsMatchTheMomentRatios) {
  for (const Case c : {Case{0.5, 0.7, 0.1}, Case{1.0, 4.0, 0.02}, Case{0.0, 2.0, 1.0}, Case{3.0, 3.001, 0.3}}) {
    const long double t0 = c.t0, t1 = c.t1, r = c.radius;
    const long double cubes = t1 * t1 * t1 - t0 * t0 * t0;
    const long double mean = 0.75L * (t1 * t1 * t1 * t1 - t0 * t0 * t0 * t0) / cubes;
    const long double second = 0.6L * (std::pow(t1, 5.0L) - std::pow(t0, 5.0L)) / cubes;
    const FrustumMoments f = frustum_moments(c.t0, c.t1, c.radius);
    EXPECT_NEAR(f.mean, static_cast<double>(mean), 1e-14 * c.t1);
    // The ratio form loses digits to cancellation for a thin frustum: compare loosely there.
    EXPECT_NEAR(f.along, static_cast<double>(second - mean * mean), 1e-9 * c.t1 * c.t1);
    EXPECT_NEAR(f.across, static_cast<double>(r * r / 4 * second), 1e-14 * c.t1 * c.t1);
  }
  // A thin frustum: t uniform on [m − h, m + h] (variance h²/3), the disc at m.
  const double m = 4.0, h = 1e-4;
  const FrustumMoments thin = frustum_moments(m - h, m + h, 0.01);
  EXPECT_NEAR(thin.mean, m, 1e-8);
  EXPECT_NEAR(thin.along, h * h / 3, 1e-6 * h * h);
  EXPECT_NEAR(thin.across, 0.01 * 0.01 * m * m / 4, 1e-8 * 0.01 * 0.01 * m * m);
  // A point: no spread.
  const FrustumMoments point = frustum_moments(2.0, 2.0, 0.3);
  EXPECT_EQ(point.mean, 2.0);
  EXPECT_EQ(point.along, 0.0);
  EXPECT_NEAR(point.across, 0.3 * 0.3 * 4 / 4, 1e-15);
  EXPECT_THROW(frustum_moments(-0.1, 1.0, 0.1), std::invalid_argument);
  EXPECT_THROW(frustum_moments(1.0, 0.5, 0.1), std::invalid_argument);
}

TEST(ConeFrustums, CameraRaysCarryThePixelsCone) {
  Camera camera;
  camera.intrinsics = Intrinsics::from_horizontal_fov(0.69, 64, 48);
  camera.camera_to_world.block<3, 3>(0, 0) = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  camera.camera_to_world.block<3, 1>(0, 3) = Eigen::Vector3d(0.5, 1.0, 4.0);
  const Rays<double> rays = image_rays<double>(camera);
  ASSERT_EQ(rays.radius.size(), rays.size());
  // The central pixels: the width at unit distance is the distance between neighbouring unit
  // directions, 1/fx there (to second order in the angle off the axis).
  for (const auto& [r, c] : {std::pair{23, 31}, std::pair{24, 32}, std::pair{0, 0}, std::pair{47, 62}}) {
    const Eigen::Index i = Eigen::Index{r} * 64 + c;
    const double neighbour = (rays.directions.row(i + 1) - rays.directions.row(i)).norm();
    const double width = rays.radius(i) * std::sqrt(12.0) / 2;
    // Off the axis the pixel shrinks as seen from the camera, by about depth_scale² across.
    const bool central = std::abs(r - 24) < 4 && std::abs(c - 32) < 4;
    EXPECT_NEAR(width, neighbour, (central ? 2e-3 : 0.2) * neighbour) << r << ", " << c;
    EXPECT_NEAR(width, rays.depth_scale(i) / camera.intrinsics.fx, 1e-15);
  }
  // subset and cast keep the radius; resize gives rays of no width.
  const std::vector<Eigen::Index> keep{5, 9};
  EXPECT_EQ(rays.subset(keep).radius(1), rays.radius(9));
  EXPECT_EQ(rays.cast<float>().radius(3), static_cast<float>(rays.radius(3)));
  Rays<float> plain;
  plain.resize(4);
  EXPECT_EQ(plain.radius.size(), 4);
  EXPECT_EQ(plain.radius.maxCoeff(), 0.0f);
}

}  // namespace
}  // namespace nfield::integrators
