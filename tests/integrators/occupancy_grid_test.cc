// SPDX-License-Identifier: MIT
//
// The occupancy grid on an analytic density (a ball) and the marcher that skips empty space.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "integrators/camera.h"
#include "integrators/occupancy_grid.h"
#include "integrators/scene_box.h"
#include "integrators/volume_rendering.h"

namespace nfield::integrators {
namespace {

constexpr double kRadius = 0.5;
constexpr double kDensity = 30.0;

// σ = kDensity inside the ball of radius kRadius about `centre`, 0 outside.
Eigen::VectorXd ball(const Eigen::MatrixXd& x, const Eigen::RowVector3d& centre = Eigen::RowVector3d::Zero()) {
  return ((x.rowwise() - centre).rowwise().norm().array() < kRadius).cast<double>() * kDensity;
}

const SceneBox kBox{Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};

TEST(OccupancyGrid, MarksTheBallAndNotTheCorners) {
  OccupancyGrid grid(kBox, {.resolution = 32});
  EXPECT_EQ(grid.occupied_cells(), grid.cells());  // everything until the first update
  for (int u = 0; u < 4; ++u) grid.update([](const Eigen::MatrixXd& x) { return ball(x); }, 0.95);
  EXPECT_EQ(grid.threshold(), 0.01);  // the mean density (≈ 2) is above the cap
  const double cell = 2.0 / 32, half_diagonal = std::sqrt(3.0) * cell / 2;
  Eigen::Index inside = 0, outside = 0;
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        const double r = (Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * cell -
                          Eigen::Vector3d::Ones()).norm();
        if (r < kRadius - half_diagonal) {  // wholly inside the ball
          EXPECT_TRUE(grid.cell_occupied(i, j, k)) << i << " " << j << " " << k;
          ++inside;
        } else if (r > kRadius + half_diagonal) {  // wholly outside
          EXPECT_FALSE(grid.cell_occupied(i, j, k)) << i << " " << j << " " << k;
          ++outside;
        }
      }
  EXPECT_GT(inside, 1500);
  EXPECT_GT(outside, 25000);
  EXPECT_TRUE(grid.occupied(Eigen::Vector3d(0.1, -0.2, 0.05)));
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0})
      for (double sz : {-1.0, 1.0}) EXPECT_FALSE(grid.occupied(Eigen::Vector3d(sx, sy, sz) * 0.97));
  EXPECT_FALSE(grid.occupied(Eigen::Vector3d(0, 0, 3)));  // outside the box
}

TEST(OccupancyGrid, ThresholdFallsToTheMeanForFaintFields) {
  OccupancyGrid grid(kBox, {.resolution = 16, .threshold = 0.01});
  grid.update([](const Eigen::MatrixXd& x) { return Eigen::VectorXd(ball(x) * 1e-5); }, 0.95);
  EXPECT_LT(grid.threshold(), 0.01);  // min(mean, 0.01) = mean
  EXPECT_TRUE(grid.occupied(Eigen::Vector3d::Zero()));
  EXPECT_FALSE(grid.occupied(Eigen::Vector3d(0.9, 0.9, 0.9)));
}

TEST(OccupancyGrid, DecayForgetsAMovedBall) {
  // The ball moves from x = −0.45 to x = +0.45: the old cells fade as decay^k under either
  // rule and drop below the threshold, the new ones light up.
  const Eigen::RowVector3d left(-0.45, 0, 0), right(0.45, 0, 0);
  for (auto rule : {OccupancyGridOptions::Rule::kDecayedMax, OccupancyGridOptions::Rule::kMovingAverage}) {
    OccupancyGrid grid(kBox, {.resolution = 16, .rule = rule});
    grid.update([&](const Eigen::MatrixXd& x) { return ball(x, left); }, 0.5);
    EXPECT_TRUE(grid.occupied(Eigen::Vector3d(-0.7, 0, 0)));
    EXPECT_FALSE(grid.occupied(Eigen::Vector3d(0.7, 0, 0)));
    for (int u = 0; u < 20; ++u) grid.update([&](const Eigen::MatrixXd& x) { return ball(x, right); }, 0.5);
    EXPECT_FALSE(grid.occupied(Eigen::Vector3d(-0.7, 0, 0)));
    EXPECT_TRUE(grid.occupied(Eigen::Vector3d(0.7, 0, 0)));
  }
}

TEST(OccupancyGrid, SubsetUpdatesReachTheBall) {
  OccupancyGrid grid(kBox, {.resolution = 16, .cells_per_update = 1024, .batch_points = 100, .seed = 3});
  Eigen::Index calls = 0;
  for (int u = 0; u < 30; ++u)
    grid.update([&](const Eigen::MatrixXd& x) { ++calls; EXPECT_LE(x.rows(), 100); return ball(x); }, 0.95);
  EXPECT_EQ(calls, 30 * 21);  // 2048 cells per update in calls of at most 100 points
  EXPECT_TRUE(grid.occupied(Eigen::Vector3d::Zero()));
  EXPECT_FALSE(grid.occupied(Eigen::Vector3d(0.9, -0.9, 0.9)));
}

// A 24 × 24 camera at distance 2.5 looking at the origin, its rays clipped to the box.
Rays<double> camera_rays() {
  Camera camera;
  camera.intrinsics = Intrinsics::from_horizontal_fov(0.8, 24, 24);
  camera.camera_to_world.block<3, 1>(0, 3) = Eigen::Vector3d(0, 0, 2.5);
  auto rays = image_rays<double>(camera);
  clip_to_box(rays, kBox);
  return rays;
}

TEST(OccupancyGrid, MarcherSkipsEmptySpaceAndRendersTheSameOpacity) {
  OccupancyGrid grid(kBox, {.resolution = 32});
  const auto rays = camera_rays();
  const MarchOptions march{.steps_per_diagonal = 512};
  const auto dense = grid.march(rays, march);  // before any update: every cell occupied
  // One jittered point per cell can miss a cell that the ball only grazes, and a ray through
  // such a cell loses a little opacity (measured here: max 0.24 after 2 updates, 0.04 after
  // 4, 3e-3 after 8, 4e-13 after 16); with the decayed max each update adds a chance.
  for (int u = 0; u < 16; ++u) grid.update([](const Eigen::MatrixXd& x) { return ball(x); }, 0.95);
  const auto sparse = grid.march(rays, march);
  sparse.validate();
  EXPECT_LT(sparse.size(), dense.size() / 3);

  const auto opacity = [&](const RaySamples<double>& s) {
    const Eigen::MatrixXd x = sample_points(rays, s);
    return render<double>(s, ball(x), Eigen::MatrixXd::Ones(s.size(), 3), Eigen::RowVector3d::Zero())
        .opacity;
  };
  const Eigen::VectorXd a_dense = opacity(dense), a_sparse = opacity(sparse);
  EXPECT_LT((a_dense - a_sparse).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_GT(a_dense.maxCoeff(), 0.99);  // rays through the ball are opaque
  EXPECT_EQ(a_dense.minCoeff(), 0.0);   // the corners of the image miss it

  // The marcher's samples: fixed step, midpoints, in occupied cells, within [near, far].
  const double step = grid.step(march);
  for (Eigen::Index r = 0; r < rays.size(); ++r)
    for (Eigen::Index i = sparse.begin(r); i < sparse.end(r); ++i) {
      EXPECT_LE(sparse.delta(i), step * (1 + 1e-12));
      EXPECT_GE(sparse.t(i) - 0.5 * sparse.delta(i), rays.near(r) - 1e-12);
      EXPECT_LE(sparse.t(i) + 0.5 * sparse.delta(i), rays.far(r) + 1e-12);
      EXPECT_TRUE(grid.occupied((rays.origins.row(r) + sparse.t(i) * rays.directions.row(r)).transpose()));
    }

  // Against the stratified sampler, an independent quadrature of the same integral.
  std::mt19937_64 rng(0);
  const auto strat = stratified_samples(rays, {.samples_per_ray = 1024, .jitter = false}, rng);
  EXPECT_LT((opacity(strat) - a_sparse).cwiseAbs().mean(), 5e-3);

  // Float rays give the same samples up to float rounding at cell faces.
  const auto sparse_f = grid.march(rays.cast<float>(), march);
  EXPECT_NEAR(sparse_f.size(), sparse.size(), sparse.size() / 100);
}

TEST(OccupancyGrid, ValidatesOptions) {
  try {
    OccupancyGrid grid(kBox, {.resolution = 0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("occupancy_grid.resolution = 0"), std::string::npos) << e.what();
  }
  OccupancyGrid grid(kBox, {.resolution = 4});
  EXPECT_THROW(grid.update([](const Eigen::MatrixXd& x) { return ball(x); }, 1.5), std::invalid_argument);
  EXPECT_THROW(grid.update([](const Eigen::MatrixXd&) { return Eigen::VectorXd(1); }, 0.9), std::runtime_error);
}

}  // namespace
}  // namespace nfield::integrators
