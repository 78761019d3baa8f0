// SPDX-License-Identifier: MIT
//
// Posed images: the bunny_blender set (NeRF-synthetic layout) read end to end, training
// batches drawn from it, and every kind of broken transforms.json rejected with its key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>

#include "integrators/multiview_dataset.h"
#include "integrators/ray_batch.h"
#include "integrators/scene_box.h"
#include "io/png_image.h"
#include "tests/testing/scratch.h"

namespace nfield::integrators {
namespace {
namespace fs = std::filesystem;

fs::path bunny(const std::string& split) {
  return fs::path(NFIELD_SOURCE_DIR) / "data" / "multiview" / "bunny_blender" /
         ("transforms_" + split + ".json");
}

TEST(BunnyBlender, FramesIntrinsicsAndPoses) {
  const auto train = read_transforms(bunny("train"));
  const auto test = read_transforms(bunny("test"));
  EXPECT_EQ(train.frames.size(), 40U);
  EXPECT_EQ(test.frames.size(), 8U);
  for (const auto* data : {&train, &test}) {
    const Intrinsics& k = data->intrinsics;
    EXPECT_EQ(k.width, 128);
    EXPECT_EQ(k.height, 128);
    // 0.5·128 / tan(20°) = 175.84 (SOURCES.md of the shared set rounds it to 175.85).
    EXPECT_NEAR(k.fx, 175.85, 0.015);
    EXPECT_NEAR(k.fx, 64 / std::tan(0.5 * 0.6981316804885864), 1e-9);
    EXPECT_EQ(k.fy, k.fx);
    EXPECT_EQ(k.cx, 64.0);
    EXPECT_EQ(k.cy, 64.0);
    for (const PosedImage& frame : data->frames) {
      EXPECT_EQ(frame.rgb.rows(), 128 * 128);
      EXPECT_EQ(frame.alpha.size(), 128 * 128);
      EXPECT_NEAR(frame.camera.centre().norm(), 2.0, 1e-5) << frame.path;
      // The ray through the image centre points at the origin, within a pixel's angle.
      const Eigen::Vector3d d = frame.camera.direction(k.cx, k.cy).normalized();
      const double angle = std::acos(std::clamp(d.dot(-frame.camera.centre().normalized()), -1.0, 1.0));
      EXPECT_LT(angle, 1.0 / k.fx) << frame.path;
    }
  }
  EXPECT_EQ(train.frames[3].path.filename(), "r_003.png");  // ".png" appended
}

TEST(BunnyBlender, RaysThroughTheBunnyMeetItsBox) {
  // Pins the pixel conventions (row 0 at the top, +y up, −z forward): every ray through a
  // covered pixel (alpha > 0.5) meets the mesh's bounding box, a little enlarged.
  const auto data = read_transforms(bunny("test"));
  const SceneBox box{Eigen::Vector3d(-0.52, -0.51, -0.41), Eigen::Vector3d(0.52, 0.51, 0.41)};
  Eigen::Index covered = 0, missed = 0;
  for (int f = 0; f < static_cast<int>(data.frames.size()); ++f) {
    const auto batch = frame_pixels<double>(data, f);
    for (Eigen::Index n = 0; n < batch.rays.size(); ++n) {
      if (batch.alpha(n) <= 0.5) continue;
      ++covered;
      const auto [enter, exit] = box.intersect(batch.rays.origins.row(n).transpose(),
                                               batch.rays.directions.row(n).transpose());
      missed += !(enter <= exit && exit > 0);
    }
  }
  EXPECT_GT(covered, 8 * 1000);
  EXPECT_EQ(missed, 0);
}

TEST(BunnyBlender, BackgroundsDifferOnlyWhereAlphaIsBelowOne) {
  const auto white = read_transforms(bunny("test"), {.background = Eigen::Vector3d(1, 1, 1)});
  const auto black = read_transforms(bunny("test"), {.background = Eigen::Vector3d(0, 0, 0)});
  Eigen::Index opaque = 0, transparent = 0;
  for (size_t f = 0; f < white.frames.size(); ++f) {
    const auto& w = white.frames[f];
    const auto& b = black.frames[f];
    ASSERT_EQ(w.alpha, b.alpha);
    for (Eigen::Index p = 0; p < w.alpha.size(); ++p) {
      const float a = w.alpha(p);
      if (a == 1.f) {
        ++opaque;
        ASSERT_EQ(w.rgb.row(p), b.rgb.row(p)) << "frame " << f << " pixel " << p;
      } else {
        ++transparent;
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(w.rgb(p, k) - b.rgb(p, k), 1 - a, 1e-6);
      }
    }
  }
  EXPECT_GT(opaque, 1000);
  EXPECT_GT(transparent, 1000);
}

TEST(BunnyBlender, RandomPixelBatches) {
  const auto data = read_transforms(bunny("train"));
  std::mt19937_64 rng(7), same(7);
  const auto batch = sample_pixels<float>(data, 4096, rng);
  const auto again = sample_pixels<float>(data, 4096, same);
  EXPECT_EQ(batch.pixel, again.pixel);
  EXPECT_EQ(batch.frame, again.frame);
  EXPECT_EQ(batch.rays.directions, again.rays.directions);
  EXPECT_GE(batch.frame.minCoeff(), 0);
  EXPECT_LT(batch.frame.maxCoeff(), 40);
  EXPECT_GT(batch.frame.maxCoeff() - batch.frame.minCoeff(), 30);  // spread over the frames
  for (Eigen::Index n = 0; n < 4096; ++n) {
    const auto& frame = data.frames[batch.frame(n)];
    ASSERT_EQ(batch.rgb.row(n), frame.rgb.row(batch.pixel(n)));
    ASSERT_EQ(batch.alpha(n), frame.alpha(batch.pixel(n)));
    ASSERT_NEAR((batch.rays.origins.row(n).cast<double>().transpose() - frame.camera.centre()).norm(), 0, 1e-6);
  }
  // The same pixels on black, from the alpha kept with them.
  const auto black = read_transforms(bunny("train"), {.background = Eigen::Vector3d::Zero()});
  const Eigen::MatrixXf on_black = composite_on<float>(batch, Eigen::RowVector3f::Zero());
  for (Eigen::Index n = 0; n < 4096; ++n)
    ASSERT_LT((on_black.row(n) - black.frames[batch.frame(n)].rgb.row(batch.pixel(n))).cwiseAbs().maxCoeff(), 1e-6);
}

// --- broken files --------------------------------------------------------------------------

class BrokenTransforms : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testutil::scratch_dir("integrators");
    write_image("a.png", 4, 4);
    write_image("b.png", 4, 4);
    write_image("wide.png", 5, 4);
  }
  void write_image(const std::string& name, int width, int height) {
    io::Image image{width, height, 4, Eigen::MatrixXf::Constant(Eigen::Index{width} * height, 4, 0.5f)};
    io::write_png(dir_ / name, image);
  }
  // A valid file with two frames, a.png and b.png, with `replace` applied.
  std::string valid() const {
    return R"({
  "camera_angle_x": 0.7,
  "frames": [
    {"file_path": "a", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,2],[0,0,0,1]]},
    {"file_path": "./b.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,3],[0,0,0,1]]}
  ]
})";
  }
  static std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  }
  // Writes `text` as transforms.json and expects a DatasetError naming the file and holding
  // every one of `parts`.
  void expect_error(const std::string& text, std::initializer_list<std::string> parts) {
    const fs::path json = dir_ / "transforms.json";
    std::ofstream(json, std::ios::binary) << text;
    expect_error_at(json, parts);
  }
  void expect_error_at(const fs::path& json, std::initializer_list<std::string> parts) {
    try {
      read_transforms(json);
      ADD_FAILURE() << "no error from " << json << ", expected " << *parts.begin();
    } catch (const DatasetError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(json.string()), std::string::npos) << message;
      for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    }
  }
  fs::path dir_;
};

TEST_F(BrokenTransforms, TheValidFileReads) {
  std::ofstream(dir_ / "transforms.json") << valid();
  const auto data = read_transforms(dir_ / "transforms.json", {.background = Eigen::Vector3d(0, 0, 0)});
  ASSERT_EQ(data.frames.size(), 2U);
  EXPECT_NEAR(data.frames[0].rgb(0, 0), 0.5f * 0.5f, 2.5e-3f);  // 8-bit 0.5, alpha 0.5, on black
  EXPECT_NEAR(data.frames[0].alpha(0), 0.5f, 2.5e-3f);
  static_assert(std::is_base_of_v<std::runtime_error, DatasetError>);
}

TEST_F(BrokenTransforms, MissingFile) {
  expect_error_at(dir_ / "absent.json", {"no such file"});
}

TEST_F(BrokenTransforms, MalformedJsonSaysWhere) {
  expect_error(replaced(valid(), R"("file_path": "a",)", R"("file_path": "a",,)"),
               {"transforms.json:4:23: malformed JSON: syntax error while parsing object key"});
}

TEST_F(BrokenTransforms, MissingOrMistypedKeys) {
  expect_error(replaced(valid(), R"("camera_angle_x": 0.7,)", ""), {"camera_angle_x: missing"});
  expect_error(replaced(valid(), "0.7", R"("wide")"), {"camera_angle_x: expected a number, got string"});
  expect_error(replaced(valid(), "0.7", "4"), {"camera_angle_x", "must be in (0, pi)"});
  expect_error("[1, 2]", {"(root): expected an object, got array"});
  expect_error(R"({"camera_angle_x": 0.7})", {"frames: missing"});
  expect_error(R"({"camera_angle_x": 0.7, "frames": {}})", {"frames: expected an array, got object"});
  expect_error(R"({"camera_angle_x": 0.7, "frames": []})", {"frames: no frames"});
  expect_error(replaced(valid(), R"({"file_path": "./b.png", )", R"({"path": "./b.png", )"),
               {"frames[1].file_path: missing"});
  expect_error(replaced(valid(), R"("file_path": "a")", R"("file_path": 5)"),
               {"frames[0].file_path: expected a string, got number"});
  expect_error(replaced(valid(), R"("./b.png", "transform_matrix")", R"("./b.png", "matrix")"),
               {"frames[1].transform_matrix: missing"});
  expect_error(replaced(valid(), "[0,0,1,3]", R"([0,"zero",1,3])"),
               {"frames[1].transform_matrix[2][1]: expected a number, got string"});
}

TEST_F(BrokenTransforms, BadMatrices) {
  expect_error(replaced(valid(), "[[1,0,0,0],[0,1,0,0],[0,0,1,2],[0,0,0,1]]", "[[1,0,0,0],[0,1,0,0],[0,0,1,2]]"),
               {"frames[0].transform_matrix: expected 4 rows, got 3"});
  expect_error(replaced(valid(), "[0,1,0,0],[0,0,1,2]", "[0,1,0],[0,0,1,2]"),
               {"frames[0].transform_matrix[1]: expected 4 numbers, got 3"});
  // JSON has no NaN or infinity; a number beyond double's range is the one way in.
  expect_error(replaced(valid(), "[0,0,1,2]", "[0,0,1,1e999]"),
               {"transforms.json:4:72: malformed JSON: number overflow parsing '1e999' (not a finite number)"});
  expect_error(replaced(valid(), "[0,0,1,3],[0,0,0,1]", "[0,0,1,3],[0,0,1,1]"),
               {"frames[1].transform_matrix[3]: must be [0, 0, 0, 1]"});
  expect_error(replaced(valid(), "[[1,0,0,0],[0,1,0,0],[0,0,1,2]", "[[2,0,0,0],[0,1,0,0],[0,0,1,2]"),
               {"frames[0].transform_matrix: the upper-left 3 x 3 block must be a rotation"});
}

TEST_F(BrokenTransforms, Images) {
  expect_error(replaced(valid(), R"("./b.png")", R"("c")"), {"frames[1].file_path", "c.png", "no such file"});
  expect_error(replaced(valid(), R"("./b.png")", R"("wide.png")"),
               {"frames[1].file_path", "wide.png' is 5x4 pixels, expected 4x4 (the size of frames[0])"});
  expect_error(replaced(valid(), R"("camera_angle_x": 0.7,)", R"("camera_angle_x": 0.7, "w": 5, "h": 4,)"),
               {"frames[0].file_path", "a.png' is 4x4 pixels, expected 5x4 (w and h of the file)"});
  std::ofstream(dir_ / "text.png") << "not a png";
  expect_error(replaced(valid(), R"("./b.png")", R"("text.png")"), {"frames[1].file_path", "not a PNG"});
}

TEST_F(BrokenTransforms, ExplicitIntrinsics) {
  std::ofstream(dir_ / "transforms.json")
      << replaced(valid(), R"("camera_angle_x": 0.7,)", R"("fl_x": 3.5, "cx": 1.75, "w": 4, "h": 4,)");
  const auto data = read_transforms(dir_ / "transforms.json");
  EXPECT_EQ(data.intrinsics.fx, 3.5);
  EXPECT_EQ(data.intrinsics.fy, 3.5);
  EXPECT_EQ(data.intrinsics.cx, 1.75);
  EXPECT_EQ(data.intrinsics.cy, 2.0);
  expect_error(replaced(valid(), R"("camera_angle_x": 0.7,)", R"("fl_x": -1,)"), {"fl_x = -1: must be > 0"});
  expect_error(replaced(valid(), R"("camera_angle_x": 0.7,)", R"("camera_angle_x": 0.7, "w": 4.5,)"),
               {"w = 4.5", "whole number"});
}

}  // namespace
}  // namespace nfield::integrators
