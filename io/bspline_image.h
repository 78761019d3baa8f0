// SPDX-License-Identifier: MIT
//
// A grey picture as a C² function of the plane: its cubic B-spline interpolant.
//
// Pixel (r, c) sits at the point (c, r) of pixel coordinates. The interpolant
//
//     s(c, r) = Σ_ij a_ij β(c − j) β(r − i),   β the cubic B-spline (support [−2, 2]),
//
// passes through every pixel, s(c, r) = p_rc, when the coefficients a are the picture
// prefiltered by the inverse of the B-spline's sampled kernel (Thévenaz, Blu and Unser,
// "Interpolation revisited", IEEE TMI 2000). VTK computes them
// (vtkImageBSplineCoefficients, mirror border); this class evaluates s and its first and
// second derivatives, which VTK does not.
//
// Why a spline: a gradient (or Laplacian) target taken as central differences at pixel
// centres is the derivative of no function through the pixels. Its response to a frequency
// ω is sin(ωh)/h instead of ω, zero at the Nyquist frequency, so a field that matches it
// reproduces a smoothed picture and the PSNR against the pixels is capped by the data
// (about 30 dB on camera.png). The spline's derivatives, sampled anywhere, are those of a
// function that is exactly the picture at its pixels: the picture up to a constant is fixed
// by ∇s, and matching them is a question of the field only.
//
// Border: the coefficients are mirrored about the first and last pixel (a_{−k} = a_k,
// a_{n−1+k} = a_{n−1−k}), the extension VTK's prefilter assumes, so s is even about the
// border pixels: ∂s/∂c = 0 on the first and last column's centre line.
//
// s is piecewise cubic: ∇s is C¹ and Δs is continuous and piecewise linear.
#pragma once

#include <Eigen/Core>

namespace nfield::io {

class BSplineImage {
 public:
  // `pixels` (height × width, row 0 the top row) of at least 2 × 2.
  explicit BSplineImage(const Eigen::MatrixXd& pixels);

  int width() const { return static_cast<int>(coefficients_.cols()); }
  int height() const { return static_cast<int>(coefficients_.rows()); }

  struct Derivatives {
    double value = 0;
    double d_column = 0, d_row = 0;            // ∂s/∂c, ∂s/∂r
    double dd_column = 0, dd_row = 0;          // ∂²s/∂c², ∂²s/∂r²
  };
  // s and its derivatives at pixel coordinates (c, r), inside [0, width − 1] × [0, height − 1].
  Derivatives at(double column, double row) const;

  const Eigen::MatrixXd& coefficients() const { return coefficients_; }

 private:
  Eigen::MatrixXd coefficients_;  // height × width
};

}  // namespace nfield::io
