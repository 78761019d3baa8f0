// SPDX-License-Identifier: MIT
//
// The floor a radiance field's test PSNR must clear: the mean PSNR over the test views of
// the best constant image, the per-channel mean of all their pixels. A fixed number is no
// floor: on views that are mostly white background, an untrained field that renders the
// background already scores it.
#pragma once

#include <filesystem>

#include <Eigen/Core>

#include "integrators/multiview_dataset.h"
#include "io/image_metrics.h"

namespace nfield::testutil {

// `transforms` read as `problem: nerf` reads its test views (on the default white background).
inline double best_constant_psnr_mean(const std::filesystem::path& transforms) {
  const integrators::MultiviewDataset views = integrators::read_transforms(transforms);
  Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(3);
  Eigen::Index pixels = 0;
  for (const integrators::PosedImage& view : views.frames) {
    sum += view.rgb.cast<double>().colwise().sum();
    pixels += view.rgb.rows();
  }
  const Eigen::RowVectorXf mean = (sum / static_cast<double>(pixels)).cast<float>();
  double psnr_sum = 0;
  for (const integrators::PosedImage& view : views.frames)
    psnr_sum += io::psnr(mean.replicate(view.rgb.rows(), 1), view.rgb);
  return psnr_sum / static_cast<double>(views.frames.size());
}

}  // namespace nfield::testutil
