// SPDX-License-Identifier: MIT
//
// nfield run on the shipped ACORN config (configs/fit_image_acorn_small.yaml), small: the
// blocks are reallocated, blocks.vtp and the tree in the checkpoint agree with metrics.json,
// a run interrupted and resumed ends bit for bit where an uninterrupted one does (the tree
// and the sampler's engine are in the checkpoint), and every acorn key refuses a bad value
// with exit 2, one line naming the key, and nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_test_support.h"
#include "io/hdf5_file.h"
#include "io/vtk_polydata.h"

namespace nfield::apps::testing {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(read_text(path)); }

std::vector<std::string> small_run(const std::filesystem::path& out, int steps) {
  return {"run", NFIELD_SOURCE_DIR "/configs/fit_image_acorn_small.yaml", "--out", out.string(),
          "--set", "equation.crop=64", "--set", "field.max_blocks=40", "--set", "field.allocate_every=10",
          "--set", "field.encoder_hidden=[32]", "--set", "training.batch.interior=2048",
          "--set", "training.threads=2", "--set", "training.log_every=1", "--set", "training.checkpoint_every=0",
          "--set", "training.stages=[{optimizer: adam, steps: " + std::to_string(steps) + ", lr: 2.0e-3}]"};
}

TEST(AcornRunTest, ReallocatesWritesItsBlocksAndResumes) {
  const auto dir = scratch_dir();
  Outcome o = run_nfield(small_run(dir / "first", 1), dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  o = run_nfield(small_run(dir / "straight", 45), dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json first = read_json(dir / "first" / "metrics.json");
  const nlohmann::json straight = read_json(dir / "straight" / "metrics.json");
  EXPECT_LT(straight["loss"].get<double>(), 0.5 * first["loss"].get<double>());
  EXPECT_GT(straight["acorn_splits"].get<double>(), 0);  // the blocks moved
  EXPECT_LE(straight["acorn_blocks"].get<double>(), 40);
  EXPECT_NE(o.out.find("blocks "), std::string::npos) << "no block count in the progress lines";
  {
    // Four corners, two triangles and four edges a block; its level and error on its corners.
    const io::PolyData blocks = io::read_vtp(dir / "straight" / "blocks.vtp");
    const auto count = static_cast<Eigen::Index>(straight["acorn_blocks"].get<double>());
    EXPECT_EQ(blocks.points.rows(), 4 * count);
    EXPECT_EQ(blocks.triangles.rows(), 2 * count);
    EXPECT_EQ(blocks.lines.rows(), 4 * count);
    ASSERT_TRUE(blocks.arrays.count("level") && blocks.arrays.count("error"));
    EXPECT_GT(blocks.arrays.at("level").maxCoeff(), 2);
    EXPECT_GT(blocks.arrays.at("error").maxCoeff(), 0);
    // The blocks cover the picture's box [−1, 1]² and nothing else: their areas add up to 4.
    double area = 0;
    for (Eigen::Index t = 0; t < blocks.triangles.rows(); ++t) {
      const Eigen::Vector2d a = blocks.points.row(blocks.triangles(t, 0)).head<2>();
      const Eigen::Vector2d b = blocks.points.row(blocks.triangles(t, 1)).head<2>();
      const Eigen::Vector2d c = blocks.points.row(blocks.triangles(t, 2)).head<2>();
      area += 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    }
    EXPECT_NEAR(area, 4.0, 1e-9);
  }
  {
    const io::H5Reader checkpoint(dir / "straight" / "checkpoint.h5");
    const auto levels = checkpoint.read_attribute<std::vector<std::int64_t>>("field", "acorn_block_level");
    EXPECT_EQ(static_cast<double>(levels.size()), straight["acorn_blocks"].get<double>());
    EXPECT_GT(*std::max_element(levels.begin(), levels.end()), 2);  // split below the start
  }

  // Interrupted after step 23 (two allocations done), then resumed.
  const Interrupted stop = interrupt_after_step(small_run(dir / "interrupted", 45), dir, dir / "stderr.txt", 23);
  ASSERT_TRUE(stop.signalled);
  ASSERT_EQ(stop.outcome.code, 130) << describe(stop.outcome);
  std::vector<std::string> resumed = small_run(dir / "resumed", 45);
  resumed.insert(resumed.end(), {"--resume", (dir / "interrupted" / "checkpoint.h5").string()});
  o = run_nfield(resumed, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json again = read_json(dir / "resumed" / "metrics.json");
  EXPECT_EQ(again["losses"], straight["losses"]);
  EXPECT_EQ(again["psnr_db"], straight["psnr_db"]);
  EXPECT_EQ(again["acorn_blocks"], straight["acorn_blocks"]);
  const io::H5Reader a(dir / "straight" / "checkpoint.h5"), b(dir / "resumed" / "checkpoint.h5");
  EXPECT_EQ(a.read_attribute<std::vector<std::int64_t>>("field", "acorn_block_index"),
            b.read_attribute<std::vector<std::int64_t>>("field", "acorn_block_index"));
  EXPECT_EQ(a.read_vector<double>("field/encoding_parameters"), b.read_vector<double>("field/encoding_parameters"));
}

TEST(AcornRunTest, EveryKeyRefusesABadValue) {
  const auto dir = scratch_dir();
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"features", "0"},          {"grid", "1"},           {"encoder_hidden", "[]"},
      {"encoder_octaves", "17"},  {"initial_level", "6"},  {"max_level", "11"},
      {"max_blocks", "3"},        {"allocate_every", "-1"}, {"split_factor", "1.5"},
      {"freeze_below", "-1"}};
  for (const auto& [key, value] : bad) {
    SCOPED_TRACE(key + " = " + value);
    std::vector<std::string> args = small_run(dir / "bad", 1);
    args.insert(args.end(), {"--set", "field." + key + "=" + value});
    const Outcome o = run_nfield(args, dir, dir / "capture");
    EXPECT_EQ(o.code, 2) << describe(o);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_NE(o.err.find("field." + key), std::string::npos) << o.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
  }
  std::vector<std::string> args = small_run(dir / "bad", 1);
  args.insert(args.end(), {"--set", "field.encoding={type: hash_grid}"});
  const Outcome o = run_nfield(args, dir, dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("use identity"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace nfield::apps::testing
