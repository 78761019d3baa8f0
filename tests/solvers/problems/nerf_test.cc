// SPDX-License-Identifier: MIT
//
// problem: nerf. The ray residual's adjoint (volume rendering and the output activations)
// against central differences, the same rows whatever block a ray falls in, a short training
// run that lowers the loss and writes test views, and config and data errors that name the
// file, line and key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "autodiff/sequential.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/run/run.h"
#include "tests/testing/best_constant.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/ray_residual_checks.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

const std::filesystem::path kBunny = std::filesystem::path(NFIELD_SOURCE_DIR) / "data/multiview/bunny_blender";

std::string nerf_config(const std::string& data, const std::string& extra = "") {
  return "problem: nerf\n"
         "data:\n" + data +
         "scene: {lower: [-0.6, -0.6, -0.6], upper: [0.6, 0.6, 0.6]}\n"
         "render: {samples: 16}\n"
         "field: {type: nerf, hidden: [32, 32], color_hidden: [16], encoding: {type: positional, frequencies: 6}}\n"
         "training:\n"
         "  batch: {rays: 256}\n"
         "  stages: [{optimizer: adam, steps: 60, lr: 5.0e-3}]\n" + extra;
}

std::string bunny_data(bool test = false) {
  std::string s = "  train: " + (kBunny / "transforms_train.json").string() + "\n";
  if (test) s += "  test: " + (kBunny / "transforms_test.json").string() + "\n";
  return s;
}

TEST(Nerf, RayResidualAdjointMatchesCentralDifferences) {
  const auto config = testutil::write_config("nerf", nerf_config(bunny_data(), "output: {dir: unused}\n"));
  const RunSetup setup = load_run(config, {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 1u);
  Random rng(3);
  const TermPoints points = terms[0].sample(rng, 12);
  ASSERT_EQ(points.groups.size(), 13u);
  ASSERT_EQ(points.x.cols(), 6);
  ASSERT_GT(points.x.rows(), 12 * 8);  // most rays cross the scene box
  const auto residual = terms[0].residual(points);

  std::mt19937_64 engine(5);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(6));
  const Streams<double> out = testutil::random_streams(points.x.rows(), 1, 4, 4.0, engine);
  testutil::expect_ray_residual_adjoint(*residual, layout, out, points.groups, 5, engine);
}

// Hierarchical sampling: each ray that crosses the box gets its stratified samples and
// `importance` more where the current field puts its weight, in order along the ray.
TEST(Nerf, ImportanceSamplesFollowTheFieldsWeights) {
  std::string text = nerf_config(bunny_data(), "output: {dir: unused}\n");
  text.replace(text.find("render: {samples: 16}"), 21, "render: {samples: 16, importance: 8}");
  RunSetup setup = load_run(testutil::write_config("nerf", text), {});
  // A field that is dense only in the slab |x| < 0.05: the fine samples gather there.
  Solution slab;
  slab.values = [](const Eigen::MatrixXd& x) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), 4);
    out.col(0) = (x.col(0).array().abs() < 0.05).select(Eigen::VectorXd::Constant(x.rows(), 5.0),
                                                         Eigen::VectorXd::Constant(x.rows(), -20.0));
    return out;
  };
  Random rng(7);
  auto* sampling = capability<SamplesWithSolution>(*setup.problem);
  ASSERT_NE(sampling, nullptr);
  sampling->before_step(0, slab, rng);
  const TermPoints points = setup.problem->loss_terms()[0].sample(rng, 32);
  int crossing = 0, in_slab = 0, fine_total = 0;
  for (size_t r = 0; r + 1 < points.groups.size(); ++r) {
    const Eigen::Index n = points.groups[r + 1] - points.groups[r];
    ASSERT_TRUE(n == 0 || n == 24) << "ray " << r << " has " << n << " samples";
    if (n == 0) continue;
    ++crossing;
    const Eigen::MatrixXd ray = points.x.middleRows(points.groups[r], n);
    // In order along the ray: the distance from the first sample grows.
    for (Eigen::Index i = 1; i < n; ++i)
      EXPECT_GE((ray.row(i).head(3) - ray.row(0).head(3)).norm(),
                (ray.row(i - 1).head(3) - ray.row(0).head(3)).norm() - 1e-12);
    for (Eigen::Index i = 0; i < n; ++i) in_slab += std::abs(ray(i, 0)) < 0.05;
    fine_total += 8;
  }
  ASSERT_GT(crossing, 16);
  // 16 stratified samples put about 1.3 per ray in the slab; the 8 fine ones go there too
  // where the ray meets it.
  EXPECT_GT(in_slab, fine_total / 2) << crossing << " rays";
  std::string with_grid = nerf_config(bunny_data());
  with_grid.replace(with_grid.find("render: {samples: 16}"), 21,
                    "render: {importance: 4, occupancy: {resolution: 8}}");
  testutil::expect_located_error(testutil::write_config("nerf", with_grid),
                                 {5, 22, "render.importance", "occupancy"});
}

// Sampling is a pure function of the engine and the problem's state: the occupancy grid
// changes only in before_step (on the first call and every `every` steps), never in a draw.
TEST(Nerf, DrawsArePureBetweenGridUpdates) {
  std::string text = nerf_config(bunny_data(), "output: {dir: unused}\n");
  text.replace(text.find("render: {samples: 16}"), 21, "render: {occupancy: {resolution: 8, every: 4, decay: 0}}");
  RunSetup setup = load_run(testutil::write_config("nerf_pure", text), {});
  auto* sampling = capability<SamplesWithSolution>(*setup.problem);
  ASSERT_NE(sampling, nullptr);
  double inside = 5;  // the density (before its activation) in the ball |x| < 0.3; −20 outside
  Solution field;
  field.values = [&inside](const Eigen::MatrixXd& x) {
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), 4);
    out.col(0) = (x.leftCols(3).rowwise().norm().array() < 0.3)
                     .select(Eigen::VectorXd::Constant(x.rows(), inside), Eigen::VectorXd::Constant(x.rows(), -20.0));
    return out;
  };
  const LossTerm term = setup.problem->loss_terms()[0];
  const auto draw = [&term](std::uint64_t seed) {
    Random rng(seed);
    return term.sample(rng, 64);
  };
  Random unused(1);
  sampling->before_step(0, field, unused);  // the first call builds the grid: a ball of σ > 0
  const TermPoints first = draw(11), again = draw(11);
  ASSERT_GT(first.x.rows(), 0);
  EXPECT_EQ(first.x, again.x);
  EXPECT_EQ(first.groups, again.groups);
  // Samples only inside the occupied ball's cells (8³ cells of 0.15: within 0.3 + a cell's diagonal).
  EXPECT_LT(first.x.leftCols(3).rowwise().norm().maxCoeff(), 0.3 + 0.27);
  // The field empties; steps 1 and 3 are not updates (every: 4): the draws stay the same.
  inside = -20;
  sampling->before_step(1, field, unused);
  EXPECT_EQ(draw(11).x, first.x);
  sampling->before_step(3, field, unused);
  EXPECT_EQ(draw(11).x, first.x);
  sampling->before_step(4, field, unused);  // an update (decay 0: the grid holds the new field only)
  EXPECT_NE(draw(11).x.rows(), first.x.rows());
}

TEST(Nerf, ShortTrainingLowersTheLossAndWritesTestViews) {
  const auto dir = testutil::scratch_dir("nerf");
  const auto config = testutil::write_config(
      "nerf_run", nerf_config(bunny_data(true), "output: {dir: " + dir.string() + "}\n"));
  RunSetup setup = load_run(config, {});
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  // The first step's loss is 0.24 from a fresh field; 60 steps bring it to 0.045.
  EXPECT_LT(metrics["loss"].get<double>(), 0.08);
  const double constant = testutil::best_constant_psnr_mean(kBunny / "transforms_test.json");
  std::printf("test views: PSNR %.2f dB, best constant %.2f dB\n", metrics["psnr_mean"].get<double>(), constant);
  // 18.55 dB over a best constant of 13.96 dB in a 2-thread run (4.6 dB).
  EXPECT_GT(metrics["psnr_mean"].get<double>(), constant + 3.0);
  EXPECT_GT(metrics["ssim_mean"].get<double>(), 0.6);
  // The halves' PSNRs (NeRF-W's protocol scores right halves): a view's squared error is the
  // mean of its halves', so its PSNR is at most the worse half's + 10·log10(2) dB, and at
  // most the halves' mean (log is concave); so are the means over the views.
  const double left = metrics["psnr_left_half_mean"].get<double>(), right = metrics["psnr_right_half_mean"].get<double>();
  EXPECT_GT(std::min(left, right), constant);
  EXPECT_LE(metrics["psnr_mean"].get<double>(), std::min(left, right) + 10 * std::log10(2.0) + 1e-9);
  EXPECT_LE(metrics["psnr_mean"].get<double>(), 0.5 * (left + right) + 1e-9);
  for (const char* suffix : {"render", "truth", "error", "depth", "opacity"})
    EXPECT_TRUE(std::filesystem::exists(dir / "test_views" / (std::string("test_007_") + suffix + ".png"))) << suffix;
  const io::Image render = io::read_png(dir / "test_views/test_000_render.png");
  EXPECT_EQ(render.width, 128);
  EXPECT_EQ(render.height, 128);
  EXPECT_FALSE(std::filesystem::exists(dir / "solution.vti"));
  for (const char* file : {"density.vti", "surface.vtp", "surface.ply", "checkpoint.h5"})
    EXPECT_TRUE(std::filesystem::exists(dir / file)) << file;

  // nfield render: a turntable, and the test cameras (whose images give PSNRs).
  RenderRequest turntable;
  turntable.turntable_frames = 3;
  render_checkpoint(dir / "checkpoint.h5", turntable, dir / "turntable");
  const io::Image frame = io::read_png(dir / "turntable/turntable_002_render.png");
  EXPECT_EQ(frame.width, 128);
  EXPECT_FALSE(std::filesystem::exists(dir / "turntable/turntable_003_render.png"));
  // The bunny is in the middle of every turntable frame, not at its corners.
  const auto pixel = [&](int r, int c) { return frame.pixels.row(r * 128 + c).head(3).mean(); };
  EXPECT_LT(pixel(64, 64), 0.95f);
  EXPECT_GT(pixel(2, 2), 0.9f);
  RenderRequest poses;
  poses.poses = kBunny / "transforms_test.json";
  render_checkpoint(dir / "checkpoint.h5", poses, dir / "views");
  EXPECT_TRUE(std::filesystem::exists(dir / "views/view_007_error.png"));
}

// mip-NeRF's integrated positional encoding: the points are [mean, d, variance] of each
// sample's frustum Gaussian (a pixel's cone, one interval long), the field trains on them,
// and `nfield render` renders its checkpoint.
std::string with_encoding(std::string text, const std::string& encoding) {
  const std::string plain = "encoding: {type: positional, frequencies: 6}";
  return text.replace(text.find(plain), plain.size(), "encoding: " + encoding);
}

TEST(Nerf, IntegratedPositionalEncodingTrainsOnFrustums) {
  const auto dir = testutil::scratch_dir("nerf_mip");
  const std::string text = with_encoding(nerf_config(bunny_data(true), "output: {dir: " + dir.string() + "}\n"),
                                         "{type: integrated_positional, frequencies: 6}");
  RunSetup setup = load_run(testutil::write_config("nerf_mip", text), {});
  ASSERT_EQ(setup.problem->field_input_dim(), 9);
  ASSERT_EQ(setup.field.input_dim, 9);
  Random rng(3);
  const TermPoints points = setup.problem->loss_terms()[0].sample(rng, 16);
  ASSERT_EQ(points.x.cols(), 9);
  ASSERT_GT(points.x.rows(), 16 * 8);
  // A 128² view of the bunny from about 4 units: a pixel's cone is some 1e-2 wide there, an
  // interval (1.2·√3/16) 0.13 long, so σ² across ~ 1e-5 and along ~ 1e-3.
  const Eigen::MatrixXd variances = points.x.rightCols(3);
  EXPECT_GT(variances.minCoeff(), 1e-7);
  EXPECT_LT(variances.maxCoeff(), 1e-2);
  for (Eigen::Index i = 0; i < points.x.rows(); ++i) EXPECT_NEAR(points.x.row(i).segment(3, 3).norm(), 1.0, 1e-12);
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  EXPECT_LT(metrics["loss"].get<double>(), 0.08);
  const double constant = testutil::best_constant_psnr_mean(kBunny / "transforms_test.json");
  std::printf("test views: PSNR %.2f dB, best constant %.2f dB\n", metrics["psnr_mean"].get<double>(), constant);
  // 18.74 dB over 13.96 dB in a 2-thread run (4.8 dB).
  EXPECT_GT(metrics["psnr_mean"].get<double>(), constant + 3.0);
  RenderRequest turntable;
  turntable.turntable_frames = 2;
  render_checkpoint(dir / "checkpoint.h5", turntable, dir / "turntable");
  const io::Image frame = io::read_png(dir / "turntable/turntable_001_render.png");
  const auto pixel = [&](int r, int c) { return frame.pixels.row(r * 128 + c).head(3).mean(); };
  EXPECT_LT(pixel(64, 64), 0.95f);
  EXPECT_GT(pixel(2, 2), 0.9f);
}

// Line and column (1-based) of the first `needle` in `text`.
testutil::Located located(const std::string& text, const std::string& needle, const std::string& key,
                          const std::string& part) {
  const std::size_t at = text.find(needle);
  const std::size_t line_start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  return {line, static_cast<int>(at - line_start) + 1, key, part};
}

TEST(Nerf, IntegratedPositionalConfigErrorsAreLocated) {
  auto check = [](const std::string& text, const std::string& needle, const std::string& key,
                  const std::string& part) {
    testutil::expect_located_error(testutil::write_config("nerf_mip", text), located(text, needle, key, part));
  };
  const std::string nerf = nerf_config(bunny_data());
  check(with_encoding(nerf, "{type: integrated_positional, frequencies: 25}"), "25", "field.encoding.frequencies",
        "24");
  check(with_encoding(nerf, "{type: integrated_positional, frequencies: 0}"), "0}", "field.encoding.frequencies",
        "1");
  check(with_encoding(nerf, "{type: integrated_positional, normalize: true}"), "normalize",
        "field.encoding.normalize", "unknown key 'normalize'");
  // A radiance problem gives a variance per position coordinate; an mlp over [x, d] would read six.
  std::string mlp = with_encoding(nerf, "{type: integrated_positional}");
  const std::string nerf_field = "type: nerf, hidden: [32, 32], color_hidden: [16],";
  mlp.replace(mlp.find(nerf_field), nerf_field.size(), "type: mlp, hidden: [32, 32],");
  check(mlp, "integrated_positional", "field.encoding.type", "use field.type: nerf");
  // A problem without variances (Poisson's points are bare coordinates).
  const std::string poisson =
      "problem: poisson\n"
      "domain: {lower: [0, 0], upper: [1, 1]}\n"
      "equation: {source: \"0\"}\n"
      "conditions: [{on: boundary, type: dirichlet, value: \"0\"}]\n"
      "field:\n"
      "  type: mlp\n"
      "  encoding: {type: integrated_positional, frequencies: 4}\n";
  check(poisson, "integrated_positional", "field.encoding.type", "problem 'poisson' gives none");
  // AutoInt's sections are no frustums either.
  check("problem: autoint_1d\n"
        "domain: {lower: [0], upper: [1]}\n"
        "equation: {integrand: \"cos(x)\"}\n"
        "field: {type: mlp, encoding: {type: integrated_positional}}\n",
        "integrated_positional", "field.encoding.type", "gives none");
}

// A copy of the bunny's transforms with `edit` applied, in a scratch folder whose images
// point back at the real ones.
std::filesystem::path edited_transforms(const std::filesystem::path& dir,
                                        const std::function<void(nlohmann::json&)>& edit) {
  std::ifstream in(kBunny / "transforms_train.json");
  nlohmann::json j = nlohmann::json::parse(in);
  for (auto& frame : j["frames"])
    frame["file_path"] = (kBunny / frame["file_path"].get<std::string>()).string();
  edit(j);
  const auto path = dir / "transforms.json";
  std::ofstream(path) << j.dump(1);
  return path;
}

void expect_data_error(const std::filesystem::path& transforms, const std::string& part) {
  const auto config = transforms.parent_path() / "config.yaml";
  std::ofstream(config) << nerf_config("  train: " + transforms.string() + "\n");
  testutil::expect_located_error(config, {3, 10, "data.train", part});
}

TEST(Nerf, DataErrorsNameTheFileAndKey) {
  const auto dir = testutil::scratch_dir("nerf");
  expect_data_error(dir / "missing.json", "missing.json");
  expect_data_error(edited_transforms(dir, [](nlohmann::json& j) { j["frames"] = nlohmann::json::array(); }),
                    "no frames");
  expect_data_error(edited_transforms(dir, [](nlohmann::json& j) { j["frames"][2].erase("transform_matrix"); }),
                    "frames[2].transform_matrix");
  {
    io::Image small;
    small.width = small.height = 64;
    small.channels = 4;
    small.pixels = Eigen::MatrixXf::Constant(64 * 64, 4, 0.5f);
    io::write_png(dir / "small.png", small);
    expect_data_error(edited_transforms(dir, [&](nlohmann::json& j) {
                        j["frames"][1]["file_path"] = (dir / "small.png").string();
                      }),
                      "small.png");
  }
  std::ofstream(dir / "broken.json") << "{\"camera_angle_x\": 0.7, \"frames\": [";
  expect_data_error(dir / "broken.json", "malformed");
  expect_data_error(edited_transforms(dir, [](nlohmann::json& j) {
                      j["frames"][0]["file_path"] = "./no_such_image";
                    }),
                    "no_such_image");
}

TEST(Nerf, ConfigErrorsAreLocated) {
  auto check = [](const std::string& text, const testutil::Located& want) {
    testutil::expect_located_error(testutil::write_config("nerf", text), want);
  };
  check(nerf_config(bunny_data() + "  background: green\n"), {4, 15, "data.background", "white"});
  std::string bad_render = nerf_config(bunny_data());
  bad_render.replace(bad_render.find("render: {samples: 16}"), 21, "render: {samples: 16, sample: 3}");
  check(bad_render, {5, 23, "render.sample", "unknown key 'sample'"});
  std::string flat = nerf_config(bunny_data());
  flat.replace(flat.find("upper: [0.6, 0.6, 0.6]"), 22, "upper: [0.6, -0.6, 0.6]");
  check(flat, {4, 43, "scene.upper", "upper > lower"});
  // A box of +-1e300 has upper > lower yet an infinite diagonal; the mip-NeRF frustums then
  // failed with a NaN deep inside the problem instead of a located error.
  std::string huge = nerf_config(bunny_data());
  huge.replace(huge.find("upper: [0.6, 0.6, 0.6]"), 22, "upper: [0.6, 0.6, 1e300]");
  huge.replace(huge.find("lower: [-0.6, -0.6, -0.6]"), 25, "lower: [-0.6, -0.6, -1e300]");
  check(huge, {4, 45, "scene.upper", "diagonal is a finite number"});
}

}  // namespace
}  // namespace nfield::solvers
