// SPDX-License-Identifier: MIT
//
// Image quality against a reference, as radiance-field papers report it.
//
//   PSNR = 10 log₁₀(1 / MSE), values in [0, 1], the mean over pixels and channels.
//   SSIM (Wang et al. 2004) per channel with an 11 × 11 Gaussian window of σ = 1.5,
//        C₁ = 0.01², C₂ = 0.03², over the windows that lie wholly inside the image ("valid"
//        filtering, as scikit-image's structural_similarity with gaussian_weights and
//        NeRF's evaluation code), then the mean over windows and channels.
// Images are io::Image pixel layouts: (height·width) × channels, row r·width + c.
#pragma once

#include <Eigen/Core>

namespace nfield::io {

// Throws std::invalid_argument when the shapes differ or the image is empty.
double psnr(const Eigen::MatrixXf& image, const Eigen::MatrixXf& reference);
// Also throws when the image is smaller than the window (11 × 11).
double ssim(const Eigen::MatrixXf& image, const Eigen::MatrixXf& reference, int width, int height);

}  // namespace nfield::io
