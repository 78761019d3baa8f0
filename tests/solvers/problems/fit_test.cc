// SPDX-License-Identifier: MIT
//
// Signal fitting (solvers/problems/fit.cc): the samples' coordinates and targets (per scale
// for a multiscale field), a small image fit far above the best constant image, short audio
// and video fits that write their files (the WAV reads back at the clip's rate and length;
// io::write_audio itself: tests/io/audio_test.cc), and bad inputs located at their keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "io/audio.h"
#include "io/png_image.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/core/residual.h"
#include "solvers/core/solution.h"
#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
using testutil::expect_located_error;
using testutil::write_config;

const fs::path kCamera = fs::path(NFIELD_SOURCE_DIR) / "data/images/camera.png";

nlohmann::json run_and_read_metrics(const fs::path& config, const fs::path& out) {
  RunSetup setup = load_run(config, {}, out);
  EXPECT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(out / "metrics.json");
  return nlohmann::json::parse(in);
}

// A small RGB picture whose colours vary with (c, r) and the frame f.
io::Image test_picture(int width, int height, int f) {
  io::Image image{width, height, 3, Eigen::MatrixXf(static_cast<Eigen::Index>(width) * height, 3)};
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      image.pixels.row(static_cast<Eigen::Index>(r) * width + c)
          << static_cast<float>(c) / static_cast<float>(width), static_cast<float>(r) / static_cast<float>(height),
          0.25f * static_cast<float>(f);
  return image;
}

// A 16 kHz clip of 0.1 s: two tones.
fs::path write_tones(const fs::path& dir) {
  io::AudioClip clip{16000, Eigen::VectorXd(1600)};
  for (Eigen::Index i = 0; i < clip.samples.size(); ++i) {
    const double t = static_cast<double>(i) / clip.sample_rate;
    clip.samples(i) = 0.5 * std::sin(2 * std::numbers::pi * 440 * t) + 0.2 * std::sin(2 * std::numbers::pi * 1250 * t);
  }
  io::write_audio(dir / "tones.wav", clip);
  return dir / "tones.wav";
}

TEST(Fit, SamplesAreThePixelCentresAndTheirTargetsThePixels) {
  const fs::path config = write_config("fit", R"yaml(
problem: fit
equation: {signal: image, path: frame.png}
training: {batch: {interior: 100000}, stages: [{optimizer: adam, steps: 1}]}
)yaml");
  const io::Image picture = test_picture(4, 3, 1);
  io::write_png(config.parent_path() / "frame.png", picture);
  const RunSetup setup = load_run(config, {});
  EXPECT_EQ(setup.problem->output_dim(), 3);
  EXPECT_EQ(setup.problem->field_input_dim(), 2);
  const std::vector<LossTerm> terms = setup.problem->loss_terms();
  ASSERT_EQ(terms.size(), 1u);
  Random rng(0);
  const TermPoints all = terms[0].sample(rng, 100000);  // more than the pixels: all of them
  ASSERT_EQ(all.x.rows(), 12);
  // Pixel (r, c) at x = -1 + (2c + 1)/4, y = 1 - (2r + 1)/3 (y up).
  EXPECT_DOUBLE_EQ(all.x(0, 0), -0.75);
  EXPECT_DOUBLE_EQ(all.x(0, 1), 1.0 - 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(all.x(11, 0), 0.75);
  EXPECT_DOUBLE_EQ(all.x(11, 1), -1.0 + 1.0 / 3.0);
  // The residual of a zero field is minus the (8-bit) pixel values.
  const auto residual = terms[0].residual(all);
  const autodiff::StreamLayout layout(terms[0].spec);
  autodiff::Streams<double> out;
  out.points = 12;
  out.count = layout.count();
  out.data = Eigen::MatrixXd::Zero(12 * out.count, 3);
  Eigen::MatrixXd r;
  residual->evaluate(0, layout, out, r);
  ASSERT_EQ(r.rows(), 12);
  ASSERT_EQ(r.cols(), 3);
  for (int i = 0; i < 12; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(-r(i, c), picture.pixels(i, c), 0.51 / 255) << i << " " << c;
  // Fewer: random pixels, each with its own target.
  const TermPoints some = terms[0].sample(rng, 5);
  EXPECT_EQ(some.x.rows(), 5);
}

// The pixel (r · width + c) that a drawn point of a width × height picture stands for.
std::vector<int> drawn_pixels(const TermPoints& points, int width, int height) {
  std::vector<int> pixels;
  for (Eigen::Index i = 0; i < points.x.rows(); ++i) {
    const long c = std::lround(((points.x(i, 0) + 1) * width - 1) / 2);
    const long r = std::lround(((1 - points.x(i, 1)) * height - 1) / 2);
    pixels.push_back(static_cast<int>(r * width + c));
  }
  return pixels;
}

// draws: epochs (the default): 12 pixels in batches of 5, each 12 consecutive draws a
// permutation of all of them, a new order each epoch, the same draws for a step whatever came
// before it (resume), another order for another training.seed; `independent` repeats pixels
// within an epoch; outside training (no step said) the draws are independent.
TEST(Fit, DrawsInEpochsTakeEveryPixelOncePerEpoch) {
  const fs::path config = write_config("fit_epochs", R"yaml(
problem: fit
equation: {signal: image, path: frame.png}
training: {seed: 3, batch: {interior: 5}, stages: [{optimizer: adam, steps: 1}]}
)yaml");
  io::write_png(config.parent_path() / "frame.png", test_picture(4, 3, 1));
  const Solution solution;
  const auto draws = [&](const std::vector<std::string>& sets, long first, long steps) {
    const RunSetup setup = load_run(config, sets);
    auto* sampling = capability<SamplesWithSolution>(*setup.problem);
    EXPECT_NE(sampling, nullptr);
    const LossTerm term = setup.problem->loss_terms().at(0);
    Random rng(0);
    std::vector<int> pixels;
    for (long step = first; step < first + steps; ++step) {
      sampling->before_step(step, solution, rng);
      const std::vector<int> batch = drawn_pixels(term.sample(rng, 5), 4, 3);
      pixels.insert(pixels.end(), batch.begin(), batch.end());
    }
    return pixels;
  };
  const std::vector<int> epochs = draws({}, 0, 12);  // 60 draws: five epochs
  std::vector<std::vector<int>> orders;
  for (size_t e = 0; e < 5; ++e) {
    std::vector<int> order(epochs.begin() + 12 * e, epochs.begin() + 12 * (e + 1));
    orders.push_back(order);
    std::sort(order.begin(), order.end());
    for (int k = 0; k < 12; ++k) EXPECT_EQ(order[k], k) << "epoch " << e;
  }
  EXPECT_NE(orders[0], orders[1]);
  EXPECT_NE(orders[1], orders[2]);
  const std::vector<int> resumed = draws({}, 7, 2);
  EXPECT_EQ(resumed, std::vector<int>(epochs.begin() + 35, epochs.begin() + 45));
  EXPECT_NE(draws({"training.seed=4"}, 0, 12), epochs);

  const std::vector<int> independent = draws({"equation.draws=independent"}, 0, 12);
  bool repeats = false;
  for (size_t e = 0; e < 5; ++e) {
    std::vector<int> order(independent.begin() + 12 * e, independent.begin() + 12 * (e + 1));
    std::sort(order.begin(), order.end());
    repeats = repeats || std::adjacent_find(order.begin(), order.end()) != order.end();
  }
  EXPECT_TRUE(repeats);
  // No step said: the trainer's engine decides, so two engines draw differently.
  const RunSetup setup = load_run(config, {});
  const LossTerm term = setup.problem->loss_terms().at(0);
  Random first(1), second(2);
  EXPECT_NE(drawn_pixels(term.sample(first, 5), 4, 3), drawn_pixels(term.sample(second, 5), 4, 3));

  const fs::path bad = write_config("fit_epochs_bad", R"yaml(
problem: fit
equation: {signal: image, path: frame.png, draws: sometimes}
)yaml");
  io::write_png(bad.parent_path() / "frame.png", test_picture(4, 3, 1));
  expect_located_error(bad, {3, 51, "equation.draws", "epochs, independent"});
}

// The periodic projection onto the modes |m| ≤ k of n samples, written out as a matrix:
// (1/n)(1 + 2 Σ_{m=1..k} cos(2π m (i − j)/n)), the identity when 2k ≥ n.
Eigen::MatrixXd lowpass_matrix(Eigen::Index n, Eigen::Index k) {
  if (2 * k >= n) return Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      double sum = 1;
      for (Eigen::Index m = 1; m <= k; ++m)
        sum += 2 * std::cos(2 * std::numbers::pi * static_cast<double>(m * (i - j)) / static_cast<double>(n));
      a(i, j) = sum / static_cast<double>(n);
    }
  return a;
}

// −r of a field whose outputs are all zero: the targets, points × channels.
Eigen::MatrixXd targets(const Residual& residual, const LossTerm& term, Eigen::Index points) {
  const autodiff::StreamLayout layout(term.spec);
  autodiff::Streams<double> out;
  out.points = points;
  out.count = layout.count();
  out.data = Eigen::MatrixXd::Zero(points * out.count, residual.components());
  Eigen::MatrixXd r;
  residual.evaluate(0, layout, out, r);
  return -r;
}

// A BACON field's scales (HasScaleTargets): with scale_targets: band_limited (the default)
// scale s is trained against the picture's modes up to its cut-off along each axis (here
// 2, 4 and 8 cycles over the box: 16 × 12 pixels keep all at the finest), the plain
// residual is the finest scale's, and ResidualLoss::evaluate_scale reads scale s's; with
// `signal` every scale's target is the picture.
TEST(Fit, MultiscaleFieldsTrainEachScaleOnThePicturesBandLimitedPart) {
  const fs::path config = write_config("fit_scales", R"yaml(
problem: fit
equation: {signal: image, path: frame.png}
field: {type: bacon, hidden: [8, 8, 8], resolution: [4, 8, 16]}
training: {batch: {interior: 100000}, stages: [{optimizer: adam, steps: 1}]}
)yaml");
  io::Image picture = test_picture(16, 12, 1);
  for (Eigen::Index i = 0; i < picture.pixels.rows(); ++i)  // some detail at every scale
    picture.pixels(i, 2) = static_cast<float>((i * 37) % 11) / 10.0f;
  io::write_png(config.parent_path() / "frame.png", picture);
  const auto residuals = [&](const std::vector<std::string>& overrides) {
    const RunSetup setup = load_run(config, overrides);
    const LossTerm term = setup.problem->loss_terms().at(0);
    Random rng(0);
    return std::pair{term, term.residual(term.sample(rng, 100000))};
  };
  const auto [term, residual] = residuals({});
  const Eigen::MatrixXd picture_values = targets(residual->at_scale(2), term, 192);
  EXPECT_EQ(targets(*residual, term, 192), picture_values);  // the plain residual: the output scale's
  for (int s = 0; s < 3; ++s) {
    const Eigen::Index k = Eigen::Index{2} << s;
    const Eigen::MatrixXd ax = lowpass_matrix(16, k), ay = lowpass_matrix(12, k);
    const Eigen::MatrixXd got = targets(residual->at_scale(s), term, 192);
    for (Eigen::Index c = 0; c < 3; ++c) {
      // Samples run x fastest: a 16 × 12 column-major matrix per channel.
      const Eigen::MatrixXd grid = Eigen::Map<const Eigen::MatrixXd>(picture_values.col(c).data(), 16, 12);
      const Eigen::MatrixXd expected = ax * grid * ay.transpose();
      EXPECT_LT((Eigen::Map<const Eigen::MatrixXd>(got.col(c).data(), 16, 12) - expected).cwiseAbs().maxCoeff(), 1e-6)
          << "scale " << s << " channel " << c;
      if (s < 2) EXPECT_GT((expected - grid).cwiseAbs().maxCoeff(), 0.05) << "scale " << s << " channel " << c;
    }
    // The loss of scale s reads scale s's target: (1/N) Σ target² for zero outputs.
    const ResidualLoss<double> loss(*residual, 1.0, 192);
    const autodiff::StreamLayout layout(term.spec);
    autodiff::Streams<double> out, adjoint;
    out.points = adjoint.points = 192;
    out.count = adjoint.count = layout.count();
    out.data = adjoint.data = Eigen::MatrixXd::Zero(192 * layout.count(), 3);
    EXPECT_NEAR(loss.evaluate_scale(s, 0, layout, out, adjoint), got.squaredNorm() / 192, 1e-12) << "scale " << s;
  }
  EXPECT_THROW(residual->at_scale(3), std::invalid_argument);

  const auto [plain_term, plain] = residuals({"equation.scale_targets=signal"});
  EXPECT_EQ(targets(plain->at_scale(0), plain_term, 192), picture_values);
  const fs::path bad = write_config("fit_scales_bad", R"yaml(
problem: fit
equation: {signal: image, path: frame.png, scale_targets: lowpass}
)yaml");
  io::write_png(bad.parent_path() / "frame.png", picture);
  expect_located_error(bad, {3, 59, "equation.scale_targets", "band_limited, signal"});
}

// ~1 s: a 32 × 32 crop of camera.png through a small hash grid, 150 Adam steps.
TEST(Fit, SmallImageFitIsFarAboveTheBestConstant) {
  const fs::path config = write_config("fit", R"yaml(
problem: fit
equation: {signal: image, path: )yaml" + kCamera.string() + R"yaml(, crop: 32}
field:
  type: mlp
  activation: relu
  hidden: [16]
  encoding: {type: hash_grid, levels: 4, features_per_level: 2, log2_table_size: 12, base_resolution: 4, finest_resolution: 32}
training:
  batch: {interior: 1024}
  stages: [{optimizer: adam, steps: 150, lr: 1.0e-2, schedule: cosine, lr_final: 1.0e-4}]
)yaml");
  const fs::path out = config.parent_path() / "out";
  const nlohmann::json metrics = run_and_read_metrics(config, out);
  // The best constant image is the crop's mean: its PSNR is 10 log10(1 / variance).
  const io::Image camera = io::read_png(kCamera);
  Eigen::VectorXd crop(32 * 32);
  for (int r = 0; r < 32; ++r)
    for (int c = 0; c < 32; ++c) crop(r * 32 + c) = camera.pixels((240 + r) * 512 + 240 + c, 0);
  const double variance = (crop.array() - crop.mean()).square().mean();
  const double constant = 10 * std::log10(1 / variance);
  std::printf("PSNR %.2f dB, best constant %.2f dB\n", metrics["psnr_db"].get<double>(), constant);
  EXPECT_GT(metrics["psnr_db"].get<double>(), constant + 20);
  EXPECT_GT(metrics["ssim"].get<double>(), 0.9);
  EXPECT_LT(metrics["stages"][0]["rel_l2"].get<double>(), 0.05);
  const io::Image reconstruction = io::read_png(out / "reconstruction.png");
  EXPECT_EQ(reconstruction.width, 32);
  EXPECT_EQ(reconstruction.height, 32);
  EXPECT_EQ(reconstruction.channels, 1);
  EXPECT_TRUE(fs::exists(out / "error.png"));

  // `nfield eval` of the checkpoint: the same outputs from the field evaluated in double.
  const nlohmann::ordered_json evaluated = evaluate_checkpoint(out / "checkpoint.h5", 8, out / "eval");
  EXPECT_NEAR(evaluated["psnr_db"].get<double>(), metrics["psnr_db"].get<double>(), 0.01);
  EXPECT_NEAR(evaluated["rel_l2"].get<double>(), metrics["rel_l2"].get<double>(), 1e-4);
  EXPECT_TRUE(fs::exists(out / "eval" / "reconstruction.png"));
  EXPECT_TRUE(fs::exists(out / "eval" / "metrics.json"));
}

TEST(Fit, AudioFitWritesAWavOfTheClipsRateAndLength) {
  const fs::path config = write_config("fit", R"yaml(
problem: fit
equation: {signal: audio, path: tones.wav, seconds: [0.0, 0.05], time_scale: 2}
field:
  type: mlp
  activation: relu
  hidden: [16]
  encoding: {type: hash_grid, levels: 6, features_per_level: 2, log2_table_size: 12, base_resolution: 8, finest_resolution: 800}
training:
  batch: {interior: 2000}
  stages: [{optimizer: adam, steps: 40, lr: 1.0e-2}]
)yaml");
  write_tones(config.parent_path());
  const fs::path out = config.parent_path() / "out";
  const RunSetup setup = load_run(config, {}, out);
  EXPECT_EQ(setup.problem->domain().lower()[0], -2.0);
  const nlohmann::json metrics = run_and_read_metrics(config, out);
  EXPECT_TRUE(std::isfinite(metrics["snr_db"].get<double>()));
  EXPECT_GT(metrics["snr_db"].get<double>(), 3.0);
  EXPECT_EQ(metrics["samples"].get<double>(), 800.0);
  const io::AudioClip clip = io::read_audio(out / "reconstruction.wav");
  EXPECT_EQ(clip.sample_rate, 16000);
  EXPECT_EQ(clip.samples.size(), 800);
  EXPECT_TRUE(fs::exists(out / "waveform.png"));
}

TEST(Fit, VideoFitWritesFramesAndPerFramePsnrs) {
  const fs::path config = write_config("fit", R"yaml(
problem: fit
equation: {signal: video, path: frames, crop: [14, 12]}
field:
  type: mlp
  activation: relu
  hidden: [16]
  encoding: {type: hash_grid, levels: 4, features_per_level: 2, log2_table_size: 12, base_resolution: 2, finest_resolution: 16}
training:
  batch: {interior: 512}
  stages: [{optimizer: adam, steps: 60, lr: 1.0e-2}]
)yaml");
  const fs::path frames = config.parent_path() / "frames";
  fs::create_directories(frames);
  for (int f = 0; f < 3; ++f) io::write_png(frames / ("f" + std::to_string(f) + ".png"), test_picture(16, 12, f));
  std::ofstream(frames / "notes.txt") << "not a frame\n";
  const fs::path out = config.parent_path() / "out";
  const RunSetup setup = load_run(config, {}, out);
  EXPECT_EQ(setup.problem->field_input_dim(), 3);
  const nlohmann::json metrics = run_and_read_metrics(config, out);
  double sum = 0;
  for (const char* key : {"psnr_frame_000", "psnr_frame_001", "psnr_frame_002"}) {
    ASSERT_TRUE(metrics.contains(key)) << key;
    sum += metrics[key].get<double>();
  }
  EXPECT_FALSE(metrics.contains("psnr_frame_003"));
  EXPECT_NEAR(metrics["psnr_mean"].get<double>(), sum / 3, 1e-9);
  EXPECT_GT(metrics["psnr_mean"].get<double>(), 20.0);
  EXPECT_TRUE(metrics.contains("ssim_mean"));
  for (int f = 0; f < 3; ++f) {
    const io::Image frame = io::read_png(out / "frames" / ("reconstruction_00" + std::to_string(f) + ".png"));
    EXPECT_EQ(frame.width, 14);
    EXPECT_EQ(frame.height, 12);
    EXPECT_EQ(frame.channels, 3);
    EXPECT_TRUE(fs::exists(out / "frames" / ("error_00" + std::to_string(f) + ".png")));
  }
}

// write_outputs reuses the last reported_error's pass over every sample when the run says
// the field has not changed since, and evaluates anew otherwise; the metrics agree.
TEST(Fit, OutputsReuseTheLastStageEvaluationOnlyWhenTheFieldIsUnchanged) {
  const fs::path config = write_config("fit", R"yaml(
problem: fit
equation: {signal: image, path: frame.png}
training: {batch: {interior: 16}, stages: [{optimizer: adam, steps: 1}]}
)yaml");
  io::write_png(config.parent_path() / "frame.png", test_picture(5, 4, 1));
  const RunSetup setup = load_run(config, {});
  int evaluations = 0;
  OutputContext context;
  context.dir = config.parent_path() / "outputs";
  fs::create_directories(context.dir);
  context.values = [&](const Eigen::MatrixXd& x) {
    ++evaluations;
    return Eigen::MatrixXd(Eigen::MatrixXd::Constant(x.rows(), 3, 0.5));
  };
  const double reported = setup.problem->reported_error(context).value();
  ASSERT_EQ(evaluations, 1);

  const auto rel_l2 = [&](const OutputContext& c) {
    std::vector<std::pair<std::string, double>> metrics;
    setup.problem->write_outputs(c, metrics);
    for (const auto& [name, value] : metrics)
      if (name == "rel_l2") return value;
    return std::numeric_limits<double>::quiet_NaN();
  };
  OutputContext unchanged = context;
  unchanged.field_as_last_reported = true;
  EXPECT_DOUBLE_EQ(rel_l2(unchanged), reported);
  EXPECT_EQ(evaluations, 1);
  EXPECT_DOUBLE_EQ(rel_l2(unchanged), reported);  // the kept pass is used once, then evaluated anew
  EXPECT_EQ(evaluations, 2);
  EXPECT_DOUBLE_EQ(rel_l2(context), reported);
  EXPECT_EQ(evaluations, 3);
}

// ---- bad inputs, each located at its key ----------------------------------------------

fs::path bad_config(const std::string& equation) {
  return write_config("fit", "problem: fit\nequation:\n" + equation +
                                 "training: {stages: [{optimizer: adam, steps: 1}]}\n");
}

TEST(Fit, MissingFileIsLocatedAtThePath) {
  const fs::path config = bad_config("  signal: image\n  path: no_such.png\n");
  expect_located_error(config, {4, 9, "equation.path", "no_such.png"});
  const fs::path audio = bad_config("  signal: audio\n  path: no_such.wav\n");
  expect_located_error(audio, {4, 9, "equation.path", "no_such.wav"});
}

TEST(Fit, UnknownSignalListsTheValidOnes) {
  const fs::path config = bad_config("  signal: volume\n  path: a.png\n");
  expect_located_error(config, {3, 11, "equation.signal", "image, audio, video"});
}

TEST(Fit, UnknownKeysAndKeysOfAnotherSignalAreRejected) {
  fs::path config = bad_config("  signal: image\n  path: " + kCamera.string() + "\n  zoom: 2\n");
  expect_located_error(config, {5, 3, "equation.zoom", "unknown key 'zoom'"});
  config = bad_config("  signal: audio\n  path: tones.wav\n  crop: 64\n");
  write_tones(config.parent_path());
  expect_located_error(config, {5, 3, "equation.crop", "unknown key 'crop'"});
  config = bad_config("  signal: image\n  path: " + kCamera.string() + "\n  channels: cmyk\n");
  expect_located_error(config, {5, 13, "equation.channels", "auto, grey, rgb"});
  config = bad_config("  signal: audio\n  path: tones.wav\n  seconds: [0, 5]\n");
  write_tones(config.parent_path());
  expect_located_error(config, {5, 12, "equation.seconds", "0.1"});
}

TEST(Fit, AFrameOfAnotherSizeIsNamed) {
  const fs::path config = bad_config("  signal: video\n  path: frames\n");
  const fs::path frames = config.parent_path() / "frames";
  fs::create_directories(frames);
  io::write_png(frames / "a.png", test_picture(16, 12, 0));
  io::write_png(frames / "b.png", test_picture(16, 12, 1));
  io::write_png(frames / "c.png", test_picture(12, 16, 2));
  expect_located_error(config, {4, 9, "equation.path", "c.png: a frame of 12 x 16 pixels"});
}

TEST(Fit, AFolderWithoutFramesOrNoFolderIsRejected) {
  const fs::path config = bad_config("  signal: video\n  path: frames\n");
  fs::create_directories(config.parent_path() / "frames");
  std::ofstream(config.parent_path() / "frames/readme.txt") << "no frames\n";
  expect_located_error(config, {4, 9, "equation.path", "no frames (*.png, *.webp)"});
  const fs::path file = bad_config("  signal: video\n  path: " + kCamera.string() + "\n");
  expect_located_error(file, {4, 9, "equation.path", "expected a folder of PNG or WebP frames"});
}

}  // namespace
}  // namespace nfield::solvers
