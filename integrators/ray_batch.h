// SPDX-License-Identifier: MIT
//
// Training batches: rays through pixels drawn at random from all images of a dataset, with
// the pixels' colours.
//
// A draw picks one pixel uniformly among all pixels of all frames (frames share one size, so
// frame = k / (w·h), pixel = k mod (w·h)), with replacement, from the raw bits of a
// std::mt19937_64 (random_bits.h): a seed gives the same batch on every standard library.
// Rays pass through pixel centres; near and far are left at 0 and +∞ for the caller
// (set_bounds for a known depth range, clip_to_box for a scene box).
//
// Random backgrounds. The colours are composited on the dataset's background b; with alpha
// the same pixel on another background b' is rgb_b + (b' − b)(1 − a), exact (composite_on).
// Training on a fresh random b' per ray and rendering with that b' (volume_rendering.h takes a
// per-ray background) keeps a field from painting the background into empty space.
#pragma once

#include <random>

#include <Eigen/Core>

#include "integrators/multiview_dataset.h"
#include "integrators/rays.h"

namespace nfield::integrators {

template <typename Scalar>
struct PixelBatch {
  Rays<Scalar> rays;
  Matrix<Scalar> rgb;      // N × 3, composited on `background`
  Vector<Scalar> alpha;    // N
  Eigen::VectorXi frame;   // N: the frame of each ray
  Eigen::VectorXi pixel;   // N: its pixel r·width + c
  Eigen::Vector3d background = Eigen::Vector3d::Ones();  // what rgb is composited on
};

// `count` pixels drawn uniformly with replacement over all pixels of all frames.
template <typename Scalar>
PixelBatch<Scalar> sample_pixels(const MultiviewDataset& data, Eigen::Index count,
                                 std::mt19937_64& rng);

// Every pixel of one frame, in pixel order (for evaluation).
template <typename Scalar>
PixelBatch<Scalar> frame_pixels(const MultiviewDataset& data, int frame);

// The batch's colours on another background: 1 × 3 (one colour) or N × 3 (one per ray).
template <typename Scalar>
Matrix<Scalar> composite_on(const PixelBatch<Scalar>& batch,
                            const ConstMatrixRef<Scalar>& background);

}  // namespace nfield::integrators
