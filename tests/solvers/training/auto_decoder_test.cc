// SPDX-License-Identifier: MIT
//
// Latent codes per instance (fields/latent_code.h, solvers/training/auto_decoder.h,
// solvers/run/latent_run.h): the gradient with respect to a code against central differences
// at a code away from 0; an auto-decoder run over a family of pictures whose codes tell the
// instances apart, a code fit with the field frozen that recovers a training instance's loss
// (and moves nothing but the code); the checkpoint with its table of codes, read back by
// `nfield fit-code`; every new key's errors located. (The derivative streams, per-point
// Jacobians and parameter gradients of latent fields go through the stream harness:
// tests/testing/stream_checks.h's latent cases.)
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "fields/field_io.h"
#include "io/png_image.h"
#include "io/vtk_polydata.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/run/latent_run.h"
#include "solvers/run/run.h"
#include "solvers/training/auto_decoder.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"
#include "tests/testing/sphere_mesh.h"
#include "tests/testing/squares_loss.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
using testutil::expect_located_error;
using testutil::write_config;

// A grey picture: a blob whose place and size depend on k, over a slope.
void write_picture(const fs::path& path, int width, int height, int k) {
  io::Image image{width, height, 1, Eigen::MatrixXf(static_cast<Eigen::Index>(width) * height, 1)};
  const float cx = 0.25f + 0.15f * static_cast<float>(k % 4), cy = 0.3f + 0.2f * static_cast<float>(k % 3);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const float u = (static_cast<float>(c) + 0.5f) / width, v = (static_cast<float>(r) + 0.5f) / height;
      const float blob = std::exp(-((u - cx) * (u - cx) + (v - cy) * (v - cy)) / 0.03f);
      image.pixels(static_cast<Eigen::Index>(r) * width + c) = 0.2f + 0.6f * blob + 0.1f * u;
    }
  io::write_png(path, image);
}

const char* kFamilyConfig = R"yaml(
problem: fit
equation:
  signal: image
  family: {images: pictures, held_out: [d.png]}
field: {type: siren, hidden: [32, 32], latent: {size: 4}}
training:
  precision: double
  threads: 1
  batch: {interior: 256}
  auto_decoder: {instances_per_step: 3, prior: 1.0e-4, init_std: 0.01, fit_steps: 150, fit_lr: 1.0e-2}
  stages: [{optimizer: adam, steps: 400, lr: 2.0e-3, schedule: cosine, lr_final: 1.0e-4}]
output: {dir: out}
)yaml";

fs::path family_folder(const std::string& group) {
  const fs::path config = write_config(group, kFamilyConfig);
  fs::create_directories(config.parent_path() / "pictures");
  for (int k = 0; k < 4; ++k)
    write_picture(config.parent_path() / "pictures" / (std::string(1, static_cast<char>('a' + k)) + ".png"), 16, 16, k);
  return config;
}

TEST(AutoDecoder, CodeGradientMatchesCentralDifferencesAwayFromZero) {
  fields::FieldOptions o;
  o.type = "siren";
  o.input_dim = 2;
  o.output_dim = 2;
  o.hidden = {8, 8};
  o.latent_size = 4;
  fields::Field<double> field(o, {.block_points = 5, .threads = 1});
  ASSERT_GE(field.latent_offset(), 0);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 0.5);
  Eigen::VectorXd code(4);
  for (auto& z : code) z = normal(rng);
  set_code(field, code);
  EXPECT_EQ(code_of(field), code);
  Eigen::MatrixXd x(9, 2);
  for (auto& v : x.reshaped()) v = normal(rng);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  autodiff::Streams<double> out;
  field.evaluate(layout, x, out);
  const testutil::SquaresLoss<double> loss(testutil::SquaresLoss<double>::balanced_weights(out));
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(field.parameter_count());
  field.value_and_gradient(field.parameters().data(), layout, autodiff::Batch<double>{x}, loss, gradient.data());
  const double h = 1e-5;
  for (int j = 0; j < 4; ++j) {
    const auto loss_at = [&](double dz) {
      Eigen::VectorXd z = code;
      z[j] += dz;
      set_code(field, z);
      autodiff::Streams<double> s;
      field.evaluate(layout, x, s);
      return loss.value(s);
    };
    const double fd = (loss_at(h) - loss_at(-h)) / (2 * h);
    EXPECT_NEAR(gradient[field.latent_offset() + j], fd, 1e-7 * std::max(1.0, std::abs(fd))) << "code entry " << j;
  }
  // The code moves the value only: the derivative streams of its columns are 0, so two codes
  // give fields that differ (the value stream) but the network reads them as constants of x.
  set_code(field, code);
  autodiff::Streams<double> a, b;
  field.evaluate(layout, x, a);
  set_code(field, Eigen::VectorXd::Zero(4));
  field.evaluate(layout, x, b);
  EXPECT_GT((a.values() - b.values()).norm(), 1e-3);
}

TEST(AutoDecoder, CodesTellTheInstancesApartAndAFitWithTheFieldFrozenRecoversOne) {
  const fs::path config = family_folder("auto_decoder");
  RunSetup setup = load_run(config, {});
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  ASSERT_EQ(tasks.size(), 3u);
  fields::Field<double> field(setup.field);
  LatentCodes codes = initial_codes(3, 4, setup.training.auto_decoder.init_std, setup.training.seed);
  EXPECT_LT(codes.cwiseAbs().maxCoeff(), 0.06);
  const AutoDecoderResult result = train_auto_decoder(tasks, field, codes, setup.training);
  ASSERT_TRUE(result.finished);
  EXPECT_EQ(result.steps, 400);
  EXPECT_EQ(code_of(field), Eigen::VectorXd::Zero(4));  // the slot is left at the prior's mean

  // Each instance's loss with its own code, and with the others' codes.
  const auto loss_of = [&](std::size_t k, const Eigen::VectorXd& code) {
    set_code(field, code);
    Trainer<double> trainer(*tasks[k].problem, field, setup.training);
    Eigen::VectorXd g(field.parameter_count());
    return trainer.loss_and_gradient_at(field.parameters().data(), g.data());
  };
  for (std::size_t k = 0; k < 3; ++k) {
    const double own = loss_of(k, codes.row(static_cast<Eigen::Index>(k)).transpose());
    for (std::size_t other = 0; other < 3; ++other)
      if (other != k)
        EXPECT_LT(4 * own, loss_of(k, codes.row(static_cast<Eigen::Index>(other)).transpose())) << k << " " << other;
  }

  // Instance 1's code forgotten and fitted again from 0 with the field frozen: the loss
  // comes back to within a small factor of its trained code's, and only the code moved.
  const double prior = setup.training.auto_decoder.prior;
  const Eigen::VectorXd trained = codes.row(1).transpose();
  const double target = loss_of(1, trained) + prior * trained.squaredNorm();
  set_code(field, Eigen::VectorXd::Zero(4));
  const Eigen::VectorXd before = field.parameters();
  const double zero_code = loss_of(1, Eigen::VectorXd::Zero(4));
  const std::vector<double> losses = fit_code(*tasks[1].problem, field, setup.training, 300, 1e-2, false, 11);
  const Eigen::VectorXd fitted = code_of(field);
  const double reached = loss_of(1, fitted) + prior * fitted.squaredNorm();
  EXPECT_GT(zero_code, 4 * target);
  EXPECT_LT(reached, 1.5 * target) << "zero code " << zero_code << ", trained " << target;
  EXPECT_LT(losses.back(), losses.front());
  Eigen::VectorXd moved = field.parameters() - before;
  moved.segment(field.latent_offset(), 4).setZero();
  EXPECT_EQ(moved.cwiseAbs().maxCoeff(), 0.0);
}

// An Adam stage's `seconds` ends an auto-decoder stage as its steps do (a finished run), the
// schedule following the time spent.
TEST(AutoDecoder, ASecondsBudgetEndsTheStage) {
  RunSetup setup = load_run(family_folder("auto_decoder_seconds"),
                            {"training.stages[0].steps=1000000", "training.stages[0].seconds=0.3"});
  fields::Field<double> field(setup.field);
  LatentCodes codes = initial_codes(3, 4, 0.01, 0);
  const auto started = std::chrono::steady_clock::now();
  const AutoDecoderResult result = train_auto_decoder(instances(*setup.problem, false), field, codes, setup.training);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_TRUE(result.finished);
  EXPECT_GT(result.steps, 0);
  EXPECT_LT(result.steps, 1000000);
  EXPECT_GE(wall, 0.3);
  EXPECT_LT(wall, 10.0);
}

TEST(AutoDecoder, RunWritesTheCodesAndFitCodeReadsTheCheckpoint) {
  const fs::path config = family_folder("auto_decoder_run");
  const fs::path dir = config.parent_path();
  RunSetup setup = load_run(config, {"training.stages=[{optimizer: adam, steps: 60, lr: 2.0e-3}]",
                                     "training.auto_decoder.fit_steps=20"},
                            dir / "out");
  ASSERT_EQ(execute_run(setup, {}), 0);
  for (const char* file : {"checkpoint.h5", "config.yaml", "metrics.json", "training/a/reconstruction.png",
                           "training/c/reconstruction.png", "held_out/d/reconstruction.png",
                           "interpolation/0/reconstruction.png", "interpolation/4/reconstruction.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;
  {
    std::ifstream in(dir / "out/metrics.json");
    const nlohmann::json metrics = nlohmann::json::parse(in);
    EXPECT_EQ(metrics["steps"], 60);
    EXPECT_EQ(metrics["training_instances"], 3);
    EXPECT_EQ(metrics["training"].size(), 3u);
    EXPECT_EQ(metrics["training_summary"]["psnr_db"]["count"], 3);
    EXPECT_GT(metrics["training_summary"]["psnr_db"]["mean"].get<double>(), 15.0);
    EXPECT_TRUE(metrics["held_out_summary"].contains("psnr_zero_code"));
    ASSERT_EQ(metrics["held_out"].size(), 1u);
    EXPECT_EQ(metrics["held_out"][0]["name"], "d.png");
    EXPECT_TRUE(metrics["held_out"][0].contains("psnr_db"));
    EXPECT_TRUE(metrics["held_out"][0].contains("psnr_zero_code"));
  }
  const io::H5Reader file(dir / "out/checkpoint.h5");
  const Eigen::MatrixXd codes = file.read_matrix<double>("latent/codes");
  EXPECT_EQ(codes.rows(), 3);
  EXPECT_EQ(codes.cols(), 4);
  EXPECT_EQ(file.read_attribute<std::vector<std::string>>("latent/codes", "names"),
            (std::vector<std::string>{"a.png", "b.png", "c.png"}));
  EXPECT_GT(codes.cwiseAbs().maxCoeff(), 0.0);
  // The field round-trips with its code slot (fields/field_io.h: latent_code).
  const fields::Field<double> loaded = fields::load_field<double>(file);
  EXPECT_EQ(loaded.latent_size(), 4);
  EXPECT_TRUE(file.has_dataset("field/latent_code"));
  // A code through the field's own passes equals the table's row written into the slot.
  fields::Field<double> with_code = loaded.cast<double>();
  set_code(with_code, codes.row(2).transpose());
  EXPECT_EQ(code_of(with_code), Eigen::VectorXd(codes.row(2).transpose()));

  // nfield fit-code: the held-out picture's code, the field frozen; and fine-tuned.
  RunSetup fit = load_run(config, {}, dir / "fit");
  ASSERT_EQ(fit_codes(dir / "out/checkpoint.h5", fit, {.fine_tune = false, .steps = 30, .lr = 1e-2}), 0);
  const io::H5Reader fitted(dir / "fit/checkpoint.h5");
  EXPECT_EQ(fitted.read_matrix<double>("latent/codes").rows(), 1);
  EXPECT_EQ(fitted.read_attribute<std::vector<std::string>>("latent/codes", "names"), (std::vector<std::string>{"d.png"}));
  EXPECT_EQ(fields::load_field<double>(fitted).parameters(), loaded.parameters());  // frozen
  EXPECT_TRUE(fs::exists(dir / "fit/d/reconstruction.png"));
  std::ifstream in(dir / "fit/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_GT(metrics["summary"]["psnr_db"]["mean"].get<double>(), metrics["summary"]["psnr_zero_code"]["mean"].get<double>());
  RunSetup tune = load_run(config, {}, dir / "tune");
  ASSERT_EQ(fit_codes(dir / "out/checkpoint.h5", tune, {.fine_tune = true, .steps = 30, .lr = 1e-3}), 0);
  EXPECT_NE(fields::load_field<double>(io::H5Reader(dir / "tune/checkpoint.h5")).parameters(), loaded.parameters());
  // One picture (any fit config) is one instance.
  std::ofstream(dir / "one.yaml") << "problem: fit\nequation: {signal: image, path: pictures/d.png}\n"
                                     "field: {type: siren, hidden: [8]}\n"
                                     "training: {precision: double, threads: 1}\noutput: {dir: one}\n";
  RunSetup one = load_run(dir / "one.yaml", {}, dir / "one");
  ASSERT_EQ(fit_codes(dir / "out/checkpoint.h5", one, {.steps = 5}), 0);
  EXPECT_TRUE(fs::exists(dir / "one/one/reconstruction.png"));
  // A checkpoint without codes is refused.
  std::ofstream(dir / "plain.yaml") << "problem: fit\nequation: {signal: image, path: pictures/a.png}\n"
                                       "field: {type: siren, hidden: [8]}\n"
                                       "training: {threads: 1, stages: [{optimizer: adam, steps: 1}]}\n";
  RunSetup plain = load_run(dir / "plain.yaml", {}, dir / "plain");
  ASSERT_EQ(execute_run(plain, {}), 0);
  RunSetup again = load_run(dir / "one.yaml", {}, dir / "again");
  EXPECT_THROW(fit_codes(dir / "plain/checkpoint.h5", again, {}), std::invalid_argument);
}

// A family of shapes (sdf): a sphere, an ellipsoid and a flatter one held out.
fs::path shape_family(const std::string& group, const std::string& family) {
  const fs::path config = write_config(group, R"yaml(
problem: sdf
equation:
  family: )yaml" + family + R"yaml(
  box_weight: 100
field: {type: siren, hidden: [32, 32], first_omega: 10, latent: {size: 4}}
training:
  threads: 1
  batch: {surface: 256, interior: 256, box: 64}
  auto_decoder: {instances_per_step: 2, fit_steps: 10, interpolation_steps: 3}
  stages: [{optimizer: adam, steps: 40, lr: 1.0e-3}]
output: {dir: out, grid: [20, 20, 20]}
)yaml");
  const fs::path dir = config.parent_path() / "shapes";
  fs::create_directories(dir);
  io::write_ply(dir / "a.ply", testutil::sphere_mesh(0.5, 12, 24));
  io::write_ply(dir / "b.ply", testutil::sphere_mesh(0.5, 12, 24, {1.0, 0.6, 0.8}));
  io::write_ply(dir / "c.ply", testutil::sphere_mesh(0.5, 12, 24, {1.0, 1.0, 0.4}));
  return config;
}

TEST(AutoDecoder, FamilyOfShapesWritesEachSurfaceAndTheInterpolationSeries) {
  const fs::path config = shape_family("auto_decoder_shapes", "{meshes: shapes, held_out: [c.ply], surface_points: 2000}");
  const fs::path dir = config.parent_path();
  RunSetup setup = load_run(config, {}, dir / "out");
  const std::vector<ProblemInstance> shapes = instances(*setup.problem, false);
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_EQ(shapes[1].name, "b.ply");
  ASSERT_EQ(execute_run(setup, {}), 0);
  for (const char* file : {"checkpoint.h5", "training/a/surface.vtp", "training/b/surface.vtp", "held_out/c/surface.vtp",
                           "interpolation/0/surface.vtp", "interpolation/2/surface.vtp", "interpolation.pvd"})
    EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;
  std::ifstream in(dir / "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["training_summary"]["chamfer_mean_per_diagonal"]["count"], 2);
  EXPECT_EQ(metrics["held_out"][0]["name"], "c.ply");
  EXPECT_TRUE(metrics["held_out"][0].contains("sign_accuracy"));  // each mesh is its own reference
  std::ifstream pvd(dir / "out/interpolation.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("interpolation/2/surface.vtp"), std::string::npos);
}

// ---- located errors -------------------------------------------------------------------

fs::path latent_config(const std::string& field, const std::string& training) {
  const fs::path config = write_config("auto_decoder_errors", "problem: fit\nequation:\n  signal: image\n"
                                                              "  family: {images: p}\nfield: " + field +
                                                              "\ntraining:\n" + training);
  fs::create_directories(config.parent_path() / "p");
  for (int k = 0; k < 3; ++k) write_picture(config.parent_path() / "p" / ("g" + std::to_string(k) + ".png"), 8, 8, k);
  return config;
}

TEST(AutoDecoder, LatentKeysAreLocated) {
  const std::string stages = "  stages: [{optimizer: adam, steps: 1}]\n";
  expect_located_error(latent_config("{type: siren, hidden: [8], latent: {size: 0}}", stages),
                       {5, 50, "field.latent.size", "[1, 4096]"});
  expect_located_error(latent_config("{type: siren, hidden: [8], latent: {}}", stages),
                       {5, 43, "field.latent.size", "missing"});
  expect_located_error(latent_config("{type: siren, hidden: [8], latent: {size: 4, film: true}}", stages),
                       {5, 53, "field.latent.film", "unknown key 'film'"});
  expect_located_error(latent_config("{type: bacon, hidden: [8, 8, 8], latent: {size: 4}}", stages),
                       {5, 8, "field", "takes no latent code"});
  expect_located_error(latent_config("{type: siren, hidden: [8]}", "  auto_decoder: {prior: 0.1}\n" + stages),
                       {7, 17, "training.auto_decoder", "add field.latent"});
  const std::string latent = "{type: siren, hidden: [8], latent: {size: 4}}";
  expect_located_error(latent_config(latent, "  auto_decoder: {prior: -1}\n" + stages),
                       {7, 25, "training.auto_decoder.prior", "[0, 1e6]"});
  expect_located_error(latent_config(latent, "  auto_decoder: {instances_per_step: 0}\n" + stages),
                       {7, 38, "training.auto_decoder.instances_per_step", "expected"});
  expect_located_error(latent_config(latent, "  auto_decoder: {fit_lr: 0}\n" + stages),
                       {7, 26, "training.auto_decoder.fit_lr", "expected"});
  expect_located_error(latent_config(latent, "  auto_decoder: {steps: 3}\n" + stages),
                       {7, 18, "training.auto_decoder.steps", "unknown key 'steps'"});
  expect_located_error(latent_config(latent, "  auto_decoder: {interpolation_steps: 1}\n" + stages),
                       {7, 39, "training.auto_decoder.interpolation_steps", "at least 2"});
  expect_located_error(latent_config(latent, "  meta: {steps: 2}\n" + stages),
                       {7, 9, "training.meta", "choose one"});
  expect_located_error(latent_config(latent, "  stages: [{optimizer: adam, steps: 1}, {optimizer: lbfgs, steps: 1}]\n"),
                       {7, 11, "training.stages", "one adam stage"});
}

TEST(AutoDecoder, ShapeFamilyKeysAreLocated) {
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: nowhere}"),
                       {4, 20, "equation.family.meshes", "no such folder"});
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: [shapes/a.ply]}"),
                       {4, 20, "equation.family.meshes", "at least two meshes"});
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: shapes, held_out: [d.ply]}"),
                       {4, 39, "equation.family.held_out[0]", "none of the family's meshes"});
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: shapes, held_out: 3}"),
                       {4, 38, "equation.family.held_out", "expected"});
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: shapes, ply: true}"),
                       {4, 28, "equation.family.ply", "unknown key 'ply'"});
  expect_located_error(shape_family("auto_decoder_shape_errors", "{meshes: shapes}\n  points: shapes/a.ply"),
                       {5, 11, "equation.points", "drop points"});
}

}  // namespace
}  // namespace nfield::solvers
