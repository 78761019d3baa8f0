// SPDX-License-Identifier: MIT
//
// Stratified and hierarchical samples along rays in the flat layout.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "integrators/ray_sampling.h"
#include "integrators/volume_rendering.h"

namespace nfield::integrators {
namespace {

// Three rays along +x, +y, +z from the origin with [near, far] = [1, 3], [0, 0] (empty), [2, 2.5].
Rays<double> three_rays() {
  Rays<double> rays;
  rays.resize(3);
  rays.origins.setZero();
  rays.directions = Eigen::Matrix3d::Identity();
  rays.near << 1, 0, 2;
  rays.far << 3, 0, 2.5;
  return rays;
}

void expect_interval_rule(const Rays<double>& rays, const RaySamples<double>& s) {
  s.validate();
  for (Eigen::Index r = 0; r < s.rays(); ++r)
    for (Eigen::Index i = s.begin(r); i < s.end(r); ++i) {
      EXPECT_GE(s.t(i), rays.near(r));
      EXPECT_LE(s.t(i), rays.far(r));
      const double next = i + 1 < s.end(r) ? s.t(i + 1) : rays.far(r);
      EXPECT_NEAR(s.delta(i), next - s.t(i), 1e-15) << "ray " << r << " sample " << i;
      EXPECT_GE(s.delta(i), 0.0);
    }
}

TEST(StratifiedSamples, OneJitteredSampleInEachBin) {
  const auto rays = three_rays();
  std::mt19937_64 rng(1);
  const auto s = stratified_samples(rays, {.samples_per_ray = 8, .jitter = true}, rng);
  EXPECT_EQ(s.offsets, (std::vector<Eigen::Index>{0, 8, 8, 16}));
  expect_interval_rule(rays, s);
  for (int i = 0; i < 8; ++i) {
    EXPECT_GE(s.t(i), 1 + 0.25 * i);
    EXPECT_LT(s.t(i), 1 + 0.25 * (i + 1));
  }
  std::mt19937_64 same(1), other(2);
  EXPECT_EQ(stratified_samples(rays, {.samples_per_ray = 8}, same).t, s.t);
  EXPECT_NE(stratified_samples(rays, {.samples_per_ray = 8}, other).t, s.t);
}

// A range of rays keeps their samples, with offsets from the range's first sample.
TEST(RayRange, RaysOfOneBlockAsSamplesOfTheirOwn) {
  std::mt19937_64 rng(3);
  const auto all = stratified_samples(three_rays(), {.samples_per_ray = 5, .jitter = true}, rng);
  const auto tail = ray_range(all, 1, 3);
  ASSERT_EQ(tail.rays(), 2);
  EXPECT_EQ(tail.offsets.front(), 0);
  EXPECT_EQ(tail.size(), all.offsets[3] - all.offsets[1]);
  EXPECT_EQ(tail.t, all.t.segment(all.offsets[1], tail.size()));
  EXPECT_EQ(tail.delta, all.delta.segment(all.offsets[1], tail.size()));
  for (Eigen::Index r = 0; r < 2; ++r) EXPECT_EQ(tail.count(r), all.count(r + 1));
  EXPECT_NO_THROW(tail.validate());
}

TEST(StratifiedSamples, MidpointsForEvaluation) {
  const auto rays = three_rays();
  std::mt19937_64 rng(1);
  const auto s = stratified_samples(rays, {.samples_per_ray = 4, .jitter = false}, rng);
  EXPECT_EQ(s.t.head(4), Eigen::Vector4d(1.25, 1.75, 2.25, 2.75));
  EXPECT_EQ(s.delta.head(4), Eigen::Vector4d(0.5, 0.5, 0.5, 0.25));  // the last to far
  expect_interval_rule(rays, s);
  // Points and view directions for the network.
  const auto x = sample_points(rays, s);
  const auto d = sample_directions(rays, s);
  EXPECT_EQ(x.row(5), Eigen::RowVector3d(0, 0, s.t(5)));
  EXPECT_EQ(d.row(1), Eigen::RowVector3d(1, 0, 0));
}

// Sections cover [near, far] exactly: midpoints, every length (the last one's too) equal, and
// rendering a constant density over them is exact (e^{−σ(far − near)}).
TEST(EqualSections, MidpointsOfEqualSectionsCoveringTheRay) {
  const auto rays = three_rays();
  const auto s = equal_sections(rays, 4);
  EXPECT_EQ(s.offsets, (std::vector<Eigen::Index>{0, 4, 4, 8}));
  EXPECT_EQ(s.t.head(4), Eigen::Vector4d(1.25, 1.75, 2.25, 2.75));
  EXPECT_EQ(s.delta.head(4), Eigen::Vector4d::Constant(0.5));
  EXPECT_EQ(s.delta.tail(4), Eigen::Vector4d::Constant(0.125));
  EXPECT_NO_THROW(s.validate());
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(s.size(), 0.7);
  const auto image = render<double>(s, sigma, Eigen::MatrixXd::Zero(s.size(), 3), Eigen::MatrixXd::Ones(1, 3));
  EXPECT_NEAR(image.color(0, 0), std::exp(-0.7 * 2.0), 1e-15);
  EXPECT_NEAR(image.color(2, 0), std::exp(-0.7 * 0.5), 1e-15);
  EXPECT_EQ(image.color(1, 0), 1.0);
  EXPECT_THROW(equal_sections(rays, 0), std::invalid_argument);
  Rays<double> open;
  open.resize(1);
  open.origins.setZero();
  open.directions.setZero();
  EXPECT_THROW(equal_sections(open, 2), std::invalid_argument);  // far = +∞
}

TEST(StratifiedSamples, RejectsInfiniteBoundsAndBadOptions) {
  Rays<double> rays;
  rays.resize(2);  // far = +∞ until set
  rays.origins.setZero();
  rays.directions.setZero();
  std::mt19937_64 rng(1);
  try {
    stratified_samples(rays, {}, rng);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ray 0"), std::string::npos) << e.what();
  }
  try {
    StratifiedOptions{.samples_per_ray = 0}.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("samples_per_ray = 0"), std::string::npos) << e.what();
  }
}

TEST(ImportanceSamples, DeterministicInversionOfAPiecewiseConstantDensity) {
  // One ray on [0, 4] with coarse intervals [0,1], [1,2], [2,3], [3,4]; all mass on [2, 3].
  Rays<double> rays;
  rays.resize(1);
  rays.origins.setZero();
  rays.directions << 0, 0, 1;
  set_bounds(rays, 0.0, 4.0);
  RaySamples<double> coarse;
  coarse.offsets = {0, 4};
  coarse.t = Eigen::Vector4d(0, 1, 2, 3);
  coarse.delta = Eigen::Vector4d(1, 1, 1, 1);
  std::mt19937_64 rng(0);
  ImportanceOptions o{.samples_per_ray = 4, .deterministic = true, .weight_floor = 0,
                      .include_coarse = false};
  auto fine = importance_samples(rays, coarse, Eigen::Vector4d(0, 0, 2, 0), o, rng);
  EXPECT_EQ(fine.t, Eigen::Vector4d(2.125, 2.375, 2.625, 2.875));
  expect_interval_rule(rays, fine);

  // Equal mass on [0,1] and [3,4]: half the samples in each.
  fine = importance_samples(rays, coarse, Eigen::Vector4d(1, 0, 0, 1), o, rng);
  EXPECT_EQ(fine.t, Eigen::Vector4d(0.25, 0.75, 3.25, 3.75));

  // No mass at all and no floor: uniform in t.
  fine = importance_samples(rays, coarse, Eigen::Vector4d::Zero(), o, rng);
  EXPECT_EQ(fine.t, Eigen::Vector4d(0.5, 1.5, 2.5, 3.5));

  // Merged with the coarse samples, sorted, δ recomputed.
  o.include_coarse = true;
  const auto merged = importance_samples(rays, coarse, Eigen::Vector4d(0, 0, 2, 0), o, rng);
  Eigen::VectorXd expected(8);
  expected << 0, 1, 2, 2.125, 2.375, 2.625, 2.875, 3;
  EXPECT_EQ(merged.t, expected);
  expect_interval_rule(rays, merged);
  EXPECT_EQ(merged.delta(7), 1.0);
}

TEST(ImportanceSamples, RandomDrawsFollowTheWeights) {
  // Many rays with the same coarse weights: the share of fine samples per interval approaches
  // the interval's share of mass (plus the floor).
  const int rays_n = 200, coarse_n = 8, fine_n = 64;
  Rays<float> rays;
  rays.resize(rays_n);
  rays.origins.setZero();
  rays.directions.setZero();
  rays.directions.col(2).setOnes();
  set_bounds(rays, 2.0, 6.0);
  std::mt19937_64 rng(11);
  const auto coarse = stratified_samples(rays, {.samples_per_ray = coarse_n, .jitter = false}, rng);
  const Eigen::VectorXf pattern = (Eigen::VectorXf(coarse_n) << 0, 1, 4, 1, 0, 0, 2, 0).finished();
  const Eigen::VectorXf weights = pattern.replicate(rays_n, 1);
  const auto fine = importance_samples(
      rays, coarse, weights, {.samples_per_ray = fine_n, .include_coarse = false}, rng);
  ASSERT_EQ(fine.size(), rays_n * fine_n);
  std::vector<double> share(coarse_n, 0.0);
  for (Eigen::Index r = 0; r < rays_n; ++r)
    for (Eigen::Index i = fine.begin(r); i < fine.end(r); ++i) {
      ASSERT_TRUE(i == fine.begin(r) || fine.t(i) >= fine.t(i - 1));
      const int bin = std::min(coarse_n - 1, static_cast<int>((fine.t(i) - coarse.t(0)) / 0.5f));
      share[bin] += 1.0 / (rays_n * fine_n);
    }
  for (int b = 0; b < coarse_n; ++b) EXPECT_NEAR(share[b], pattern(b) / 8.0, 0.01) << "bin " << b;
  // Rays with no coarse samples get no fine ones.
  RaySamples<float> none;
  none.offsets.assign(rays_n + 1, 0);
  EXPECT_EQ(importance_samples(rays, none, Eigen::VectorXf(), {}, rng).size(), 0);
}

TEST(ImportanceSamples, CoarseThenFineRendersTheSameSurface) {
  // A slab of density on [3, 3.2]: coarse weights find it, fine samples crowd into it.
  Rays<double> rays;
  rays.resize(1);
  rays.origins.setZero();
  rays.directions << 0, 0, 1;
  set_bounds(rays, 2.0, 6.0);
  std::mt19937_64 rng(4);
  const auto density = [](const RaySamples<double>& s) {
    Eigen::VectorXd sigma(s.size());
    for (Eigen::Index i = 0; i < s.size(); ++i) sigma(i) = s.t(i) >= 3.0 && s.t(i) < 3.2 ? 50.0 : 0.0;
    return sigma;
  };
  const auto coarse = stratified_samples(rays, {.samples_per_ray = 64}, rng);
  const auto rgb = [](const RaySamples<double>& s) { return Eigen::MatrixXd::Ones(s.size(), 3); };
  const auto out = render<double>(coarse, density(coarse), rgb(coarse), Eigen::RowVector3d::Zero());
  const auto fine = importance_samples(rays, coarse, out.weights, {.samples_per_ray = 64}, rng);
  Eigen::Index inside = 0;
  for (Eigen::Index i = 0; i < fine.size(); ++i) inside += fine.t(i) >= 2.9 && fine.t(i) < 3.3;
  EXPECT_GT(inside, 60);
  const auto refined = render<double>(fine, density(fine), rgb(fine), Eigen::RowVector3d::Zero());
  EXPECT_NEAR(refined.opacity(0), 1 - std::exp(-50.0 * 0.2), 2e-3);
  EXPECT_NEAR(refined.depth(0) / refined.opacity(0), 3.02, 0.06);
}

}  // namespace
}  // namespace nfield::integrators
