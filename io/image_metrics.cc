// SPDX-License-Identifier: MIT
#include "io/image_metrics.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace nfield::io {
namespace {

void check_shapes(const Eigen::MatrixXf& image, const Eigen::MatrixXf& reference) {
  if (image.rows() != reference.rows() || image.cols() != reference.cols() || image.size() == 0)
    throw std::invalid_argument("image metrics: images of " + std::to_string(image.rows()) + " x " +
                                std::to_string(image.cols()) + " and " +
                                std::to_string(reference.rows()) + " x " +
                                std::to_string(reference.cols()) + " values");
}

constexpr int kWindow = 11;
constexpr double kSigma = 1.5;

// Valid-mode separable Gaussian filter of one channel (height × width, row-major in a
// column-major matrix: value (r, c) at img(c, r)).
Eigen::ArrayXXd filter(const Eigen::ArrayXXd& img, const Eigen::ArrayXd& g) {
  const Eigen::Index w = img.rows(), h = img.cols(), ow = w - kWindow + 1, oh = h - kWindow + 1;
  Eigen::ArrayXXd rows(ow, h), out(ow, oh);
  for (Eigen::Index r = 0; r < h; ++r)
    for (Eigen::Index c = 0; c < ow; ++c) rows(c, r) = (img.col(r).segment(c, kWindow) * g).sum();
  for (Eigen::Index r = 0; r < oh; ++r) {
    out.col(r).setZero();
    for (int k = 0; k < kWindow; ++k) out.col(r) += g(k) * rows.col(r + k);
  }
  return out;
}

}  // namespace

double psnr(const Eigen::MatrixXf& image, const Eigen::MatrixXf& reference) {
  check_shapes(image, reference);
  const double mse = (image.cast<double>() - reference.cast<double>()).squaredNorm() /
                     static_cast<double>(image.size());
  return mse > 0 ? -10.0 * std::log10(mse) : std::numeric_limits<double>::infinity();
}

double ssim(const Eigen::MatrixXf& image, const Eigen::MatrixXf& reference, int width, int height) {
  check_shapes(image, reference);
  if (static_cast<Eigen::Index>(width) * height != image.rows())
    throw std::invalid_argument("ssim: " + std::to_string(image.rows()) + " pixels for a " +
                                std::to_string(width) + " x " + std::to_string(height) + " image");
  if (width < kWindow || height < kWindow)
    throw std::invalid_argument("ssim: the image is smaller than the 11 x 11 window");
  Eigen::ArrayXd g(kWindow);
  for (int k = 0; k < kWindow; ++k) g(k) = std::exp(-0.5 * std::pow((k - kWindow / 2) / kSigma, 2));
  g /= g.sum();
  constexpr double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  double total = 0;
  for (Eigen::Index ch = 0; ch < image.cols(); ++ch) {
    const Eigen::ArrayXXd x = Eigen::Map<const Eigen::ArrayXXf>(image.col(ch).data(), width, height).cast<double>();
    const Eigen::ArrayXXd y = Eigen::Map<const Eigen::ArrayXXf>(reference.col(ch).data(), width, height).cast<double>();
    const Eigen::ArrayXXd mx = filter(x, g), my = filter(y, g);
    const Eigen::ArrayXXd sxx = filter(x * x, g) - mx * mx, syy = filter(y * y, g) - my * my,
                          sxy = filter(x * y, g) - mx * my;
    const Eigen::ArrayXXd map = ((2 * mx * my + c1) * (2 * sxy + c2)) /
                                ((mx * mx + my * my + c1) * (sxx + syy + c2));
    total += map.mean();
  }
  return total / static_cast<double>(image.cols());
}

}  // namespace nfield::io
