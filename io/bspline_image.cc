// SPDX-License-Identifier: MIT
#include "io/bspline_image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <vtkDoubleArray.h>
#include <vtkImageBSplineCoefficients.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>

namespace nfield::io {
namespace {

// Index k of a coefficient row of length n, mirrored about 0 and n − 1.
int mirror(int k, int n) {
  const int period = 2 * (n - 1);
  k %= period;
  if (k < 0) k += period;
  return k < n ? k : period - k;
}

// The four cubic B-spline weights of coefficients floor(x) − 1 … floor(x) + 2 at fraction t,
// with their first and second derivatives in t.
struct Weights {
  std::array<double, 4> w, d, dd;
};
Weights weights(double t) {
  const double u = 1 - t;
  return {{u * u * u / 6, (3 * t * t * t - 6 * t * t + 4) / 6, (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6, t * t * t / 6},
          {-u * u / 2, 1.5 * t * t - 2 * t, -1.5 * t * t + t + 0.5, t * t / 2},
          {u, 3 * t - 2, 1 - 3 * t, t}};
}

}  // namespace

BSplineImage::BSplineImage(const Eigen::MatrixXd& pixels) {
  const auto height = pixels.rows(), width = pixels.cols();
  if (height < 2 || width < 2)
    throw std::invalid_argument("BSplineImage: the picture is " + std::to_string(width) + "x" +
                                std::to_string(height) + "; a spline needs at least 2x2 pixels");
  vtkNew<vtkImageData> image;
  image->SetDimensions(static_cast<int>(width), static_cast<int>(height), 1);
  vtkNew<vtkDoubleArray> values;
  values->SetNumberOfTuples(width * height);
  // VTK's point (i, j) is pixel column i, row j; the row order does not matter to the spline.
  for (Eigen::Index r = 0; r < height; ++r)
    for (Eigen::Index c = 0; c < width; ++c) values->SetValue(r * width + c, pixels(r, c));
  image->GetPointData()->SetScalars(values);
  vtkNew<vtkImageBSplineCoefficients> prefilter;
  prefilter->SetInputData(image);
  prefilter->SetSplineDegree(3);
  prefilter->SetBorderModeToMirror();
  prefilter->SetOutputScalarTypeToDouble();
  prefilter->Update();
  vtkDataArray* a = prefilter->GetOutput()->GetPointData()->GetScalars();
  if (!a || a->GetNumberOfTuples() != width * height)
    throw std::runtime_error("BSplineImage: vtkImageBSplineCoefficients gave no coefficients");
  coefficients_.resize(height, width);
  for (Eigen::Index r = 0; r < height; ++r)
    for (Eigen::Index c = 0; c < width; ++c) coefficients_(r, c) = a->GetComponent(r * width + c, 0);
}

BSplineImage::Derivatives BSplineImage::at(double column, double row) const {
  const int n_c = width(), n_r = height();
  // The last cell's left end, so that the border pixel itself has t = 1 within the grid.
  const int c0 = std::min(static_cast<int>(std::floor(column)), n_c - 2);
  const int r0 = std::min(static_cast<int>(std::floor(row)), n_r - 2);
  const Weights wc = weights(column - c0), wr = weights(row - r0);
  Derivatives s;
  for (int i = 0; i < 4; ++i) {
    const int r = mirror(r0 - 1 + i, n_r);
    double v = 0, dc = 0, ddc = 0;
    for (int j = 0; j < 4; ++j) {
      const double a = coefficients_(r, mirror(c0 - 1 + j, n_c));
      v += wc.w[j] * a;
      dc += wc.d[j] * a;
      ddc += wc.dd[j] * a;
    }
    s.value += wr.w[i] * v;
    s.d_column += wr.w[i] * dc;
    s.d_row += wr.d[i] * v;
    s.dd_column += wr.w[i] * ddc;
    s.dd_row += wr.dd[i] * v;
  }
  return s;
}

namespace {

// Lagrange weights of the nodes 0, 1/3, 2/3, 1 at t.
std::array<double, 4> third_weights(double t) {
  return {-4.5 * (t - 1.0 / 3) * (t - 2.0 / 3) * (t - 1), 13.5 * t * (t - 2.0 / 3) * (t - 1),
          -13.5 * t * (t - 1.0 / 3) * (t - 1), 4.5 * t * (t - 1.0 / 3) * (t - 2.0 / 3)};
}

}  // namespace

BSplineLaplacianFlux::BSplineLaplacianFlux(const BSplineImage& spline, double hx, double hy)
    : spline_(spline), hx_(hx), hy_(hy), cells_c_(spline.width() - 1), cells_r_(spline.height() - 1) {
  cell_rows_.resize(3 * cells_r_ + 1, cells_c_);
  for (int j = 0; j < cell_rows_.rows(); ++j) {
    const double r = j / 3.0;
    double left = laplacian(0, r);
    for (int k = 0; k < cells_c_; ++k) {
      const double right = laplacian(k + 1, r);
      cell_rows_(j, k) = (left + 4 * laplacian(k + 0.5, r) + right) / 6;
      left = right;
    }
  }
  Eigen::MatrixXd level(cells_r_, cells_c_);
  for (int i = 0; i < cells_r_; ++i)
    for (int k = 0; k < cells_c_; ++k)
      level(i, k) = (cell_rows_(3 * i, k) + 3 * cell_rows_(3 * i + 1, k) + 3 * cell_rows_(3 * i + 2, k) +
                     cell_rows_(3 * i + 3, k)) / 8;
  means_.push_back(level);
  // Blocks of level ℓ: cells [j·2^ℓ, min((j + 1)·2^ℓ, n)) along each axis.
  for (int l = 1; means_.back().rows() > 1 || means_.back().cols() > 1; ++l) {
    const Eigen::MatrixXd& child = means_.back();
    const int size = 1 << l, half = size / 2;
    Eigen::MatrixXd parent((cells_r_ + size - 1) / size, (cells_c_ + size - 1) / size);
    for (int bi = 0; bi < parent.rows(); ++bi)
      for (int bk = 0; bk < parent.cols(); ++bk) {
        double mass = 0, area = 0;
        for (int ci = 2 * bi; ci < std::min<int>(2 * bi + 2, child.rows()); ++ci)
          for (int ck = 2 * bk; ck < std::min<int>(2 * bk + 2, child.cols()); ++ck) {
            const double a = (std::min((ci + 1) * half, cells_r_) - ci * half) * (std::min((ck + 1) * half, cells_c_) - ck * half);
            mass += a * child(ci, ck);
            area += a;
          }
        parent(bi, bk) = mass / area;
      }
    means_.push_back(parent);
  }
  mean_ = means_.back()(0, 0);
}

double BSplineLaplacianFlux::laplacian(double column, double row) const {
  const BSplineImage::Derivatives d = spline_.at(column, row);
  return d.dd_column / (hx_ * hx_) + d.dd_row / (hy_ * hy_);
}

double BSplineLaplacianFlux::cell_row_integral(int k, double row) const {
  const int i = std::clamp(static_cast<int>(std::floor(row)), 0, cells_r_ - 1);
  const std::array<double, 4> w = third_weights(row - i);
  double total = 0;
  for (int a = 0; a < 4; ++a) total += w[a] * cell_rows_(3 * i + a, k);
  return total;
}

Eigen::Vector2d BSplineLaplacianFlux::at(double column, double row) const {
  column = std::clamp(column, 0.0, static_cast<double>(cells_c_));
  row = std::clamp(row, 0.0, static_cast<double>(cells_r_));
  const int k = std::min(static_cast<int>(std::floor(column)), cells_c_ - 1);
  const int i = std::min(static_cast<int>(std::floor(row)), cells_r_ - 1);
  const double dc = column - k, dr = row - i;
  // Level 0, the pixel cell (k, i) with g: from its left side and its top by Simpson's rule
  // (exact for the cubics).
  const double row_mean = cell_row_integral(k, row);
  double qx = dc * (laplacian(k, row) + 4 * laplacian(k + dc / 2, row) + laplacian(column, row)) / 6 - dc * row_mean;
  double qy = dr * (cell_rows_(3 * i, k) + 4 * cell_row_integral(k, i + dr / 2) + row_mean) / 6 - dr * means_[0](i, k);
  // Level ℓ: the block of 2 × 2 children of size `half` holding the cell, each child's
  // density its mean; the child column ck0 or ck0 + 1 and row ci0 or ci0 + 1 holding (c, r).
  for (std::size_t l = 1; l < means_.size(); ++l) {
    const Eigen::MatrixXd& child = means_[l - 1];
    const int half = 1 << (l - 1);
    const int ck = k / half, ci = i / half, ck0 = ck & ~1, ci0 = ci & ~1;
    const bool two_c = ck0 + 1 < child.cols();
    const double left = ck0 * half, mid_c = std::min((ck0 + 1) * half, cells_c_),
                 right = two_c ? std::min((ck0 + 2) * half, cells_c_) : mid_c;
    const double top = ci0 * half, mid_r = std::min((ci0 + 1) * half, cells_r_);
    // The mean along a row of the block in the child row ci.
    const auto row_density = [&](int r_child) {
      double mass = child(r_child, ck0) * (mid_c - left);
      if (two_c) mass += child(r_child, ck0 + 1) * (right - mid_c);
      return mass / (right - left);
    };
    const double along = ck == ck0 ? child(ci, ck0) * (column - left)
                                   : child(ci, ck0) * (mid_c - left) + child(ci, ck0 + 1) * (column - mid_c);
    qx += along - (column - left) * row_density(ci);
    const double block = means_[l](ci0 / 2, ck0 / 2);
    qy += ci == ci0 ? (row_density(ci0) - block) * (row - top)
                    : (row_density(ci0) - block) * (mid_r - top) + (row_density(ci0 + 1) - block) * (row - mid_r);
  }
  return {hx_ * qx, hy_ * qy};
}

}  // namespace nfield::io
