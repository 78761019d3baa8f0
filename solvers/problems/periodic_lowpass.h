// SPDX-License-Identifier: MIT
//
// The band-limited part of samples on a uniform periodic grid: the orthogonal projection onto
// the Fourier modes of at most K cycles per grid period along each axis,
//
//   P_K s = F⁻¹ [ 1{|m_x| ≤ K_x, |m_y| ≤ K_y, |m_t| ≤ K_t} · F s ],
//
// separable, so one axis at a time (Eigen's FFT over each line). A BACON head band-limited
// to F cycles per unit over a box of width D holds exactly the modes |m| ≤ ⌊F D⌋ per axis of
// the box-periodic Fourier series (fields/bacon.h, period 1): on the sample grid, P_K s is the
// closest such head can come to s in the mean square, which is why a multiscale fit trains
// each coarse head against it (solvers/problems/fit.cc). K ≥ N/2 along an axis of N samples
// keeps every mode (the axis is left as it is).
#pragma once

#include <array>

#include <Eigen/Core>

namespace nfield::solvers {

// Whether P_K leaves an axis of n samples as it is: K ≥ n/2 keeps every mode.
inline bool keeps_every_mode(Eigen::Index n, Eigen::Index cycles) { return n <= 1 || 2 * cycles >= n; }

// `values`: samples × channels, samples ordered x fastest, then y, then t (dims = N_x, N_y,
// N_t; 1 for an axis the grid lacks). `cycles`: K per axis, ≥ 0. Each channel is projected.
void periodic_lowpass(Eigen::Ref<Eigen::MatrixXd> values, const std::array<Eigen::Index, 3>& dims,
                      const std::array<Eigen::Index, 3>& cycles);

}  // namespace nfield::solvers
