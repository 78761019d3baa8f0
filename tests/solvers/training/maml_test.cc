// SPDX-License-Identifier: MIT
//
// MAML (solvers/training/maml.h): the meta-gradient, second-order terms included, against
// central differences of the adapted loss F(θ) = L(φ_K) itself; the second-order terms are
// not negligible there (FOMAML's gradient differs); MAML on a family of constant pictures
// goes to their mean (the closed-form best initialisation for one SGD step); a maml run
// writes its initialisation; its keys' errors are located.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "fields/field_io.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/run/run.h"
#include "solvers/training/maml.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
using testutil::expect_located_error;
using testutil::write_config;

void write_picture(const fs::path& path, int size, int k) {
  io::Image image{size, size, 1, Eigen::MatrixXf(static_cast<Eigen::Index>(size) * size, 1)};
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c)
      image.pixels(static_cast<Eigen::Index>(r) * size + c) =
          0.5f + 0.4f * std::sin(0.7f * static_cast<float>(c + k) + 0.3f * static_cast<float>(k * r));
  io::write_png(path, image);
}

fs::path family(const std::string& meta, const std::string& precision = "double") {
  const fs::path config = write_config("maml", R"yaml(
problem: fit
equation:
  signal: image
  family: {images: pictures, held_out: [p2.png]}
field: {type: siren, hidden: [12, 12]}
training:
  precision: )yaml" + precision + R"yaml(
  threads: 1
  batch: {interior: 64}
  meta: )yaml" + meta + R"yaml(
  stages: [{optimizer: adam, steps: 3, lr: 1.0e-3}]
output: {dir: out}
)yaml");
  fs::create_directories(config.parent_path() / "pictures");
  for (int k = 0; k < 3; ++k) write_picture(config.parent_path() / "pictures" / ("p" + std::to_string(k) + ".png"), 8, k);
  return config;
}

Eigen::VectorXd unit_direction(std::mt19937& rng, Eigen::Index size) {
  std::normal_distribution<double> normal;
  Eigen::VectorXd d(size);
  for (Eigen::Index i = 0; i < size; ++i) d(i) = normal(rng);
  return d / d.norm();
}

TEST(Maml, MetaGradientMatchesCentralDifferencesOfTheAdaptedLoss) {
  RunSetup setup = load_run(family("{algorithm: maml, inner_steps: 3, inner_lr: 0.05}"), {});
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  ASSERT_EQ(tasks.size(), 2u);
  fields::Field<double> field(setup.field);
  const Eigen::VectorXd theta = field.parameters();
  const auto adapted = [&](const Eigen::VectorXd& at, bool first_order) {
    field.parameters() = at;
    return maml_gradient(*tasks[0].problem, field, setup.training, InnerRates<double>{0.05}, 3, first_order, 7);
  };
  const MamlGradient<double> exact = adapted(theta, false);
  EXPECT_EQ(field.parameters(), theta);  // left unchanged
  EXPECT_LT(exact.loss_after, 0.9 * exact.loss_before);
  const MamlGradient<double> first_order = adapted(theta, true);
  EXPECT_EQ(first_order.loss_after, exact.loss_after);
  // The second-order terms matter here: FOMAML's direction is off by more than 5 %.
  EXPECT_GT((first_order.gradient - exact.gradient).norm(), 0.05 * exact.gradient.norm());

  std::mt19937 rng(3);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd d = unit_direction(rng, theta.size());
    const double h = 1e-5;
    const double difference =
        (adapted(theta + h * d, true).loss_after - adapted(theta - h * d, true).loss_after) / (2 * h);
    const double directional = exact.gradient.dot(d);
    EXPECT_NEAR(directional, difference, 1e-6 * exact.gradient.norm()) << "trial " << trial;
  }
}

// Meta-SGD's rates, one per parameter: ∂F/∂θ and ∂F/∂α against central differences of F.
TEST(Maml, PerParameterRatesGradientsMatchCentralDifferences) {
  RunSetup setup = load_run(family("{algorithm: maml, inner_steps: 2, inner_lr: 0.05, learn_inner_lr: true}"), {});
  EXPECT_TRUE(setup.training.meta.learn_inner_lr);
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  fields::Field<double> field(setup.field);
  const Eigen::VectorXd theta = field.parameters();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.02, 0.08);
  Eigen::VectorXd alpha(theta.size());
  for (Eigen::Index i = 0; i < alpha.size(); ++i) alpha(i) = uniform(rng);
  const auto adapted = [&](const Eigen::VectorXd& at, const Eigen::VectorXd& rates) {
    field.parameters() = at;
    return maml_gradient(*tasks[0].problem, field, setup.training, InnerRates<double>{0, &rates}, 2, false, 3);
  };
  const MamlGradient<double> exact = adapted(theta, alpha);
  ASSERT_EQ(exact.rate_gradient.size(), theta.size());
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd d = unit_direction(rng, theta.size());
    const double h = 1e-5;
    const double along_theta =
        (adapted(theta + h * d, alpha).loss_after - adapted(theta - h * d, alpha).loss_after) / (2 * h);
    EXPECT_NEAR(exact.gradient.dot(d), along_theta, 1e-6 * exact.gradient.norm()) << "trial " << trial;
    const double along_alpha =
        (adapted(theta, alpha + h * d).loss_after - adapted(theta, alpha - h * d).loss_after) / (2 * h);
    EXPECT_NEAR(exact.rate_gradient.dot(d), along_alpha, 1e-6 * exact.rate_gradient.norm()) << "trial " << trial;
  }
}

TEST(Maml, FloatMetaGradientAgreesWithDouble) {
  RunSetup setup = load_run(family("{algorithm: maml, inner_steps: 2, inner_lr: 0.05}"), {});
  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  fields::Field<double> field(setup.field);
  fields::Field<float> field_f(setup.field);
  field_f.parameters() = field.parameters().cast<float>();
  const Eigen::VectorXd g = maml_gradient(*tasks[1].problem, field, setup.training, InnerRates<double>{0.05}, 2, false, 1).gradient;
  const Eigen::VectorXd g_f =
      maml_gradient(*tasks[1].problem, field_f, setup.training, InnerRates<float>{0.05}, 2, false, 1)
          .gradient.cast<double>();
  EXPECT_LT((g_f - g).norm(), 1e-3 * g.norm());
}

void write_constant(const fs::path& path, float value) {
  io::write_png(path, io::Image{8, 8, 1, Eigen::MatrixXf::Constant(64, 1, value)});
}

// For one SGD step, Reptile's fixed point on a family of constants is the field equal to
// their mean (reptile_test.cc). MAML optimises the loss after the step itself, and a SIREN
// can be placed where one step goes far for every constant: its adapted loss ends far below
// the adapted loss at Reptile's initialisation.
TEST(Maml, ConstantFamilyAdaptedLossFallsBelowReptilesAndTheRunWritesItsInitialisation) {
  const fs::path config = write_config("maml", R"yaml(
problem: fit
equation:
  signal: image
  family: {images: pictures, held_out: [d.png]}
field: {type: siren, hidden: [16]}
training:
  precision: double
  threads: 1
  batch: {interior: 64}
  meta: {algorithm: MAML, steps: 300, tasks_per_step: 3, inner_steps: 1, inner_lr: 0.1, outer_lr: 1.0e-2, curve_steps: 2}
  stages: [{optimizer: adam, steps: 2, lr: 1.0e-3}]
output: {dir: out}
)yaml");
  const fs::path dir = config.parent_path();
  fs::create_directories(dir / "pictures");
  write_constant(dir / "pictures/a.png", 0.2f);
  write_constant(dir / "pictures/b.png", 0.4f);
  write_constant(dir / "pictures/c.png", 230.0f / 255.0f);
  write_constant(dir / "pictures/d.png", 0.5f);
  RunSetup setup = load_run(config, {}, dir / "out");
  EXPECT_EQ(setup.training.meta.algorithm, "maml");
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["meta_algorithm"], "maml");
  EXPECT_EQ(metrics["meta_steps"], 300);
  ASSERT_TRUE(fs::exists(dir / "out/checkpoint.h5"));

  const std::vector<ProblemInstance> tasks = instances(*setup.problem, false);
  fields::Field<double> field(setup.field);
  const auto mean_adapted_loss = [&](const Eigen::VectorXd& theta) {
    double sum = 0;
    for (const ProblemInstance& task : tasks) {
      field.parameters() = theta;
      sum += maml_gradient(*task.problem, field, setup.training, InnerRates<double>{0.1}, 1, true, 1).loss_after;
    }
    return sum / static_cast<double>(tasks.size());
  };
  const Eigen::VectorXd standard = field.parameters();
  const io::H5Reader checkpoint(dir / "out/checkpoint.h5");
  const Eigen::VectorXd learned = fields::load_field<double>(checkpoint).parameters();
  MetaOptions reptile = setup.training.meta;
  reptile.algorithm = "reptile";
  reptile.outer_lr = 1.0;
  field.parameters() = standard;
  run_reptile(tasks, field, setup.training, reptile);
  const Eigen::VectorXd reptiles = field.parameters();
  const double f_maml = mean_adapted_loss(learned), f_reptile = mean_adapted_loss(reptiles);
  std::printf("adapted loss: standard %.3e, reptile %.3e, maml %.3e\n", mean_adapted_loss(standard), f_reptile, f_maml);
  EXPECT_LT(f_maml, 0.25 * f_reptile);
}

TEST(Maml, LearnedRatesAreWrittenAndUsedByTheHeldOutCurves) {
  const fs::path config = family("{algorithm: fomaml, steps: 20, tasks_per_step: 2, inner_steps: 2, inner_lr: 0.05, "
                                 "outer_lr: 1.0e-3, learn_inner_lr: true, curve_steps: 2}");
  RunSetup setup = load_run(config, {}, config.parent_path() / "out");
  ASSERT_EQ(execute_run(setup, {}), 0);
  const io::H5Reader checkpoint(config.parent_path() / "out/checkpoint.h5");
  const Eigen::VectorXd rates = checkpoint.read_vector("/meta/inner_rates");
  fields::Field<double> field(setup.field);
  ASSERT_EQ(rates.size(), field.parameter_count());
  EXPECT_GT((rates.array() - 0.05).abs().maxCoeff(), 1e-3);  // they moved
  std::ifstream in(config.parent_path() / "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_NEAR(metrics["inner_rate_mean"].get<double>(), rates.mean(), 1e-6);
  // The held-out curve from the learned θ takes its steps at those rates: its PSNR after two
  // steps is the one of two steps at the rates (from the same seed), not at inner_lr.
  const std::vector<ProblemInstance> held_out = instances(*setup.problem, true);
  ASSERT_EQ(held_out.size(), 1u);
  const io::Image picture = io::read_png(config.parent_path() / "pictures/p2.png");
  Eigen::MatrixXd x(64, 2);
  for (int i = 0; i < 64; ++i) x.row(i) << -1.0 + (2.0 * (i % 8) + 1.0) / 8.0, 1.0 - (2.0 * (i / 8) + 1.0) / 8.0;
  const auto psnr_after_two = [&](const Eigen::VectorXd* per_parameter) {
    field.parameters() = fields::load_field<double>(checkpoint).parameters();
    adapt(*held_out[0].problem, field, setup.training, "sgd", 0.05, 2, setup.training.seed + 7919, {}, per_parameter);
    const Eigen::ArrayXd error = field.values(x).col(0).array().min(1.0).max(0.0) -
                                 picture.pixels.col(0).cast<double>().array();
    return 10 * std::log10(1.0 / error.square().mean());
  };
  const double reported = metrics["held_out"][0]["meta"][2].get<double>();
  EXPECT_NEAR(reported, psnr_after_two(&rates), 1e-3);
  EXPECT_GT(std::abs(reported - psnr_after_two(nullptr)), 1e-3);
}

TEST(Maml, KeysAreLocated) {
  expect_located_error(family("{algorithm: maml, inner_optimizer: adam}"),
                       {11, 44, "training.meta.inner_optimizer", "expected sgd with algorithm maml"});
  expect_located_error(family("{algorithm: fomaml, outer_lr: 3}"),
                       {11, 39, "training.meta.outer_lr", "the outer Adam's rate"});
  expect_located_error(family("{algorithm: imaml}"), {11, 21, "training.meta.algorithm", "reptile, maml, fomaml"});
  expect_located_error(family("{algorithm: reptile, learn_inner_lr: true}"),
                       {11, 46, "training.meta.learn_inner_lr", "expected false with algorithm reptile"});
}

}  // namespace
}  // namespace nfield::solvers
