// SPDX-License-Identifier: MIT
//
// Datasets made from frames (integrators/dataset_views.h): a band of columns keeps every kept
// pixel's ray and colour; recolouring scales and shifts the object's straight colour, clamps
// it, and leaves the background alone; the drawn scales and shifts lie in their ranges and
// follow the seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "integrators/dataset_views.h"
#include "integrators/ray_batch.h"

namespace nfield::integrators {
namespace {

const std::filesystem::path kBunny = std::filesystem::path(NFIELD_SOURCE_DIR) / "data/multiview/bunny_blender";

TEST(DatasetViews, ColumnsKeepTheirRaysAndColours) {
  const MultiviewDataset test = read_transforms(kBunny / "transforms_test.json");
  const int width = test.intrinsics.width;
  for (const auto& [begin, end] : {std::pair{0, 64}, std::pair{64, 128}, std::pair{17, 18}}) {
    const MultiviewDataset band = frame_columns(test, 3, begin, end);
    ASSERT_EQ(band.frames.size(), 1U);
    EXPECT_EQ(band.intrinsics.width, end - begin);
    const PixelBatch<double> all = frame_pixels<double>(test, 3), kept = frame_pixels<double>(band, 0);
    ASSERT_EQ(kept.rgb.rows(), Eigen::Index{end - begin} * test.intrinsics.height);
    for (Eigen::Index p = 0; p < kept.rgb.rows(); ++p) {
      const Eigen::Index row = p / (end - begin), column = p % (end - begin) + begin;
      const Eigen::Index q = row * width + column;
      EXPECT_LT((kept.rays.directions.row(p) - all.rays.directions.row(q)).norm(), 1e-12) << p;
      EXPECT_LT((kept.rays.origins.row(p) - all.rays.origins.row(q)).norm(), 1e-12) << p;
      EXPECT_EQ(kept.rgb.row(p), all.rgb.row(q)) << p;
      EXPECT_EQ(kept.alpha(p), all.alpha(q)) << p;
    }
  }
  EXPECT_THROW(frame_columns(test, 3, 64, 64), std::invalid_argument);
  EXPECT_THROW(frame_columns(test, 3, 0, width + 1), std::invalid_argument);
  EXPECT_THROW(frame_columns(test, 8, 0, 64), std::invalid_argument);
  EXPECT_THROW(single_frame(test, -1), std::invalid_argument);
}

TEST(DatasetViews, RecolouringScalesTheObjectAndKeepsTheBackground) {
  MultiviewDataset data;
  data.intrinsics = Intrinsics::from_horizontal_fov(0.7, 4, 1);
  data.background = Eigen::Vector3d(1.0, 1.0, 1.0);
  PosedImage image;
  image.camera.intrinsics = data.intrinsics;
  const Eigen::Vector4f alpha(1.0f, 0.0f, 0.5f, 1.0f);
  Eigen::MatrixXf straight(4, 3);  // the object's own colour
  straight << 0.5f, 0.2f, 0.9f, 0.3f, 0.3f, 0.3f, 0.4f, 0.6f, 0.1f, 0.95f, 0.05f, 0.5f;
  image.alpha = alpha;
  image.rgb.resize(4, 3);
  for (int p = 0; p < 4; ++p)
    for (int c = 0; c < 3; ++c) image.rgb(p, c) = alpha(p) * straight(p, c) + (1 - alpha(p)) * 1.0f;
  data.frames = {image};
  Recolouring r{Eigen::MatrixXd(1, 3), Eigen::MatrixXd(1, 3)};
  r.scale << 1.2, 0.8, 1.1;
  r.shift << 0.1, -0.2, 0.15;
  recolour(data, r);
  for (int p = 0; p < 4; ++p)
    for (int c = 0; c < 3; ++c) {
      const double coloured = std::clamp(straight(p, c) * r.scale(0, c) + r.shift(0, c), 0.0, 1.0);
      EXPECT_NEAR(data.frames[0].rgb(p, c), alpha(p) * coloured + (1 - alpha(p)), 1e-6) << p << " " << c;
    }
  EXPECT_EQ(data.frames[0].rgb.row(1), Eigen::RowVector3f::Ones());  // background: untouched
  EXPECT_EQ(data.frames[0].rgb(3, 0), 1.0f);                         // 0.95·1.2 + 0.1: clamped
  EXPECT_THROW(recolour(data, Recolouring{Eigen::MatrixXd(2, 3), Eigen::MatrixXd(2, 3)}), std::invalid_argument);
}

TEST(DatasetViews, DrawnRecolouringsLieInTheirRangesAndFollowTheSeed) {
  const Recolouring a = draw_recolouring(40, 0.8, 1.2, -0.2, 0.2, 7), b = draw_recolouring(40, 0.8, 1.2, -0.2, 0.2, 7);
  const Recolouring other = draw_recolouring(40, 0.8, 1.2, -0.2, 0.2, 8);
  EXPECT_EQ(a.scale, b.scale);
  EXPECT_EQ(a.shift, b.shift);
  EXPECT_NE(a.scale, other.scale);
  EXPECT_GE(a.scale.minCoeff(), 0.8);
  EXPECT_LE(a.scale.maxCoeff(), 1.2);
  EXPECT_GE(a.shift.minCoeff(), -0.2);
  EXPECT_LE(a.shift.maxCoeff(), 0.2);
  // Spread over the range, not bunched: 120 draws cover most of it.
  EXPECT_GT(a.scale.maxCoeff() - a.scale.minCoeff(), 0.3);
  EXPECT_GT(a.shift.maxCoeff() - a.shift.minCoeff(), 0.3);
}

}  // namespace
}  // namespace nfield::integrators
