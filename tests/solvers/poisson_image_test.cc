// SPDX-License-Identifier: MIT
//
// Poisson image reconstruction (solvers/problems/poisson_image.cc): the gradient and
// Laplacian targets of a smooth picture against the picture's own derivatives in field
// coordinates (x right, y up, pixel centres over [−1, 1]²), the flux term's normals, a short
// fit from the gradient far above the best constant, and bad inputs located at their keys.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedShortArray.h>

#include "solvers/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;
using testutil::expect_located_error;
using testutil::write_config;

const fs::path kCamera = fs::path(NFIELD_SOURCE_DIR) / "data/images/camera.png";

// p(x, y) in field coordinates, and its derivatives.
double picture(double x, double y) { return 0.5 + 0.25 * std::sin(2 * x + 0.3) * std::cos(1.5 * y); }
double picture_dx(double x, double y) { return 0.5 * std::cos(2 * x + 0.3) * std::cos(1.5 * y); }
double picture_dy(double x, double y) { return -0.375 * std::sin(2 * x + 0.3) * std::sin(1.5 * y); }
double picture_laplacian(double x, double y) { return -(4 + 2.25) * (picture(x, y) - 0.5); }

// A 16-bit grey PNG of `picture` (8 bits would put quantization noise of 1/510 over h into
// the gradient); pixel (r, c) at x = −1 + 2c/(w − 1), y = 1 − 2r/(h − 1).
void write_smooth_picture(const fs::path& path, int width, int height) {
  vtkNew<vtkImageData> image;
  image->SetDimensions(width, height, 1);
  vtkNew<vtkUnsignedShortArray> values;
  values->SetNumberOfTuples(static_cast<vtkIdType>(width) * height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const double x = -1.0 + 2.0 * c / (width - 1), y = 1.0 - 2.0 * r / (height - 1);
      // VTK's row 0 is the bottom row of the picture.
      values->SetValue(static_cast<vtkIdType>(height - 1 - r) * width + c,
                       static_cast<unsigned short>(std::lround(picture(x, y) * 65535)));
    }
  image->GetPointData()->SetScalars(values);
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->SetFileName(path.c_str());
  writer->Write();
}

// The residual rows of term at x for a field whose gradient there is `gradient` (value and
// second derivatives 0).
Eigen::MatrixXd residual_rows(const LossTerm& term, const Eigen::MatrixXd& x, const Eigen::Vector2d& gradient) {
  const autodiff::StreamLayout layout(term.spec);
  autodiff::Streams<double> out;
  out.points = x.rows();
  out.count = layout.count();
  out.data = Eigen::MatrixXd::Zero(x.rows() * out.count, 1);
  if (layout.count() > 1)
    for (int a = 0; a < 2; ++a) out.data.middleRows(layout.tangent(a) * x.rows(), x.rows()).setConstant(gradient(a));
  Eigen::MatrixXd r;
  term.residual(x)->evaluate(0, layout, out, r);
  return r;
}

// Residual rows of a zero field: minus the targets.
Eigen::MatrixXd targets(const LossTerm& term, const Eigen::MatrixXd& x) {
  return -residual_rows(term, x, Eigen::Vector2d::Zero());
}

const char* kSmoothConfig = R"yaml(
problem: poisson_image
equation:
  image: smooth.png
  supervise: SUPERVISE
training: {batch: {interior: 200, boundary: 40}, stages: [{optimizer: adam, steps: 1}]}
)yaml";

fs::path smooth_config(const std::string& supervise) {
  std::string text = kSmoothConfig;
  text.replace(text.find("SUPERVISE"), 9, supervise);
  const fs::path config = write_config("poisson_image", text);
  write_smooth_picture(config.parent_path() / "smooth.png", 96, 80);
  return config;
}

// Away from the border (where the mirrored spline bends towards a zero normal derivative),
// the spline's derivatives are the smooth picture's, up to interpolation error.
TEST(PoissonImage, SplineTargetsAreThePicturesDerivatives) {
  Random rng(1);
  const RunSetup gradient_setup = load_run(smooth_config("gradient"), {});
  const std::vector<LossTerm> gradient_terms = gradient_setup.problem->loss_terms();
  ASSERT_EQ(gradient_terms.size(), 1u);
  Eigen::MatrixXd x = gradient_terms[0].sample(rng, 400).x;
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 1.0);
  x = 0.7 * x;  // at least 0.3 from the border: 12 pixels
  const Eigen::MatrixXd g = targets(gradient_terms[0], x);
  ASSERT_EQ(g.cols(), 2);
  // 16-bit quantization noise (±7.6e-6) through the prefilter and 1/h ≈ 48: a few 1e-4 at
  // worst, about 2e-4 as a root mean square; a scale error of 1 % would add 2e-3.
  double worst_g = 0, sum_g = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double ex = g(i, 0) - picture_dx(x(i, 0), x(i, 1)), ey = g(i, 1) - picture_dy(x(i, 0), x(i, 1));
    worst_g = std::max({worst_g, std::abs(ex), std::abs(ey)});
    sum_g += ex * ex + ey * ey;
  }
  const double rms_g = std::sqrt(sum_g / (2.0 * static_cast<double>(x.rows())));
  std::printf("gradient targets: worst error %.2e, rms %.2e\n", worst_g, rms_g);
  EXPECT_LT(worst_g, 1.5e-3);
  EXPECT_LT(rms_g, 4e-4);
  const RunSetup laplacian_setup = load_run(smooth_config("laplacian"), {});
  const std::vector<LossTerm> laplacian_terms = laplacian_setup.problem->loss_terms();
  ASSERT_EQ(laplacian_terms.size(), 2u);
  EXPECT_EQ(laplacian_terms[1].name, "flux");
  const Eigen::MatrixXd lap = targets(laplacian_terms[0], x);
  ASSERT_EQ(lap.cols(), 1);
  double sum = 0, cross = 0, square = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double truth = picture_laplacian(x(i, 0), x(i, 1));
    sum += (lap(i, 0) - truth) * (lap(i, 0) - truth);
    cross += lap(i, 0) * truth;
    square += truth * truth;
  }
  const double rms = std::sqrt(sum / static_cast<double>(x.rows())), slope = cross / square;
  std::printf("Laplacian targets: rms error %.2e (values up to 1.6), slope %.4f\n", rms, slope);
  // The same noise through 1/h² ≈ 2000 is about 0.05; it averages out of the least-squares
  // slope, which a sign or scale error of the coordinate map would move.
  EXPECT_LT(rms, 0.08);
  EXPECT_NEAR(slope, 1.0, 0.01);
}

// The flux term reads ∂u/∂n with the side's outward normal; the mirrored spline's normal
// derivative on the border is zero, so a field with u = x + 2y has residual n·(1, 2).
TEST(PoissonImage, FluxTermUsesTheOutwardNormal) {
  const RunSetup setup = load_run(smooth_config("laplacian"), {});
  const LossTerm flux = setup.problem->loss_terms().at(1);
  Random rng(2);
  const Eigen::MatrixXd x = flux.sample(rng, 200).x;
  const Eigen::MatrixXd r = residual_rows(flux, x, Eigen::Vector2d(1.0, 2.0));
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const bool x_side = std::abs(x(i, 0)) == 1.0;
    ASSERT_TRUE(x_side || std::abs(x(i, 1)) == 1.0) << x.row(i);
    const double expected = x_side ? x(i, 0) * 1.0 : x(i, 1) * 2.0;
    EXPECT_NEAR(r(i, 0), expected, 1e-9) << x.row(i);
  }
}

// ~2 s: camera.png averaged down by 8 (64 × 64) from its gradient only.
TEST(PoissonImage, ShortFitFromTheGradientIsFarAboveTheBestConstant) {
  const fs::path config = write_config("poisson_image", R"yaml(
problem: poisson_image
equation: {image: )yaml" + kCamera.string() + R"yaml(, supervise: gradient, downsample: 8}
field:
  type: mlp
  activation: relu
  hidden: [16]
  encoding: {type: hash_grid, levels: 6, features_per_level: 2, log2_table_size: 12, base_resolution: 4, finest_resolution: 64}
training:
  batch: {interior: 2048}
  stages: [{optimizer: adam, steps: 200, lr: 1.0e-2, schedule: cosine, lr_final: 1.0e-4}]
output: {grid: [8, 8]}
)yaml");
  const fs::path out = config.parent_path() / "out";
  RunSetup setup = load_run(config, {}, out);
  ASSERT_EQ(execute_run(setup, {}), 0);
  std::ifstream in(out / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  const double psnr = metrics["psnr_db"].get<double>();
  std::printf("PSNR %.2f dB, SSIM %.4f\n", psnr, metrics["ssim"].get<double>());
  // The best constant of camera.png at 64² is about 11.5 dB.
  EXPECT_GT(psnr, 30.0);
  EXPECT_GT(metrics["ssim"].get<double>(), 0.9);
  EXPECT_TRUE(fs::exists(out / "reconstruction.png"));
  EXPECT_TRUE(fs::exists(out / "error.png"));
}

fs::path bad_config(const std::string& equation) {
  return write_config("poisson_image", "problem: poisson_image\nequation:\n  image: " + kCamera.string() + "\n" +
                                           equation + "training: {stages: [{optimizer: adam, steps: 1}]}\n");
}

TEST(PoissonImage, BadKeysAreLocated) {
  expect_located_error(bad_config("  derivatives: sobel\n"), {4, 16, "equation.derivatives", "spline, central_differences"});
  expect_located_error(bad_config("  downsample: 200\n"), {4, 15, "equation.downsample", "[1, 64]"});
  const fs::path small = smooth_config("gradient\n  downsample: 40");  // 96 x 80 pixels
  expect_located_error(small, {6, 15, "equation.downsample", "fewer than 3 pixels of the 96 x 80 image"});
  expect_located_error(bad_config("  flux_weight: -1\n"), {4, 16, "equation.flux_weight", ""});
  expect_located_error(bad_config("  zoom: 2\n"), {4, 3, "equation.zoom", "unknown key 'zoom'"});
  const fs::path thin = smooth_config("gradient");
  write_smooth_picture(thin.parent_path() / "smooth.png", 40, 2);
  expect_located_error(thin, {4, 10, "equation.image", "40 x 2 pixels"});
}

}  // namespace
}  // namespace nfield::solvers
