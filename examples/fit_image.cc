// SPDX-License-Identifier: MIT
//
// Example 1 — fit a SIREN to an image (Sitzmann et al. 2020, Fig. 1).
//
// What it shows: building a field, a loss over one stream (the value), the chunked
// forward/reverse pass, Adam, and then evaluating the trained field's gradient and
// Laplacian streams — derivatives the image was never trained on.
// (To fit images, sound clips and videos from a config, without code: `problem: fit`,
// solvers/problems/fit.cc and configs/fit_image.yaml; this program stays a tutorial.)
//
// Run:   build/examples/fit_image data/images/camera.png --steps 500 --out out/fit_image
// Small: build/examples/fit_image data/images/camera.png --crop 64 --steps 100 --min-psnr 25
// Writes reconstruction.png, gradient_norm.png and laplacian.png into --out.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "fields/field.h"
#include "io/image_file.h"
#include "io/png_image.h"
#include "solvers/training/adam.h"

using namespace nfield;

// 6. Value, gradient and Laplacian of the trained field on the pixel grid, written as
// pictures; returns the final mean squared error of the value.
double write_streams(const fields::Field<float>& field, const autodiff::Matrix<float>& coords,
                     const autodiff::Vector<float>& target, int size_x, int size_y, const std::string& out_dir) {
  const Eigen::Index n = coords.rows();
  const autodiff::StreamLayout laplacian(autodiff::StreamSpec::laplacian(2));
  autodiff::Streams<float> out;
  field.evaluate(laplacian, coords, out);
  const double final_mse = (out.stream(0).col(0) - target).squaredNorm() / n;
  auto as_image = [&](const Eigen::VectorXd& v) {
    Eigen::MatrixXd m(size_y, size_x);
    for (int r = 0; r < size_y; ++r)
      for (int c = 0; c < size_x; ++c) m(r, c) = v(static_cast<Eigen::Index>(r) * size_x + c);
    return m;
  };
  const Eigen::VectorXd value = out.stream(0).col(0).cast<double>();
  const Eigen::VectorXd gradient_norm =
      (out.stream(1).col(0).cast<double>().array().square() + out.stream(2).col(0).cast<double>().array().square()).sqrt();
  const Eigen::VectorXd lap = out.stream(3).col(0).cast<double>();
  std::filesystem::create_directories(out_dir);
  io::write_scalar_png(out_dir + "/reconstruction.png", as_image(value), {std::pair{-1.0, 1.0}, io::Colormap::kGrey});
  io::write_scalar_png(out_dir + "/gradient_norm.png", as_image(gradient_norm), {std::nullopt, io::Colormap::kGrey});
  // The Laplacian has a few huge values at edges: clip at its 99th percentile.
  Eigen::VectorXd sorted = lap.cwiseAbs();
  std::sort(sorted.data(), sorted.data() + sorted.size());
  const double clip = sorted(static_cast<Eigen::Index>(0.99 * (sorted.size() - 1)));
  io::write_scalar_png(out_dir + "/laplacian.png", as_image(lap), {std::pair{-clip, clip}, io::Colormap::kDiverging});
  return final_mse;
}

int main(int argc, char** argv) {
  std::string image_path, out_dir = "out/fit_image";
  int steps = 500, crop = 0;
  double lr = 1e-4, min_psnr = 0;
  std::vector<int> hidden{256, 256, 256, 256};
  CLI::App app{"Fit a SIREN to a PNG or WebP picture and write its gradient and Laplacian"};
  app.add_option("image", image_path, "PNG or WebP picture")->required()->check(CLI::ExistingFile);
  app.add_option("--steps", steps, "Adam steps")->check(CLI::Range(1, 1000000))->capture_default_str();
  app.add_option("--crop", crop, "Use the central crop of this many pixels (0: whole image)")->capture_default_str();
  app.add_option("--lr", lr, "Learning rate")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--hidden", hidden, "Hidden widths")->capture_default_str();
  app.add_option("--out", out_dir, "Output folder")->capture_default_str();
  app.add_option("--min-psnr", min_psnr, "Exit 1 if the final PSNR (dB) is below this")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  // 1. The image as grey values in [0, 1] (the central crop if asked).
  const io::Image image = io::read_image(image_path);
  const int size_x = crop > 0 ? std::min(crop, image.width) : image.width;
  const int size_y = crop > 0 ? std::min(crop, image.height) : image.height;
  const int x0 = (image.width - size_x) / 2, y0 = (image.height - size_y) / 2;
  const Eigen::Index n = static_cast<Eigen::Index>(size_x) * size_y;

  // 2. One sample per pixel: coordinates in [−1, 1]², (x right, y up), targets in [−1, 1].
  autodiff::Matrix<float> coords(n, 2);
  autodiff::Vector<float> target(n);
  for (int r = 0; r < size_y; ++r)
    for (int c = 0; c < size_x; ++c) {
      const Eigen::Index i = static_cast<Eigen::Index>(r) * size_x + c;
      coords(i, 0) = -1.0f + 2.0f * c / (size_x - 1);
      coords(i, 1) = 1.0f - 2.0f * r / (size_y - 1);
      const Eigen::Index p = static_cast<Eigen::Index>(y0 + r) * image.width + (x0 + c);
      target(i) = 2.0f * image.pixels.row(p).head(std::min(image.channels, 3)).mean() - 1.0f;
    }

  // 3. The SIREN of the paper: ω₀ = 30, float.
  fields::FieldOptions options;
  options.input_dim = 2;
  options.hidden = hidden;
  fields::Field<float> field(options);
  solvers::Adam<float> adam(field.parameter_count(), {lr});

  // 4. The loss: mean squared error of the value stream.
  const autodiff::StreamLayout values(autodiff::StreamSpec::values(2));
  autodiff::LambdaLoss<float> loss([&](Eigen::Index first, const autodiff::StreamLayout&,
                                       const autodiff::Streams<float>& out,
                                       autodiff::Streams<float>& adjoint) {
    const autodiff::Vector<float> r = out.stream(0).col(0) - target.segment(first, out.points);
    adjoint.stream(0).col(0) = (2.0f / n) * r;
    return static_cast<double>(r.squaredNorm()) / n;
  });
  // PSNR of images in [0, 1]: the target range [−1, 1] is twice as wide.
  auto psnr = [](double mse) { return 10.0 * std::log10(4.0 / mse); };

  // 5. Train.
  std::printf("fitting %dx%d pixels of %s with %ld parameters\n", size_x, size_y, image_path.c_str(),
              static_cast<long>(field.parameter_count()));
  autodiff::Vector<float> gradient(field.parameter_count());
  double mse = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int step = 1; step <= steps; ++step) {
    gradient.setZero();
    mse = field.value_and_gradient(field.parameters().data(), values, autodiff::Batch<float>{coords}, loss, gradient.data());
    adam.step(field.parameters().data(), gradient.data());
    if (step == 1 || step % std::max(1, steps / 10) == 0 || step == steps)
      std::printf("step %5d  PSNR %6.2f dB  (%.1f s)\n", step, psnr(mse),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  // 6. Value, gradient and Laplacian of the trained field on the pixel grid.
  const double final_mse = write_streams(field, coords, target, size_x, size_y, out_dir);
  std::printf("final PSNR %.2f dB; wrote reconstruction.png, gradient_norm.png, laplacian.png in %s\n",
              psnr(final_mse), out_dir.c_str());
  return psnr(final_mse) >= min_psnr ? 0 : 1;
}
