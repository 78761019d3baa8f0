// SPDX-License-Identifier: MIT
//
// problem: autoint_nerf. On a random integral field: a section's mean from two values of Φ
// equals the dense average of the tangent stream ∂Φ/∂t = ∇ₓΦ·d over the section, and that
// stream equals central differences of Φ along the ray. The section residual's adjoint
// against central differences, a drawn batch's per-point tangents, config errors located,
// and a short training run whose loss falls (through the trainer's per-point tangents) and
// that writes and renders test views. The sampling network: its sections tile each ray, its
// gradient against central differences, it learns to enclose a thin slab of a known
// integral field, and it is kept in checkpoints.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "autodiff/sequential.h"
#include "fields/field.h"
#include "fields/positional_encoding.h"
#include "integrators/volume_rendering.h"
#include "io/hdf5_file.h"
#include "io/png_image.h"
#include "solvers/problems/section_sampler.h"
#include "solvers/run/run.h"
#include "tests/testing/best_constant.h"
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
  options.encoding = fields::encoding_options(fields::PositionalOptions{.frequencies = 5, .normalize = true});
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
  check(autoint_config("{sampler: {min_share: 1}}"), {5, 31, "render.sampler.min_share", "[0, 1)"});
  check(autoint_config("{sampler: {hidden: [0]}}"), {5, 28, "render.sampler.hidden", ">= 1"});
  check(autoint_config("{sampler: {layers: 2}}"), {5, 20, "render.sampler.layers", "unknown key 'layers'"});
  check(autoint_config("{sampler: [64]}"), {5, 19, "render.sampler", "true, false or a mapping"});
  check(autoint_config("{sampler: yes please}"), {5, 19, "render.sampler", ""});
}

// Rays through the box [−0.6, 0.6]³ from a sphere of radius 2, a few of them missing it.
integrators::Rays<double> random_rays(Eigen::Index n, std::mt19937_64& engine) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  integrators::Rays<double> rays;
  rays.origins.resize(n, 3);
  rays.directions.resize(n, 3);
  rays.depth_scale.setOnes(n);
  rays.near.resize(n);
  rays.far.resize(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    const Eigen::Vector3d o = Eigen::Vector3d(normal(engine), normal(engine), normal(engine)).normalized() * 2;
    const Eigen::Vector3d aim(uniform(engine), uniform(engine), uniform(engine));
    const Eigen::Vector3d d = (aim - o).normalized();
    rays.origins.row(r) = o.transpose();
    rays.directions.row(r) = d.transpose();
    rays.near(r) = 1.2;
    rays.far(r) = r % 7 == 3 ? 1.0 : 2.8;  // every 7th ray: an empty interval
  }
  return rays;
}

OutputContext::FieldStreams streams_of(const fields::Field<double>& field) {
  return [&field](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
    autodiff::Streams<double> out;
    field.evaluate(layout, x, out);
    return out;
  };
}

TEST(SectionSampler, SectionsTileEachRayWithTheMinimumShare) {
  SectionSamplerOptions options;
  options.min_share = 0.4;
  SectionSampler sampler(8, options);
  std::mt19937_64 engine(1);
  // An untrained S gives equal sections (its output layer starts at zero): other weights.
  EXPECT_TRUE(sampler.sections(random_rays(5, engine)).delta.isApproxToConstant(1.6 / 8, 1e-12));
  sampler.parameters().setRandom();
  const integrators::Rays<double> rays = random_rays(30, engine);
  const Eigen::MatrixXd t = sampler.boundaries(rays);
  const integrators::RaySamples<double> sections = sampler.sections(rays);
  ASSERT_EQ(sections.rays(), 30);
  Eigen::Index k = 0;
  double most_unequal = 0;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (r % 7 == 3) {
      EXPECT_EQ(sections.count(r), 0) << r;
      continue;
    }
    ASSERT_EQ(sections.count(r), 8) << r;
    EXPECT_EQ(t(k, 0), rays.near(r));
    EXPECT_EQ(t(k, 8), rays.far(r));
    const double length = rays.far(r) - rays.near(r);
    for (int i = 0; i < 8; ++i) {
      const double delta = t(k, i + 1) - t(k, i);
      EXPECT_GE(delta, (1 - 1e-12) * 0.4 / 8 * length) << r << " " << i;
      EXPECT_NEAR(sections.delta(sections.begin(r) + i), delta, 1e-15);
      EXPECT_NEAR(sections.t(sections.begin(r) + i), 0.5 * (t(k, i) + t(k, i + 1)), 1e-15);
      most_unequal = std::max(most_unequal, delta / (length / 8));
    }
    ++k;
  }
  EXPECT_EQ(k, t.rows());
  EXPECT_GT(most_unequal, 1.1);  // the network does place them
}

TEST(SectionSampler, GradientMatchesCentralDifferences) {
  const fields::Field<double> field = random_integral_field();
  SectionSampler sampler(5, {});
  std::mt19937_64 engine(2);
  sampler.parameters() = 0.3 * Eigen::VectorXd::Random(sampler.parameter_count());
  const integrators::Rays<double> rays = random_rays(24, engine);
  Eigen::MatrixXd target = Eigen::MatrixXd::Random(24, 3).array() * 0.5 + 0.5;
  const Eigen::MatrixXd background = Eigen::RowVector3d(1, 1, 1);
  DensityActivation density;
  Eigen::VectorXd gradient, unused;
  sampler.loss_and_gradient(rays, target, background, streams_of(field), density, 10, gradient);
  ASSERT_EQ(gradient.size(), sampler.parameter_count());
  ASSERT_GT(gradient.norm(), 0);
  auto loss = [&] {
    return sampler.loss_and_gradient(rays, target, background, streams_of(field), density, 10, unused).loss;
  };
  std::uniform_int_distribution<Eigen::Index> pick(0, sampler.parameter_count() - 1);
  int checked = 0;
  for (int n = 0; n < 200 && checked < 25; ++n) {
    const Eigen::Index p = pick(engine);
    if (std::abs(gradient(p)) < 1e-8) continue;  // a ReLU unit that is off everywhere
    const double saved = sampler.parameters()(p), h = 1e-6;
    sampler.parameters()(p) = saved + h;
    const double plus = loss();
    sampler.parameters()(p) = saved - h;
    const double minus = loss();
    sampler.parameters()(p) = saved;
    EXPECT_NEAR(gradient(p), (plus - minus) / (2 * h), 1e-5 * (std::abs(gradient(p)) + 1e-3)) << "parameter " << p;
    ++checked;
  }
  EXPECT_GE(checked, 20);
}

// An integral field along +x only: a thin slab [a, b] of density and of a colour unlike the
// rest. Φ = (Φ_σ, Φ_r, Φ_g, Φ_b), with the slab's indicator smoothed to width w,
//   bump(x) = ½(tanh((x − a)/w) − tanh((x − b)/w)),  B(x) = ∫ bump = ½w log(cosh((x−a)/w) / cosh((x−b)/w)),
//   ∂Φ_σ/∂x = −4 + 12·bump,  ∂Φ_r/∂x = −3 + 6·bump,  ∂Φ_g/∂x = ∂Φ_b/∂x = −3.
OutputContext::FieldStreams slab_field(double a, double b, double w) {
  return [a, b, w](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
    autodiff::Streams<double> out;
    out.resize(x.rows(), layout.count(), 4);
    out.data.setZero();
    for (Eigen::Index n = 0; n < x.rows(); ++n) {
      const double s = x(n, 0);
      const double bump = 0.5 * (std::tanh((s - a) / w) - std::tanh((s - b) / w));
      const double B = 0.5 * w * (std::log(std::cosh((s - a) / w)) - std::log(std::cosh((s - b) / w)));
      out.stream(0).row(n) << -4 * s + 12 * B, -3 * s + 6 * B, -3 * s, -3 * s;
      for (int i = 0; i < layout.tangents(); ++i) {
        const double along_x = layout.spec().tangents(0, i);
        out.stream(layout.tangent(i)).row(n) = along_x * Eigen::RowVector4d(-4 + 12 * bump, -3 + 6 * bump, -3, -3);
      }
    }
    return out;
  };
}

TEST(SectionSampler, LearnsToEncloseAThinSlab) {
  const double a = 0.05, b = 0.25;
  const OutputContext::FieldStreams field = slab_field(a, b, 0.01);
  // Rays along +x through [−0.6, 0.6], at random heights (the field ignores them).
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> height(-0.5, 0.5);
  const Eigen::Index n = 64;
  integrators::Rays<double> rays;
  rays.origins.resize(n, 3);
  rays.directions.resize(n, 3);
  for (Eigen::Index r = 0; r < n; ++r) {
    rays.origins.row(r) << -1.0, height(engine), height(engine);
    rays.directions.row(r) << 1.0, 0.0, 0.0;
  }
  rays.depth_scale.setOnes(n);
  rays.near.setConstant(n, 0.4);
  rays.far.setConstant(n, 1.6);
  // The pixels: the same field rendered with 4000 equal sections (converged).
  SectionSampler fine(4000, {});
  fine.parameters().setZero();  // zero logits: equal sections
  DensityActivation density;
  Eigen::VectorXd unused;
  const Eigen::MatrixXd background = Eigen::RowVector3d(1, 1, 1);
  Eigen::MatrixXd truth = Eigen::MatrixXd::Zero(n, 3);
  {
    // loss_and_gradient against a black target is ‖C‖²/R per ray, not C; render directly.
    const integrators::RaySamples<double> sections = fine.sections(rays);
    const Eigen::MatrixXd x = SectionSampler::end_points(rays, fine.boundaries(rays));
    autodiff::StreamSpec spec = autodiff::StreamSpec::values(6);
    const autodiff::Streams<double> phi = field(autodiff::StreamLayout(spec), x);
    Eigen::MatrixXd means(sections.size(), 4);
    for (Eigen::Index r = 0; r < n; ++r)
      for (int i = 0; i < 4000; ++i)
        means.row(r * 4000 + i) = (phi.stream(0).row(r * 4001 + i + 1) - phi.stream(0).row(r * 4001 + i)) /
                                  sections.delta(r * 4000 + i);
    const Shading shading = shade(means, density);
    truth = integrators::render<double>(sections, shading.sigma, shading.rgb, background).color;
  }
  SectionSamplerOptions options;
  options.learning_rate = 1e-2;
  options.min_share = 0.1;
  SectionSampler sampler(4, options);
  const double before = sampler.loss_and_gradient(rays, truth, background, field, density, 1, unused).loss;
  for (int step = 0; step < 300; ++step) sampler.update(rays, truth, background, field, density, 1);
  const double after = sampler.loss_and_gradient(rays, truth, background, field, density, 1, unused).loss;
  std::printf("rendering error %.3e -> %.3e: %.0f-fold\n", before, after, before / after);
  // Equal sections: 3.0e-2; after 300 steps 3.0e-6 (10,169-fold on 2026-11-26, too close to
  // 10⁴ to assert), the boundaries at x = 0.046 and 0.254.
  EXPECT_LT(after, 1e-3 * before) << "before " << before;
  // A section now lies close around the slab (x = t − 1 along these rays).
  const Eigen::MatrixXd t = sampler.boundaries(rays);
  double tightest = 1e9;
  for (int i = 0; i < 4; ++i)
    if (t(0, i) - 1 <= a + 0.01 && t(0, i + 1) - 1 >= b - 0.01) tightest = std::min(tightest, t(0, i + 1) - t(0, i));
  EXPECT_LT(tightest, 0.22) << "the slab is 0.2 long, equal sections 0.3";
}

TEST(SectionSampler, AnUpdateReadsTheFirstRaysOfTheBatchOnly) {
  const fields::Field<double> field = random_integral_field();
  std::mt19937_64 engine(5);
  const integrators::Rays<double> rays = random_rays(12, engine);
  Eigen::MatrixXd target = Eigen::MatrixXd::Constant(12, 3, 0.5);
  const Eigen::MatrixXd background = Eigen::RowVector3d(1, 1, 1);
  SectionSamplerOptions options;
  options.rays = 6;
  SectionSampler a(4, options), b(4, options);
  const SamplerUpdate first = a.update(rays, target, background, streams_of(field), {}, 10);
  target.bottomRows(6).setZero();  // pixels of rays the update does not read
  const SamplerUpdate second = b.update(rays, target, background, streams_of(field), {}, 10);
  EXPECT_EQ(first.loss, second.loss);
  EXPECT_EQ(a.parameters(), b.parameters());
  target.row(0).setZero();  // a pixel it reads
  SectionSampler c(4, options);
  EXPECT_NE(c.update(rays, target, background, streams_of(field), {}, 10).loss, first.loss);
}

TEST(SectionSampler, IsSavedAndLoadedWithItsAdamState) {
  const fields::Field<double> field = random_integral_field();
  std::mt19937_64 engine(4);
  const integrators::Rays<double> rays = random_rays(16, engine);
  const Eigen::MatrixXd target = Eigen::MatrixXd::Constant(16, 3, 0.5);
  const Eigen::MatrixXd background = Eigen::RowVector3d(1, 1, 1);
  SectionSampler trained(6, {});
  for (int i = 0; i < 3; ++i) trained.update(rays, target, background, streams_of(field), {}, 10);
  const auto path = testutil::scratch_dir("section_sampler") / "sampler.h5";
  {
    io::H5Writer file(path);
    trained.save(file, "sampler");
    file.commit();
  }
  SectionSampler loaded(6, {});
  loaded.load(io::H5Reader(path), "sampler");
  EXPECT_EQ(loaded.parameters(), trained.parameters());
  // The same next step: the Adam moments and step count came along.
  trained.update(rays, target, background, streams_of(field), {}, 10);
  loaded.update(rays, target, background, streams_of(field), {}, 10);
  EXPECT_EQ(loaded.parameters(), trained.parameters());
  EXPECT_EQ(loaded.boundaries(rays), trained.boundaries(rays));

  SectionSampler other_shape(7, {});
  try {
    other_shape.load(io::H5Reader(path), "sampler");
    FAIL() << "a sampler of 6 sections loaded into one of 7";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("6 sections"), std::string::npos) << e.what();
  }
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
  const double constant = testutil::best_constant_psnr_mean(kBunny / "transforms_test.json");
  std::printf("test views: PSNR %.2f dB, best constant %.2f dB\n", metrics["psnr_mean"].get<double>(), constant);
  // 16.63 dB over a best constant of 13.96 dB in a 2-thread run (2.7 dB).
  EXPECT_GT(metrics["psnr_mean"].get<double>(), constant + 1.5);
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

TEST(AutointNerf, SamplingNetworkTrainsBesideTheFieldAndRendersFromTheCheckpoint) {
  const auto dir = testutil::scratch_dir("autoint_nerf_sampler");
  std::string text = autoint_config("{sections: 8, samples_per_section: 2, density_scale: 10, sampler: {every: 2}}",
                                    "output: {dir: " + (dir / "run").string() + "}\n", true);
  RunSetup setup = load_run(testutil::write_config("autoint_sampler", text), {});
  EXPECT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(dir / "run/metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["sampling_network"].get<double>(), 1.0);
  EXPECT_GT(metrics["sampler_parameters"].get<double>(), 1000.0);
  EXPECT_GT(metrics["sampler_max_section_share"].get<double>(), 1.0);
  const double constant = testutil::best_constant_psnr_mean(kBunny / "transforms_test.json");
  std::printf("test views: PSNR %.2f dB, best constant %.2f dB\n", metrics["psnr_mean"].get<double>(), constant);
  // 16.58 dB over 13.96 dB in a 2-thread run (2.6 dB).
  EXPECT_GT(metrics["psnr_mean"].get<double>(), constant + 1.5);
  EXPECT_TRUE(io::H5Reader(dir / "run/checkpoint.h5").has_group("sampler"));
  // `nfield render` of the test poses from the checkpoint gives the run's own PSNR: the
  // sampling network came back with the field.
  RenderRequest poses;
  poses.poses = kBunny / "transforms_test.json";
  render_checkpoint(dir / "run/checkpoint.h5", poses, dir / "rendered");
  const io::Image rendered = io::read_png(dir / "rendered/view_007_render.png");
  const io::Image written = io::read_png(dir / "run/test_views/test_007_render.png");
  EXPECT_EQ(rendered.pixels, written.pixels);
}

}  // namespace
}  // namespace nfield::solvers
