// SPDX-License-Identifier: MIT
#include "integrators/dataset_views.h"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

namespace nfield::integrators {

MultiviewDataset single_frame(const MultiviewDataset& data, int frame) {
  if (frame < 0 || frame >= static_cast<int>(data.frames.size()))
    throw std::invalid_argument("single_frame: frame = " + std::to_string(frame) + ": must be in [0, " +
                                std::to_string(data.frames.size()) + ")");
  MultiviewDataset one;
  one.source = data.source;
  one.intrinsics = data.intrinsics;
  one.background = data.background;
  one.frames = {data.frames[static_cast<std::size_t>(frame)]};
  return one;
}

MultiviewDataset frame_columns(const MultiviewDataset& data, int frame, int begin, int end) {
  MultiviewDataset band = single_frame(data, frame);
  const int width = data.intrinsics.width, height = data.intrinsics.height;
  if (begin < 0 || end > width || begin >= end)
    throw std::invalid_argument("frame_columns: columns [" + std::to_string(begin) + ", " + std::to_string(end) +
                                "): expected 0 <= begin < end <= width = " + std::to_string(width));
  PosedImage& image = band.frames.front();
  const int kept = end - begin;
  Eigen::MatrixXf rgb(Eigen::Index{kept} * height, 3);
  Eigen::VectorXf alpha(Eigen::Index{kept} * height);
  for (int r = 0; r < height; ++r)
    for (int c = begin; c < end; ++c) {
      const Eigen::Index from = Eigen::Index{r} * width + c, to = Eigen::Index{r} * kept + (c - begin);
      rgb.row(to) = image.rgb.row(from);
      alpha(to) = image.alpha(from);
    }
  image.rgb = std::move(rgb);
  image.alpha = std::move(alpha);
  for (Intrinsics* intrinsics : {&band.intrinsics, &image.camera.intrinsics}) {
    intrinsics->width = kept;
    intrinsics->cx -= begin;
  }
  return band;
}

Recolouring draw_recolouring(int frames, double scale_low, double scale_high, double shift_low, double shift_high,
                             std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  const auto uniform = [&](double low, double high) {
    return low + (high - low) * (static_cast<double>(engine() >> 11) * 0x1.0p-53);
  };
  Recolouring r{Eigen::MatrixXd(frames, 3), Eigen::MatrixXd(frames, 3)};
  for (int k = 0; k < frames; ++k)
    for (int c = 0; c < 3; ++c) {
      r.scale(k, c) = uniform(scale_low, scale_high);
      r.shift(k, c) = uniform(shift_low, shift_high);
    }
  return r;
}

void recolour(MultiviewDataset& data, const Recolouring& recolouring) {
  const auto frames = static_cast<Eigen::Index>(data.frames.size());
  if (recolouring.scale.rows() != frames || recolouring.shift.rows() != frames || recolouring.scale.cols() != 3 ||
      recolouring.shift.cols() != 3)
    throw std::invalid_argument("recolour: " + std::to_string(recolouring.scale.rows()) + " scales and " +
                                std::to_string(recolouring.shift.rows()) + " shifts for " + std::to_string(frames) +
                                " frames (3 channels each)");
  for (Eigen::Index k = 0; k < frames; ++k) {
    PosedImage& image = data.frames[static_cast<std::size_t>(k)];
    for (Eigen::Index p = 0; p < image.rgb.rows(); ++p) {
      const double a = image.alpha(p);
      for (int c = 0; c < 3; ++c) {
        const double behind = (1 - a) * data.background(c);
        const double premultiplied = image.rgb(p, c) - behind;
        const double coloured = recolouring.scale(k, c) * premultiplied + a * recolouring.shift(k, c);
        image.rgb(p, c) = static_cast<float>(std::clamp(coloured, 0.0, a) + behind);
      }
    }
  }
}

}  // namespace nfield::integrators
