// SPDX-License-Identifier: MIT
//
// Meta-learned initialisations (solvers/training/reptile.h, solvers/run/meta_run.h) over a family
// of pictures (solvers/problems/image_family.h): Reptile on a family of constant pictures
// moves the field to the mean of the constants (the closed-form best initialisation for one
// SGD inner step), not to their median; a meta run writes its initialisation and held-out
// curves, and `field.init` starts a fit from that checkpoint; every new key's errors are
// located.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fields/field_io.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/run/run.h"
#include "solvers/training/reptile.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
using testutil::expect_located_error;
using testutil::write_config;

void write_constant(const fs::path& path, int width, int height, float value) {
  io::write_png(path, io::Image{width, height, 1,
                                Eigen::MatrixXf::Constant(static_cast<Eigen::Index>(width) * height, 1, value)});
}

// A grey picture with a gradient whose direction depends on k.
void write_gradient(const fs::path& path, int width, int height, int k) {
  io::Image image{width, height, 1, Eigen::MatrixXf(static_cast<Eigen::Index>(width) * height, 1)};
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      image.pixels(static_cast<Eigen::Index>(r) * width + c) =
          0.5f + 0.4f * ((k % 2 ? 1.0f : -1.0f) * static_cast<float>(c) / width - 0.5f * static_cast<float>(r) / height);
  io::write_png(path, image);
}

TEST(Reptile, ConstantFamilyMovesTheFieldToTheMeanNotTheMedian) {
  const fs::path config = write_config("reptile", R"yaml(
problem: fit
equation:
  signal: image
  family: {images: pictures, held_out: 0}
field: {type: siren, hidden: [16]}
training:
  precision: double
  threads: 1
  batch: {interior: 64}
  meta: {algorithm: reptile, steps: 300, tasks_per_step: 3, inner_steps: 1, inner_optimizer: sgd, inner_lr: 0.1}
  stages: [{optimizer: adam, steps: 1}]
)yaml");
  fs::create_directories(config.parent_path() / "pictures");
  // 8-bit grey levels 51, 102, 230: mean 0.5007843, median 0.4.
  write_constant(config.parent_path() / "pictures/a.png", 8, 8, 0.2f);
  write_constant(config.parent_path() / "pictures/b.png", 8, 8, 0.4f);
  write_constant(config.parent_path() / "pictures/c.png", 8, 8, 230.0f / 255.0f);
  const double mean = (51.0 + 102.0 + 230.0) / 3.0 / 255.0;
  RunSetup setup = load_run(config, {});
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  ASSERT_EQ(tasks.size(), 3u);
  EXPECT_TRUE(instances(*setup.problem, true).empty());
  fields::Field<double> field(setup.field);
  Eigen::MatrixXd x(64, 2);
  for (int i = 0; i < 64; ++i) x.row(i) << -1.0 + (2.0 * (i % 8) + 1.0) / 8.0, 1.0 - (2.0 * (i / 8) + 1.0) / 8.0;
  const Eigen::VectorXd before = field.values(x).col(0);
  ASSERT_GT(std::abs(before.mean() - mean), 0.2);  // it has somewhere to go
  const MetaResult result = run_reptile(tasks, field, setup.training, setup.training.meta);
  EXPECT_TRUE(result.finished);
  EXPECT_EQ(result.steps, 300);
  const Eigen::VectorXd after = field.values(x).col(0);
  EXPECT_NEAR(after.mean(), mean, 5e-3);
  EXPECT_LT((after.array() - mean).abs().maxCoeff(), 2e-2);  // about constant
  EXPECT_GT(std::abs(after.mean() - 0.4), 0.08);              // not the median
}

TEST(Reptile, MetaRunWritesItsInitialisationAndFieldInitStartsFromIt) {
  const fs::path config = write_config("reptile", R"yaml(
problem: fit
equation:
  signal: image
  family: {images: [pictures/a.png, pictures/b.png, pictures/c.png], held_out: [c.png]}
field: {type: siren, hidden: [16]}
training:
  threads: 1
  meta: {steps: 4, tasks_per_step: 2, inner_steps: 2, curve_steps: 3}
  stages: [{optimizer: adam, steps: 5, lr: 1.0e-3}]
output: {dir: out}
)yaml");
  const fs::path dir = config.parent_path();
  fs::create_directories(dir / "pictures");
  for (int k = 0; k < 3; ++k) write_gradient(dir / "pictures" / (std::string(1, static_cast<char>('a' + k)) + ".png"), 12, 10, k);
  RunSetup setup = load_run(config, {}, dir / "out");
  ASSERT_EQ(execute_run(setup, {}), 0);
  for (const char* file : {"checkpoint.h5", "config.yaml", "held_out_curve.csv", "metrics.json",
                           "held_out/c/meta_0/reconstruction.png", "held_out/c/meta_2/reconstruction.png",
                           "held_out/c/standard_3/reconstruction.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;
  std::ifstream in(dir / "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["meta_steps"], 4);
  EXPECT_EQ(metrics["held_out"].size(), 1u);
  EXPECT_EQ(metrics["held_out"][0]["meta"].size(), 4u);  // steps 0 … 3
  EXPECT_TRUE(metrics.contains("held_out_meta_step2"));

  // A fit of the held-out picture from the learned initialisation.
  std::ofstream(dir / "fit.yaml") << R"yaml(
problem: fit
equation: {signal: image, path: pictures/c.png}
field: {type: siren, hidden: [16], init: out/checkpoint.h5}
training: {threads: 1, stages: [{optimizer: adam, steps: 1}]}
output: {dir: fit_out}
)yaml";
  RunSetup fit = load_run(dir / "fit.yaml", {});
  const io::H5Reader checkpoint(dir / "out/checkpoint.h5");
  const Eigen::VectorXd learned = fields::load_field<double>(checkpoint).parameters();
  ASSERT_EQ(fit.init.parameters.size(), learned.size());
  EXPECT_EQ(fit.init.parameters, learned);
  EXPECT_EQ(fit.resolved["field"]["init"].as<std::string>(), "out/checkpoint.h5");
}

// ---- located errors -------------------------------------------------------------------

fs::path family_config(const std::string& family, const std::string& training) {
  const fs::path config = write_config("reptile", "problem: fit\nequation:\n  signal: image\n  family: " + family +
                                                      "\nfield: {type: siren, hidden: [8]}\ntraining:\n" + training);
  fs::create_directories(config.parent_path() / "p");
  for (int k = 0; k < 3; ++k) write_gradient(config.parent_path() / "p" / ("g" + std::to_string(k) + ".png"), 8, 8, k);
  return config;
}

const std::string kMeta = "  meta: {steps: 2}\n  stages: [{optimizer: adam, steps: 1}]\n";

TEST(Reptile, PicturesOfMixedSizesAreLocatedAtImages) {
  const fs::path config = family_config("{images: p}", kMeta);
  write_gradient(config.parent_path() / "p/g3.png", 12, 8, 3);
  expect_located_error(config, {4, 20, "equation.family.images", "g3.png: a picture of 12 x 8 pixels"});
  // With a crop, pictures of several sizes are fine; one smaller than the crop is not.
  const fs::path cropped = family_config("{images: p, crop: 10}", kMeta);
  expect_located_error(cropped, {4, 20, "equation.family.images", "smaller than the crop of 10 x 10"});
}

TEST(Reptile, HeldOutNamesAndCountsAreChecked) {
  expect_located_error(family_config("{images: p, held_out: [g9.png]}", kMeta),
                       {4, 34, "equation.family.held_out[0]", "'g9.png' is none of the family's pictures"});
  expect_located_error(family_config("{images: p, held_out: 3}", kMeta),
                       {4, 33, "equation.family.held_out", "expected"});
  expect_located_error(family_config("{images: p, held_out: [g0.png, g1.png, g2.png]}", kMeta),
                       {4, 33, "equation.family.held_out", "at least one of the pictures left for training"});
}

TEST(Reptile, MetaKeysAreLocated) {
  expect_located_error(family_config("{images: p}", "  meta: {algorithm: imaml}\n"),
                       {7, 21, "training.meta.algorithm", "reptile"});
  expect_located_error(family_config("{images: p}", "  meta: {inner_steps: 0}\n"),
                       {7, 23, "training.meta.inner_steps", "expected"});
  expect_located_error(family_config("{images: p}", "  meta: {outer_lr: 2}\n"),
                       {7, 20, "training.meta.outer_lr", "(0, 1]"});
  expect_located_error(family_config("{images: p}", "  meta: {inner_optimizer: lbfgs}\n"),
                       {7, 27, "training.meta.inner_optimizer", "sgd, adam"});
  expect_located_error(family_config("{images: p}", "  meta: {inner_lr: 0.1, zoom: 1}\n"),
                       {7, 25, "training.meta.zoom", "unknown key 'zoom'"});
  expect_located_error(family_config("{images: p}", "  meta: {}\n  stages: [{optimizer: lbfgs, steps: 1}]\n"),
                       {8, 24, "training.stages[0].optimizer", "expected an adam stage with schedule constant"});
}

TEST(Reptile, FamilyAndMetaGoTogether) {
  expect_located_error(family_config("{images: p}", "  stages: [{optimizer: adam, steps: 1}]\n"),
                       {4, 11, "equation.family", "trained by training.meta"});
  const fs::path poisson = write_config("reptile", R"yaml(problem: poisson
domain: {lower: [0, 0], upper: [1, 1]}
equation: {source: "1"}
conditions: [{on: boundary, type: dirichlet, value: "0"}]
training:
  meta: {steps: 2}
)yaml");
  expect_located_error(poisson, {6, 9, "training.meta", "no family of instances"});
}

TEST(Reptile, FieldInitIsLocatedWhenMissingOrOfAnotherShape) {
  const fs::path dir = write_config("reptile", "").parent_path();
  write_gradient(dir / "a.png", 8, 8, 0);
  std::ofstream(dir / "missing.yaml")
      << "problem: fit\nequation: {signal: image, path: a.png}\nfield: {type: siren, hidden: [8], init: none.h5}\n";
  expect_located_error(dir / "missing.yaml", {3, 41, "field.init", "no such checkpoint file"});
  // A checkpoint of a [8]-wide field, read by a config of a [16]-wide one.
  std::ofstream(dir / "small.yaml") << "problem: fit\nequation: {signal: image, path: a.png}\n"
                                       "field: {type: siren, hidden: [8]}\n"
                                       "training: {threads: 1, stages: [{optimizer: adam, steps: 1}]}\n"
                                       "output: {dir: small_out}\n";
  RunSetup small = load_run(dir / "small.yaml", {}, dir / "small_out");
  ASSERT_EQ(execute_run(small, {}), 0);
  std::ofstream(dir / "wide.yaml") << "problem: fit\nequation: {signal: image, path: a.png}\n"
                                      "field: {type: siren, hidden: [16], init: small_out/checkpoint.h5}\n";
  expect_located_error(dir / "wide.yaml", {3, 42, "field.init", "expected the same shape"});
}

}  // namespace
}  // namespace nfield::solvers
