// SPDX-License-Identifier: MIT
//
// AutoInt in 1-D (solvers/problems/autoint_1d.cc): a field trained through its derivative recovers a
// closed-form antiderivative up to a constant, its derivative stream agrees with central
// differences of its values, integrals from its ends beat the untrained field by orders of
// magnitude, data integrands are fitted at their points, and bad configs are located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "integrators/segment_integrals.h"
#include "solvers/run/run.h"
#include "solvers/training/trainer.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

using testutil::write_config;

constexpr const char* kCosine = R"yaml(
problem: autoint_1d
domain: {lower: [-1], upper: [1]}
equation: {integrand: "cos(10*x)", antiderivative: "sin(10*x)/10", intervals: 200}
field: {type: siren, hidden: [16, 16], first_omega: 10, hidden_omega: 1}
training:
  seed: 3
  precision: double
  batch: {interior: 256}
  stages:
    - {optimizer: adam, steps: 300, lr: 5.0e-3, schedule: cosine, lr_final: 1.0e-4}
    - {optimizer: lm, steps: 30}
)yaml";

Eigen::VectorXd column(const Eigen::MatrixXd& m) { return m.col(0); }

// ~2 s: Adam then LM on 256 points; the error bounds have a margin of 10× or more over
// what seeds 0–3 reach (integrals ≈ 1e-6 … 1e-5).
TEST(AutoInt1d, RecoversTheClosedFormAntiderivativeAndItsIntegrals) {
  RunSetup setup = load_run(write_config("autoint", kCosine), {});
  fields::Field<double> field(setup.field);
  const auto phi = [&field](const Eigen::MatrixXd& x) -> Eigen::VectorXd { return column(field.values(x)); };

  Eigen::MatrixXd a = Eigen::MatrixXd::Random(500, 1), b = Eigen::MatrixXd::Random(500, 1);
  const auto exact = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) -> Eigen::VectorXd {
    return ((10 * b.array()).sin() - (10 * a.array()).sin()) / 10;
  };
  const double untrained = (integrators::antiderivative_differences(phi, a, b) - exact(a, b)).norm() /
                           exact(a, b).norm();

  Trainer<double> trainer(*setup.problem, field, setup.training);
  ASSERT_TRUE(trainer.run({}));
  const double trained = (integrators::antiderivative_differences(phi, a, b) - exact(a, b)).norm() /
                         exact(a, b).norm();
  std::printf("integral rel. L2 error: untrained %.3e, trained %.3e\n", untrained, trained);
  EXPECT_GT(untrained, 0.3);
  EXPECT_LT(trained, 1e-4);

  // Φ(x) − Φ(0) against sin(10x)/10 on a grid.
  const Eigen::MatrixXd x = Eigen::VectorXd::LinSpaced(101, -1, 1);
  const Eigen::VectorXd shifted = phi(x).array() - phi(Eigen::MatrixXd::Zero(1, 1))(0);
  EXPECT_LT((shifted - column((10 * x.array()).sin() / 10)).cwiseAbs().maxCoeff(), 1e-4);

  // The tangent stream the loss trained is the derivative of the values: central differences.
  autodiff::Streams<double> out;
  field.evaluate(autodiff::StreamLayout(autodiff::StreamSpec::gradient(1)), x, out);
  const double h = 1e-5;
  const Eigen::VectorXd difference = (phi(x.array() + h) - phi(x.array() - h)) / (2 * h);
  EXPECT_LT((out.stream(1).col(0) - difference).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((out.stream(1).col(0) - column((10 * x.array()).cos())).cwiseAbs().maxCoeff(), 1e-3);
}

// The stage error the trainer reports is the integral error over the problem's intervals,
// and it falls from stage to stage.
TEST(AutoInt1d, ReportsFallingIntegralErrorsPerStage) {
  RunSetup setup = load_run(write_config("autoint", kCosine), {});
  fields::Field<double> field(setup.field);
  Trainer<double> trainer(*setup.problem, field, setup.training);
  const OutputContext context{
      {}, nullptr, {}, [&field](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
        autodiff::Streams<double> out;
        field.evaluate(layout, x, out);
        return out;
      }};
  Trainer<double>::Callbacks callbacks;
  callbacks.stage_error = [&] { return *setup.problem->reported_error(context); };
  ASSERT_TRUE(trainer.run(callbacks));
  ASSERT_EQ(trainer.stage_errors().size(), 2u);
  EXPECT_LT(trainer.stage_errors()[0], 0.1);
  EXPECT_LT(trainer.stage_errors()[1], 0.1 * trainer.stage_errors()[0]);
}

std::filesystem::path write_samples(const std::filesystem::path& dir, const std::string& text) {
  std::ofstream(dir / "samples.txt") << text;
  return dir / "samples.txt";
}

// Data integrands are fitted at their own points, where the residual's source is the datum.
TEST(AutoInt1d, SampledIntegrandsTrainAtTheirPoints) {
  const auto config = write_config("autoint", R"yaml(
problem: autoint_1d
domain: {lower: [0], upper: [3]}
equation: {samples: samples.txt}
training: {batch: {interior: 100}, stages: [{optimizer: adam, steps: 1}]}
)yaml");
  write_samples(config.parent_path(), "# x f\n0 1\n1 3\n\n2 -1  # a comment\n3 0\n");
  const RunSetup setup = load_run(config, {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 1u);
  Random rng(1);
  const TermPoints all = terms[0].sample(rng, 100);
  ASSERT_EQ(all.x.rows(), 4);
  EXPECT_EQ(all.x(2, 0), 2.0);
  const TermPoints some = terms[0].sample(rng, 3);
  ASSERT_EQ(some.x.rows(), 3);
  EXPECT_NE(some.x(0, 0), some.x(1, 0));

  // r = ∂Φ/∂x − f at the data: zero streams give −f.
  const auto residual = terms[0].residual(all);
  const autodiff::StreamLayout layout(terms[0].spec);
  autodiff::Streams<double> out;
  out.resize(4, layout.count(), 1);
  out.data.setZero();
  Eigen::MatrixXd r(4, 1);
  residual->evaluate(0, layout, out, r);
  EXPECT_EQ(r(0, 0), -1.0);
  EXPECT_EQ(r(1, 0), -3.0);
  EXPECT_EQ(r(2, 0), 1.0);
  EXPECT_EQ(r(3, 0), 0.0);
}

TEST(AutoInt1d, LocatesConfigErrors) {
  using testutil::expect_located_error;
  expect_located_error(write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [-1], upper: [1]}
equation:
  integrand: "x"
  audio: clip.wav
)yaml"),
                       {4, 3, "equation", "exactly one of"});
  expect_located_error(write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [-1, 0], upper: [1, 1]}
equation: {integrand: "x"}
)yaml"),
                       {2, 9, "domain", "one coordinate"});
  expect_located_error(write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [-1], upper: [1]}
equation: {integrand: "x", intervals: 0}
)yaml"),
                       {3, 39, "equation.intervals", ""});
  expect_located_error(write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [-1], upper: [1]}
equation: {integrand: "x", antiderivate: "x^2/2"}
)yaml"),
                       {3, 28, "equation.antiderivate", "unknown key 'antiderivate'"});

  auto config = write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [0], upper: [2]}
equation: {samples: samples.txt}
)yaml");
  write_samples(config.parent_path(), "0 1\n1 2 3\n2 0\n");
  expect_located_error(config, {3, 21, "equation.samples", "samples.txt:2: expected two finite numbers"});
  write_samples(config.parent_path(), "0 1\n1 x\n");
  expect_located_error(config, {3, 21, "equation.samples", "samples.txt:2: expected numbers"});
  write_samples(config.parent_path(), "0 1\n1 2\n");
  expect_located_error(config, {3, 21, "equation.samples", "does not cover the domain"});
  write_samples(config.parent_path(), "0 1\n2 2\n1 2\n");
  expect_located_error(config, {3, 21, "equation.samples", "samples.txt:3: x must increase"});

  config = write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [0], upper: [1]}
equation: {audio: )yaml" NFIELD_SOURCE_DIR R"yaml(/data/audio/counting_espeak.wav, audio_seconds: [6, 7]}
)yaml");
  try {
    load_run(config, {});
    FAIL() << "no error";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), "equation.audio_seconds");
    EXPECT_NE(std::string(e.what()).find("6.66"), std::string::npos) << e.what();
  }
  config = write_config("autoint", R"yaml(problem: autoint_1d
domain: {lower: [0], upper: [1]}
equation: {audio: missing.wav}
)yaml");
  try {
    load_run(config, {});
    FAIL() << "no error";
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.key_path(), "equation.audio");
    EXPECT_NE(std::string(e.what()).find("missing.wav"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nfield::solvers
