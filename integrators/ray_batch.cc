// SPDX-License-Identifier: MIT
#include "integrators/ray_batch.h"

#include <stdexcept>
#include <string>

#include "integrators/camera.h"
#include "integrators/random_bits.h"

namespace nfield::integrators {
namespace {

template <typename Scalar>
PixelBatch<Scalar> empty_batch(const MultiviewDataset& data, Eigen::Index count) {
  PixelBatch<Scalar> batch;
  batch.rays.resize(count);
  batch.rgb.resize(count, 3);
  batch.alpha.resize(count);
  batch.frame.resize(count);
  batch.pixel.resize(count);
  batch.background = data.background;
  return batch;
}

template <typename Scalar>
void set_pixel(const MultiviewDataset& data, int frame, int pixel, PixelBatch<Scalar>& batch,
               Eigen::Index n) {
  const PosedImage& image = data.frames[frame];
  const int width = data.intrinsics.width;
  set_ray(image.camera, pixel % width + 0.5, pixel / width + 0.5, batch.rays, n);
  batch.rgb.row(n) = image.rgb.row(pixel).template cast<Scalar>();
  batch.alpha(n) = static_cast<Scalar>(image.alpha(pixel));
  batch.frame(n) = frame;
  batch.pixel(n) = pixel;
}

}  // namespace

template <typename Scalar>
PixelBatch<Scalar> sample_pixels(const MultiviewDataset& data, Eigen::Index count,
                                 std::mt19937_64& rng) {
  if (data.frames.empty()) throw std::invalid_argument("sample_pixels: the dataset has no frames");
  if (count < 0)
    throw std::invalid_argument("sample_pixels: count = " + std::to_string(count) + ": must be >= 0");
  const auto per_image = static_cast<std::uint64_t>(data.pixels_per_image());
  const std::uint64_t total = per_image * data.frames.size();
  auto batch = empty_batch<Scalar>(data, count);
  for (Eigen::Index n = 0; n < count; ++n) {
    const std::uint64_t k = uniform_index(rng, total);
    set_pixel(data, static_cast<int>(k / per_image), static_cast<int>(k % per_image), batch, n);
  }
  return batch;
}

template <typename Scalar>
PixelBatch<Scalar> frame_pixels(const MultiviewDataset& data, int frame) {
  if (frame < 0 || frame >= static_cast<int>(data.frames.size()))
    throw std::invalid_argument("frame_pixels: frame = " + std::to_string(frame) +
                                ": must be in [0, " + std::to_string(data.frames.size()) + ")");
  const auto n = data.pixels_per_image();
  auto batch = empty_batch<Scalar>(data, n);
  for (Eigen::Index p = 0; p < n; ++p) set_pixel(data, frame, static_cast<int>(p), batch, p);
  return batch;
}

template <typename Scalar>
Matrix<Scalar> composite_on(const PixelBatch<Scalar>& batch,
                            const ConstMatrixRef<Scalar>& background) {
  const Eigen::Index n = batch.rgb.rows();
  if ((background.rows() != 1 && background.rows() != n) || background.cols() != 3)
    throw std::invalid_argument("composite_on: background is " + std::to_string(background.rows()) +
                                " x " + std::to_string(background.cols()) + ", expected 1 x 3 or " +
                                std::to_string(n) + " x 3");
  Matrix<Scalar> out(n, 3);
  const Eigen::Matrix<Scalar, 1, 3> old = batch.background.transpose().template cast<Scalar>();
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto b = background.row(background.rows() == 1 ? 0 : i);
    out.row(i) = batch.rgb.row(i) + (b - old) * (Scalar(1) - batch.alpha(i));
  }
  return out;
}

#define NFIELD_INSTANTIATE(Scalar)                                                           \
  template PixelBatch<Scalar> sample_pixels(const MultiviewDataset&, Eigen::Index,           \
                                            std::mt19937_64&);                               \
  template PixelBatch<Scalar> frame_pixels(const MultiviewDataset&, int);                    \
  template Matrix<Scalar> composite_on<Scalar>(const PixelBatch<Scalar>&,                            \
                                       const ConstMatrixRef<Scalar>&);
NFIELD_INSTANTIATE(float)
NFIELD_INSTANTIATE(double)
#undef NFIELD_INSTANTIATE

}  // namespace nfield::integrators
