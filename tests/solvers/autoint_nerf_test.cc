// SPDX-License-Identifier: MIT
//
// problem: autoint_nerf. On a random integral field: a section's mean from two values of Φ
// equals the dense average of the tangent stream ∂Φ/∂t = ∇ₓΦ·d over the section, and that
// stream equals central differences of Φ along the ray. The section residual's adjoint
// against central differences, a drawn batch's per-point tangents, config errors located,
// and a short training run whose loss falls (through the trainer's per-point tangents) and
// that writes and renders test views.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "autodiff/sequential.h"
#include "fields/field.h"
#include "io/png_image.h"
#include "solvers/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/ray_residual_checks.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

const std::filesystem::path kBunny = std::filesystem::path(NFIELD_SOURCE_DIR) / "data/multiview/bunny_blender";

std::string autoint_config(const std::string& render, const std::string& extra = "", bool test = false) {
  std::string data = "  train: " + (kBunny / "transforms_train.json").string() + "\n";
  if (test) data += "  test: " + (kBunny / "transforms_test.json").string() + "\n";
  return "problem: autoint_nerf\n"
         "data:\n" + data +
         "scene: {lower: [-0.6, -0.6, -0.6], upper: [0.6, 0.6, 0.6]}\n"
         "render: " + render + "\n"
         "field: {type: nerf, activation: tanh, hidden: [32, 32], color_hidden: [16],\n"
         "        encoding: {type: positional, frequencies: 6, normalize: true}}\n"
         "training:\n"
         "  batch: {rays: 256}\n"
         "  stages: [{optimizer: adam, steps: 60, lr: 5.0e-3}]\n" + extra;
}

fields::Field<double> random_integral_field() {
  fields::FieldOptions options;
  options.type = "nerf";
  options.activation = "softplus";
  options.input_dim = 6;
  options.output_dim = 4;
  options.hidden = {24, 24};
  options.color_hidden = {12};
  options.encoding.type = "positional";
  options.encoding.frequencies = 5;
  options.encoding.normalize = true;
  options.seed = 11;
  fields::Field<double> field(options);
  field.initialize();
  return field;
}

// Φ and ∂Φ/∂t at x(t) = o + t·d, the tangent (d, 0) given per point.
struct AlongRay {
  Eigen::MatrixXd value, rate;
};
AlongRay along_ray(const fields::Field<double>& field, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                   const Eigen::VectorXd& t) {
  Eigen::MatrixXd x(t.size(), 6), tangents = Eigen::MatrixXd::Zero(t.size(), 6);
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    x.row(i) << (o + t(i) * d).transpose(), d.transpose();
    tangents.row(i).head(3) = d.transpose();
  }
  autodiff::StreamSpec spec = autodiff::StreamSpec::values(6);
  spec.tangents = Eigen::MatrixXd::Zero(6, 1);
  spec.tangents(0, 0) = 1;  // replaced by the per-point tangents
  const autodiff::StreamLayout layout(spec);
  autodiff::Streams<double> out;
  field.evaluate(field.parameters().data(), layout, autodiff::Batch<double>{x, &tangents}, out);
  return {out.stream(0), out.stream(layout.tangent(0))};
}

TEST(AutointNerf, SectionMeanFromValuesIsTheMeanOfTheTangentStream) {
  const fields::Field<double> field = random_integral_field();
  const Eigen::Vector3d o(0.3, -0.2, 0.1), d = Eigen::Vector3d(0.2, 0.5, -0.8).normalized();
  const double a = 0.1, b = 0.45;
  const AlongRay ends = along_ray(field, o, d, Eigen::Vector2d(a, b));
  const Eigen::RowVectorXd from_values = (ends.value.row(1) - ends.value.row(0)) / (b - a);

  // Midpoint rule over 20000 cells: its error, (b − a)h²/24 · max|∂³Φ/∂t³|, is below 1e-9
  // here (octave 4 of the encoding: ∂³ ≲ (16π)² per feature).
  const int n = 20000;
  Eigen::VectorXd t(n);
  for (int i = 0; i < n; ++i) t(i) = a + (i + 0.5) * (b - a) / n;
  const Eigen::RowVectorXd dense_mean = along_ray(field, o, d, t).rate.colwise().mean();
  ASSERT_GT(from_values.norm(), 1e-3);  // a field whose section means are not all zero
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(from_values(c), dense_mean(c), 1e-8 * (1 + std::abs(dense_mean(c)))) << c;

  // A few samples per section only estimate it: m = 4 midpoints are off by far more.
  Eigen::VectorXd coarse(4);
  for (int i = 0; i < 4; ++i) coarse(i) = a + (i + 0.5) * (b - a) / 4;
  EXPECT_GT((along_ray(field, o, d, coarse).rate.colwise().mean() - from_values).norm(), 1e-6);

  // The tangent stream against central differences of Φ along the ray.
  const Eigen::Vector3d some_t(-0.3, 0.05, 0.7);
  const AlongRay at = along_ray(field, o, d, some_t);
  const double h = 1e-5;
  const AlongRay plus = along_ray(field, o, d, some_t.array() + h), minus = along_ray(field, o, d, some_t.array() - h);
  const Eigen::MatrixXd central = (plus.value - minus.value) / (2 * h);
  for (Eigen::Index i = 0; i < central.size(); ++i)
    EXPECT_NEAR(at.rate.data()[i], central.data()[i], 1e-7 * (1 + std::abs(central.data()[i]))) << i;
}

TEST(AutointNerf, DrawnBatchCarriesEachSamplesRayDirection) {
  const RunSetup setup = load_run(testutil::write_config("autoint", autoint_config(
                                                             "{sections: 8, samples_per_section: 3}",
                                                             "output: {dir: unused}\n")),
                                  {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 1u);
  EXPECT_EQ(terms[0].spec.tangents.cols(), 1);
  Random rng(3);
  const TermPoints points = terms[0].sample(rng, 20);
  ASSERT_EQ(points.groups.size(), 21u);
  ASSERT_EQ(points.tangents.rows(), points.x.rows());
  ASSERT_EQ(points.tangents.cols(), 6);
  int crossing = 0;
  for (size_t r = 0; r + 1 < points.groups.size(); ++r) {
    const Eigen::Index n = points.groups[r + 1] - points.groups[r];
    ASSERT_TRUE(n == 0 || n == 24) << "ray " << r << " has " << n << " samples";
    crossing += n > 0;
  }
  EXPECT_GT(crossing, 10);
  EXPECT_TRUE(points.tangents.leftCols(3).isApprox(points.x.rightCols(3)));
  EXPECT_EQ(points.tangents.rightCols(3).norm(), 0.0);
}

TEST(AutointNerf, SectionResidualAdjointMatchesCentralDifferences) {
  const RunSetup setup = load_run(testutil::write_config("autoint", autoint_config(
                                                             "{sections: 6, samples_per_section: 3}",
                                                             "output: {dir: unused}\n")),
                                  {});
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  Random rng(5);
  const TermPoints points = terms[0].sample(rng, 12);
  ASSERT_GT(points.x.rows(), 12 * 9);
  const auto residual = terms[0].residual(points);
  const autodiff::StreamLayout layout(terms[0].spec);
  ASSERT_EQ(layout.count(), 2);

  std::mt19937_64 engine(7);
  const Streams<double> out = testutil::random_streams(points.x.rows(), 2, 4, 6.0, engine);
  const Streams<double> adjoint = testutil::expect_ray_residual_adjoint(*residual, layout, out, points.groups, 5, engine);
  // Φ itself is not read in training: only its rate along the ray.
  EXPECT_EQ(adjoint.stream(0).norm(), 0.0);
  EXPECT_GT(adjoint.stream(1).norm(), 0.0);
}

TEST(AutointNerf, ConfigErrorsAreLocated) {
  auto check = [](const std::string& text, const testutil::Located& want) {
    testutil::expect_located_error(testutil::write_config("autoint", text), want);
  };
  check(autoint_config("{sections: 0}"), {5, 20, "render.sections", ""});
  check(autoint_config("{sections: 8, samples: 3}"),
        {5, 23, "render.samples", "unknown key 'samples'"});
  check(autoint_config("{samples_per_section: 2.5}"), {5, 31, "render.samples_per_section", ""});
  check(autoint_config("{density: relu}"), {5, 19, "render.density", "softplus"});
}

double run_loss(const std::filesystem::path& dir, int steps, bool test_views) {
  std::string text = autoint_config("{sections: 8, samples_per_section: 2, density_scale: 10}", "output: {dir: " + dir.string() + "}\n",
                                    test_views);
  text.replace(text.find("steps: 60"), 9, "steps: " + std::to_string(steps));
  RunSetup setup = load_run(testutil::write_config("autoint_run", text), {});
  EXPECT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "metrics.json");
  return nlohmann::json::parse(in)["loss"].get<double>();
}

TEST(AutointNerf, ShortTrainingLowersTheLossAndRendersTestViews) {
  const auto dir = testutil::scratch_dir("autoint_nerf");
  const double first = run_loss(dir / "one_step", 1, false);
  const double trained = run_loss(dir / "trained", 60, true);
  EXPECT_LT(trained, 0.5 * first) << "first step " << first;
  std::ifstream in(dir / "trained/metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  EXPECT_GT(metrics["psnr_mean"].get<double>(), 13.0);
  EXPECT_EQ(metrics["field_evaluations_per_ray"].get<double>(), 9.0);
  EXPECT_GT(metrics["render_ms_mean"].get<double>(), 0.0);
  for (const char* suffix : {"render", "truth", "error", "depth", "opacity"})
    EXPECT_TRUE(std::filesystem::exists(dir / "trained/test_views" / (std::string("test_007_") + suffix + ".png")))
        << suffix;
  RenderRequest turntable;
  turntable.turntable_frames = 2;
  render_checkpoint(dir / "trained/checkpoint.h5", turntable, dir / "turntable");
  const io::Image frame = io::read_png(dir / "turntable/turntable_001_render.png");
  EXPECT_EQ(frame.width, 128);
}

}  // namespace
}  // namespace nfield::solvers
