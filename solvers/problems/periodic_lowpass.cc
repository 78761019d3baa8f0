// SPDX-License-Identifier: MIT
#include "solvers/problems/periodic_lowpass.h"

#include <complex>
#include <stdexcept>
#include <vector>

#include <unsupported/Eigen/FFT>

namespace nfield::solvers {

namespace {

// Projects every line of `n` samples along one axis: line starts are `stride` apart within a
// block of n · stride samples, and blocks follow each other.
void lowpass_axis(double* data, Eigen::Index total, Eigen::Index n, Eigen::Index stride, Eigen::Index cycles) {
  if (keeps_every_mode(n, cycles)) return;
  Eigen::FFT<double> fft;
  std::vector<double> line(static_cast<size_t>(n));
  std::vector<std::complex<double>> spectrum;
  for (Eigen::Index block = 0; block < total; block += n * stride)
    for (Eigen::Index offset = 0; offset < stride; ++offset) {
      double* start = data + block + offset;
      for (Eigen::Index i = 0; i < n; ++i) line[static_cast<size_t>(i)] = start[i * stride];
      fft.fwd(spectrum, line);
      for (Eigen::Index i = cycles + 1; i < n - cycles; ++i) spectrum[static_cast<size_t>(i)] = 0.0;
      fft.inv(line, spectrum);
      for (Eigen::Index i = 0; i < n; ++i) start[i * stride] = line[static_cast<size_t>(i)];
    }
}

}  // namespace

void periodic_lowpass(Eigen::Ref<Eigen::MatrixXd> values, const std::array<Eigen::Index, 3>& dims,
                      const std::array<Eigen::Index, 3>& cycles) {
  const Eigen::Index total = dims[0] * dims[1] * dims[2];
  if (total != values.rows()) throw std::invalid_argument("periodic_lowpass: the grid's size is not the rows'");
  for (Eigen::Index c = 0; c < values.cols(); ++c) {
    double* column = values.col(c).data();
    Eigen::Index stride = 1;
    for (int axis = 0; axis < 3; ++axis) {
      if (cycles[static_cast<size_t>(axis)] < 0) throw std::invalid_argument("periodic_lowpass: cycles < 0");
      lowpass_axis(column, total, dims[static_cast<size_t>(axis)], stride, cycles[static_cast<size_t>(axis)]);
      stride *= dims[static_cast<size_t>(axis)];
    }
  }
}

}  // namespace nfield::solvers
