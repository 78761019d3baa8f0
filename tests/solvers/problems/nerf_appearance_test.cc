// SPDX-License-Identifier: MIT
//
// NeRF in the Wild's appearance codes (problem: nerf with data.appearance; issue 28 item 6):
// every training image is an instance of a family, every test image a held-out one whose code
// is fitted on its left half only; a short auto-decoder run learns codes that the held-out
// fits improve on, writes them in the checkpoint, and `nfield render --code` picks and blends
// them. Config errors name their key.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "integrators/multiview_dataset.h"
#include "io/hdf5_file.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/run/run.h"
#include "solvers/sampling/random.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
const fs::path kBunny = fs::path(NFIELD_SOURCE_DIR) / "data/multiview/bunny_blender";

// The first `frames` frames of the bunny's `split` set, their images named by absolute paths.
fs::path subset(const fs::path& dir, const std::string& split, int frames) {
  std::ifstream in(kBunny / ("transforms_" + split + ".json"));
  nlohmann::json j = nlohmann::json::parse(in);
  nlohmann::json kept = nlohmann::json::array();
  for (int k = 0; k < frames; ++k) {
    nlohmann::json frame = j["frames"][k];
    frame["file_path"] = (kBunny / frame["file_path"].get<std::string>()).lexically_normal().string();
    kept.push_back(frame);
  }
  j["frames"] = kept;
  const fs::path path = dir / (split + ".json");
  std::ofstream(path) << j.dump(1);
  return path;
}

// Line 4 is data.recolour, 5 data.appearance, 8 render, 9 field.
std::string appearance_config(const fs::path& dir, const std::string& render = "{samples: 16}",
                              const std::string& field_extra = ", latent: {size: 4}",
                              const std::string& appearance = "true") {
  return "problem: nerf\n"
         "data:\n"
         "  train: " + subset(dir, "train", 6).string() + "\n"
         "  recolour: {scale: [0.6, 1.4], shift: [-0.3, 0.3], seed: 3}\n"
         "  appearance: " + appearance + "\n"
         "  test: " + subset(dir, "test", 2).string() + "\n"
         "scene: {lower: [-0.6, -0.6, -0.6], upper: [0.6, 0.6, 0.6]}\n"
         "render: " + render + "\n"
         "field: {type: nerf, hidden: [32, 32], color_hidden: [16]" + field_extra +
         ", encoding: {type: positional, frequencies: 6}}\n"
         "training:\n"
         "  threads: 2\n"
         "  batch: {rays: 128}\n"
         "  auto_decoder: {instances_per_step: 3, prior: 1.0e-4, fit_steps: 60, fit_lr: 3.0e-2, interpolation_steps: 2}\n"
         "  stages: [{optimizer: adam, steps: 200, lr: 5.0e-3}]\n"
         "output: {dir: " + (dir / "run").string() + "}\n";
}

TEST(NerfAppearance, EachImageIsAnInstanceAndHeldOutImagesDrawTheirLeftHalves) {
  const fs::path dir = testutil::scratch_dir("nerf_appearance_instances");
  const RunSetup setup = load_run(testutil::write_config("nerf_appearance", appearance_config(dir)), {});
  const auto training = instances(*setup.problem, false), held_out = instances(*setup.problem, true);
  ASSERT_EQ(training.size(), 6U);
  ASSERT_EQ(held_out.size(), 2U);
  EXPECT_EQ(training[4].name, "r_004.png");
  const integrators::MultiviewDataset test = integrators::read_transforms(dir / "test.json");
  // In the camera's axes (x right) a left-half pixel's ray has x < 0: (c + ½ − cx)/fx with c < 64.
  const auto camera_x = [](const ProblemInstance& instance, const integrators::Camera& camera) {
    Random rng(5);
    const TermPoints points = instance.problem->loss_terms().front().sample(rng, 300);
    const Eigen::Matrix3d rotation = camera.camera_to_world.topLeftCorner<3, 3>();
    return Eigen::VectorXd((points.x.middleCols(3, 3) * rotation).col(0));
  };
  for (int k = 0; k < 2; ++k) {
    const Eigen::VectorXd x = camera_x(held_out[static_cast<std::size_t>(k)], test.frames[static_cast<std::size_t>(k)].camera);
    EXPECT_LT(x.maxCoeff(), 0.0) << "held-out image " << k << " drew a ray from its right half";
  }
  const integrators::MultiviewDataset train = integrators::read_transforms(dir / "train.json");
  const Eigen::VectorXd x = camera_x(training[2], train.frames[2].camera);
  EXPECT_LT(x.minCoeff(), 0.0);
  EXPECT_GT(x.maxCoeff(), 0.0);  // a training image draws from all of it
}

TEST(NerfAppearance, CodesFollowTheImagesAndRenderPicksThem) {
  const fs::path dir = testutil::scratch_dir("nerf_appearance_run");
  RunSetup setup = load_run(testutil::write_config("nerf_appearance", appearance_config(dir)), {});
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "run/metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["training_instances"], 6);
  EXPECT_EQ(metrics["held_out_instances"], 2);
  // A held-out image's code, fitted on its left half, lifts its right half's PSNR above the
  // code 0's: the code carries the image's colours, which the halves share.
  for (const auto& h : metrics["held_out"]) {
    std::printf("%s: right half %.2f dB with code 0, %.2f dB fitted\n", h["name"].get<std::string>().c_str(),
                h["psnr_zero_code"].get<double>(), h["psnr_right_half_mean"].get<double>());
    EXPECT_GT(h["psnr_right_half_mean"].get<double>(), h["psnr_zero_code"].get<double>() + 0.5) << h["name"];
  }
  EXPECT_TRUE(fs::exists(dir / "run/held_out/r_001/view/test_000_render.png"));
  EXPECT_TRUE(fs::exists(dir / "run/training/r_000/density.vti"));    // once: no code changes it
  EXPECT_FALSE(fs::exists(dir / "run/training/r_001/density.vti"));
  const io::H5Reader file(dir / "run/checkpoint.h5");
  EXPECT_EQ(file.read_matrix<double>("latent/codes").rows(), 6);
  EXPECT_EQ(file.read_attribute<std::vector<std::string>>("latent/codes", "names").at(5), "r_005.png");

  // nfield render: two images' codes give two colourings of one turntable frame; --to at t = 0
  // is --code alone; an unknown name lists the valid ones.
  RenderRequest turntable;
  turntable.turntable_frames = 1;
  const auto frame = [&](const RenderCode& code, const std::string& folder) {
    render_checkpoint(dir / "run/checkpoint.h5", turntable, dir / folder, code);
    return io::read_png(dir / folder / "turntable_000_render.png").pixels;
  };
  const Eigen::MatrixXf a = frame({"r_001", "", 0.5}, "a"), b = frame({"4", "", 0.5}, "b");
  EXPECT_GT((a - b).cwiseAbs().maxCoeff(), 0.02f);
  EXPECT_EQ(frame({"r_001.png", "r_004", 0.0}, "a0"), a);
  try {
    render_checkpoint(dir / "run/checkpoint.h5", turntable, dir / "bad", {"r_009", "", 0.5});
    ADD_FAILURE() << "rendered with a code the checkpoint does not hold";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--code r_009"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("r_000.png, r_001.png"), std::string::npos) << e.what();
  }
}

TEST(NerfAppearance, ConfigErrorsAreLocated) {
  const fs::path dir = testutil::scratch_dir("nerf_appearance_errors");
  const auto check = [&](const std::string& text, const testutil::Located& want) {
    testutil::expect_located_error(testutil::write_config("nerf_appearance", text), want);
  };
  check(appearance_config(dir, "{samples: 16}", ""), {5, 15, "data.appearance", "field.latent"});
  check(appearance_config(dir, "{samples: 16, occupancy: {resolution: 16}}"), {8, 34, "render.occupancy", "appearance"});
  check(appearance_config(dir, "{samples: 16, importance: 8}"), {8, 35, "render.importance", "appearance"});
  std::string no_test = appearance_config(dir);
  no_test.erase(no_test.find("  test: "), no_test.find("scene:") - no_test.find("  test: "));
  check(no_test, {5, 15, "data.appearance", "data.test"});
  std::string reversed = appearance_config(dir);
  reversed.replace(reversed.find("[0.6, 1.4]"), 10, "[1.4, 0.6]");
  check(reversed, {4, 21, "data.recolour.scale", "lower <= upper"});
  std::string unknown = appearance_config(dir);
  unknown.replace(unknown.find("seed: 3"), 7, "sed: 3");
  check(unknown, {4, 53, "data.recolour.sed", "unknown key"});
}

}  // namespace
}  // namespace nfield::solvers
