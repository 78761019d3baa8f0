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
// reproduces a smoothed picture and the PSNR against the pixels is capped by the data. The spline's derivatives, sampled anywhere, are those of a
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

#include <vector>

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

// A zero-flux vector field whose divergence is the spline's Laplacian, built from values of
// the Laplacian alone (never the spline's gradient): the data of the Ritz (energy) form of
// the Neumann problem Δu = g, ∂u/∂n = 0 (solvers/problems/poisson_image.cc).
//
// Coordinates X = c·hx, Y = r·hy (hx, hy the spacings of the columns and rows), g = ∂²s/∂X²
// + ∂²s/∂Y² on the box [0, (w − 1)·hx] × [0, (h − 1)·hy], m the mean of g over the box.
// q satisfies ∇·q = g − m, and q·n = 0 on the border. For the mirrored spline m is zero up to
// rounding (∫∫g is the flux of ∇s through the border, and ∂s/∂n = 0 there); it is taken off
// all the same, so that q·n = 0 holds exactly even when it is not. Then ∫ g·φ = −∫ q·∇φ for
// every φ, and ½∫|∇u − q|² is the Ritz energy ½∫|∇u|² + ∫ g·u plus a constant: its minimisers
// solve Δu = g − m with ∂u/∂n = 0, the spline itself up to a constant. q is not ∇s: the two
// differ by a divergence-free field with zero flux, which is orthogonal to every gradient.
//
// Construction, local at every scale. On a rectangle R with a density ρ, the "row-first"
// field
//
//     q_X = ∫ from R's left side to X of (ρ − ρ̄(Y)) dX',   q_Y = ∫ from R's top to Y of (ρ̄ − ρ_R) dY'
//
// (ρ̄(Y) the mean of ρ along R's row at Y, ρ_R its mean over R) has divergence ρ − ρ_R and
// zero flux through R's sides. Level 0 applies it to g in every pixel cell (leaving the cell
// means); level ℓ ≥ 1 applies it to the piecewise constant means of the 2 × 2 blocks of
// level ℓ − 1 within each block of 2^ℓ × 2^ℓ cells (fewer at the far sides), up to one block:
// the sum has divergence g − m. Integrating along whole rows at once (the row-first field on
// the whole box) would be simpler, but its divergence-free part holds the y-curvature of the
// picture integrated along whole rows: on camera.png at 256² the least-squares fit of ∇u to it
// ends with a mean square residual of 2.6e4, against 1.6e2 for the local construction, and
// that part is noise to a fit from random points (it is orthogonal to gradients only on
// average over the box).
//
// Exact to rounding: s is a cubic in c and in r on each pixel cell (knots at the pixel
// centres, the border pixels on knots), so g is a cubic in each variable on a cell and the
// cell's row integral ḡ(r) = ∫ over the cell's columns of g(·, r) is a cubic in r. The
// constructor tabulates ḡ (Simpson's rule, exact for cubics) at four rows of every cell (its
// ends and thirds) and the cell means from them (the 3/8 rule, exact for cubics); at(c, r)
// interpolates ḡ in r by the cubic through those rows and integrates the rest by Simpson.
class BSplineLaplacianFlux {
 public:
  BSplineLaplacianFlux(const BSplineImage& spline, double hx, double hy);

  // g = ∂²s/∂X² + ∂²s/∂Y² at pixel coordinates (c, r).
  double laplacian(double column, double row) const;
  // ∫ from k to k + 1 of g(c, r) dc (pixel units) for the cell column k, any r in [0, h − 1].
  double cell_row_integral(int k, double row) const;
  // m, the mean of g over the box, taken off g in q (see above).
  double mean() const { return mean_; }
  // (q_X, q_Y) at pixel coordinates (c, r) inside [0, w − 1] × [0, h − 1].
  Eigen::Vector2d at(double column, double row) const;

 private:
  BSplineImage spline_;
  double hx_, hy_;
  int cells_c_, cells_r_;  // w − 1, h − 1
  Eigen::MatrixXd cell_rows_;          // (3(h − 1) + 1) × (w − 1): cell_row_integral(k, j/3)
  std::vector<Eigen::MatrixXd> means_;  // level ℓ: the mean of g over each block (rows × columns)
  double mean_ = 0;
};

}  // namespace nfield::io
