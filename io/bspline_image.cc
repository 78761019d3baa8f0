// SPDX-License-Identifier: MIT
#include "io/bspline_image.h"

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

}  // namespace nfield::io
