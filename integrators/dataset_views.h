// SPDX-License-Identifier: MIT
//
// New datasets made from a MultiviewDataset's frames: one frame alone, a band of its columns,
// and every frame recoloured. They serve NeRF in the Wild's protocol (solvers/problems/nerf.cc,
// data.appearance): one appearance code per image, and a test image's code fitted on its left
// half and scored on its right half.
//
// Columns. Pixel (r, c) of a frame is the ray through image point (c + ½, r + ½), its
// direction in the camera ∝ ((c + ½ − cx)/fx, …) (ray_batch.h, camera.h). Keeping columns
// [begin, end) and moving the principal point to cx − begin keeps every kept pixel's ray
// exactly: the band's pixel (r, c − begin) has (c − begin + ½ − (cx − begin))/fx, the same.
//
// Recolouring (NeRF-W's synthetic experiments, Martin-Brualla et al. 2021, Sec. 6): frame k's
// colour becomes c·s_k + b_k per channel, clamped to [0, 1], with s_k and b_k drawn uniformly
// from the given ranges. It applies to the object's straight (unpremultiplied) colour c, which
// is then composited on the dataset's background again: pixel rgb = a·c + (1 − a)·bg becomes
// a·clamp(c·s + b) + (1 − a)·bg = clamp(s·(rgb − (1 − a)·bg) + a·b, 0, a) + (1 − a)·bg. The
// background stays the renderer's constant: it is no part of the field, and recolouring it
// would give every image a backdrop colour no field can hold.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "integrators/multiview_dataset.h"

namespace nfield::integrators {

// Frame `frame` of `data` alone. Throws std::invalid_argument for a frame out of range.
MultiviewDataset single_frame(const MultiviewDataset& data, int frame);

// Frame `frame` of `data`, its columns [begin, end) alone (0 ≤ begin < end ≤ width), with the
// principal point moved so that each kept pixel keeps its ray. Throws std::invalid_argument.
MultiviewDataset frame_columns(const MultiviewDataset& data, int frame, int begin, int end);

// Per frame and channel, a scale and a shift (frames × 3 each).
struct Recolouring {
  Eigen::MatrixXd scale, shift;
};

// Scales from U(scale_low, scale_high) and shifts from U(shift_low, shift_high), per frame and
// channel, drawn from `seed` (the same on every platform).
Recolouring draw_recolouring(int frames, double scale_low, double scale_high, double shift_low, double shift_high,
                             std::uint64_t seed);

// Applies `recolouring` (one row per frame of `data`) as above. Throws std::invalid_argument
// when the rows and frames differ.
void recolour(MultiviewDataset& data, const Recolouring& recolouring);

}  // namespace nfield::integrators
