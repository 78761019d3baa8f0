// SPDX-License-Identifier: MIT
//
// Poisson image reconstruction (Sitzmann et al. 2020, Sec. 4.1): fit a field on [−1, 1]² to
// an image's gradient only, or its Laplacian only, and compare the result with the image.
//
//   problem: poisson_image
//   equation:
//     image: ../data/images/camera.png   # relative to the config file; grey (mean of R, G, B)
//     supervise: gradient                # gradient | laplacian
//     laplacian_loss: residual           # residual | energy (with supervise: laplacian)
//     stream_function: false             # with laplacian_loss: energy: a second output ψ
//     derivatives: spline                # spline | central_differences
//     downsample: 2                      # optional: area-average blocks of 2 × 2 pixels
//     crop: 128                          # optional: then the central crop of this many pixels
//
// Pixel centres spread over [−1, 1]² (x right, y up); the domain is fixed and its `domain:`
// section is not read.
//
// Where the derivatives come from:
//   spline               the derivatives of the picture's cubic B-spline interpolant
//                        (io/bspline_image.h), a C² function through every pixel, at points
//                        drawn uniformly in [−1, 1]². The gradient fixes the picture up to a
//                        constant, so the PSNR measures the field alone.
//   central_differences  (p[c+1] − p[c−1])/2h and the 5-point Laplacian at interior pixel
//                        centres (the SIREN paper's set-up takes Sobel filters). These are the
//                        derivatives of no function through the pixels: they damp a frequency ω
//                        by sin(ωh)/(ωh), so even an exact fit is a smoothed picture.
//
// The loss of `supervise: laplacian` (`laplacian_loss`, spline only for `energy`):
//   residual             the strong form Δu − g at random points, with the `flux` term ∂u/∂n
//                        on the border. Its Hessian weighs an error of frequency ω by ω⁴:
//                        the fine detail converges first and the smooth shading is nearly
//                        free, and noisy in a random batch (docs/experiments.md).
//   energy               the Ritz energy of the Neumann problem Δu = g, ∂u/∂n = 0, written
//                        as the least squares ∇u − q with q a zero-flux field of divergence
//                        g built from values of g alone (io::BSplineLaplacianFlux): ∫ g·u =
//                        −∫ q·∇u, so ½∫|∇u − q|² = ½∫|∇u|² + ∫ g·u + const. It weighs ω by
//                        ω² only, the flux condition is natural (no term), and the minimiser
//                        is the picture up to a constant although q is not its gradient.
//   stream_function      q's divergence-free part (q − ∇s) cannot be fitted by ∇u and stays
//                        in the residual as noise to each random batch (its mean over the
//                        square is orthogonal to gradients, a batch's is not). A second output
//                        ψ, held to zero on the border (term `stream`), adds (∂ψ/∂y, −∂ψ/∂x),
//                        which is orthogonal to every ∇u and so leaves u's optimum alone, and
//                        takes that part up: the residual can go to zero as with the gradient.
//
// Outputs: reconstruction.png (grey, [0, 1]), error.png (|error|, viridis from 0 to
// max_abs_err); metrics.json psnr_db, ssim, max_abs_err.
//
// Normalisation (metrics.json psnr_db): the supervision cannot see a constant, so the
// reconstruction is shifted by the mean difference before the PSNR over all pixels, with the
// peak 1 (pixels in [0, 1]). The Laplacian cannot see any harmonic function either; the same
// mean shift is all that is removed, so a harmonic error the field makes counts against it.
#include <algorithm>
#include <cmath>
#include <optional>

#include "io/bspline_image.h"
#include "io/image_file.h"
#include "io/image_metrics.h"
#include "io/png_image.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

class PoissonImage final : public Problem {
 public:
  explicit PoissonImage(const ProblemContext& context) : domain_({-1.0, -1.0}, {1.0, 1.0}) {
    const io::ConfigNode equation = context.root.child("equation");
    const std::filesystem::path path = context.config_dir / equation.get<std::string>("image");
    supervise_ = equation.get_choice("supervise", {"gradient", "laplacian"}, "gradient");
    spline_ = equation.get_choice("derivatives", {"spline", "central_differences"}, "spline") == "spline";
    if (equation.has("laplacian_loss")) {
      energy_ = equation.get_choice("laplacian_loss", {"residual", "energy"}) == "energy";
      if (supervise_ != "laplacian")
        throw equation.error("laplacian_loss", "applies to supervise: laplacian only");
      // The exact q needs g between the pixel centres; a discrete analogue for the 5-point
      // Laplacian is not built.
      if (energy_ && !spline_)
        throw equation.error("laplacian_loss", "energy needs derivatives: spline (central_differences gives the "
                                               "Laplacian at pixel centres only)");
    }
    if (equation.has("stream_function")) {
      stream_ = equation.get<bool>("stream_function");
      if (stream_ && !energy_) throw equation.error("stream_function", "applies to laplacian_loss: energy only");
    }
    if (equation.has("stream_weight")) {
      stream_weight_ = equation.get_nonnegative<double>("stream_weight");
      if (!stream_) throw equation.error("stream_weight", "applies to stream_function: true only");
    }
    flux_weight_ = equation.has("flux_weight") ? equation.get_nonnegative<double>("flux_weight") : 1.0;
    // The energy's flux condition is natural: a flux term would only weigh the border twice.
    if (energy_ && equation.has("flux_weight"))
      throw equation.error("flux_weight", "applies to laplacian_loss: residual only (the energy form needs no flux term)");
    const int downsample = equation.has("downsample") ? equation.get_in_range("downsample", 1, 64) : 1;
    const int crop = equation.has("crop") ? equation.get_in_range("crop", 3, 1 << 16) : 0;
    io::Image image;
    try {
      image = io::read_image(path);
    } catch (const std::exception& e) {
      throw equation.error("image", e.what());
    }
    equation.reject_unknown_keys();
    if (downsample > 1) {
      if (downsample * 3 > std::min(image.width, image.height))
        throw equation.error("downsample", "a factor of " + std::to_string(downsample) + " leaves fewer than 3 pixels of the " +
                                               std::to_string(image.width) + " x " + std::to_string(image.height) + " image");
      image = io::box_downsample(image, downsample);
    }
    if (crop > 0) image = io::central_crop(image, crop, crop);
    if (image.width < 3 || image.height < 3)
      throw equation.error("image", "a picture of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                                        " pixels; at least 3 x 3 are needed");
    width_ = image.width;
    height_ = image.height;
    // Grey: the mean of the colour channels (alpha dropped), row r of the picture in row r.
    const Eigen::VectorXf grey = io::with_channels(image, 1).pixels.col(0);
    pixels_ = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                  grey.data(), height_, width_).cast<double>();
    hx_ = 2.0 / (width_ - 1);
    hy_ = 2.0 / (height_ - 1);
    if (spline_) spline_image_.emplace(pixels_);
    if (energy_) flux_field_.emplace(*spline_image_, hx_, hy_);
  }

  const Domain& domain() const override { return domain_; }
  // The supervision lives on pixel centres only; the grid output has no residual.
  int residual_term() const override { return -1; }
  int output_dim() const override { return stream_ ? 2 : 1; }
  std::vector<std::string> output_names() const override {
    return stream_ ? std::vector<std::string>{"u", "psi"} : std::vector<std::string>{"u"};
  }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm term;
    term.name = energy_ ? "energy" : supervise_;
    term.batch_key = "interior";
    term.spec = supervise_ == "gradient" || energy_ ? autodiff::StreamSpec::gradient(2) : autodiff::StreamSpec::laplacian(2);
    term.sample = [this](Random& rng, Eigen::Index n) {
      Eigen::MatrixXd x(n, 2);
      if (spline_) {
        for (Eigen::Index i = 0; i < n; ++i) x.row(i) << -1.0 + 2.0 * uniform01(rng), -1.0 + 2.0 * uniform01(rng);
        return x;
      }
      // Interior pixel centres, so central differences exist there.
      for (Eigen::Index i = 0; i < n; ++i) {
        const int c = 1 + static_cast<int>(uniform01(rng) * (width_ - 2));
        const int r = 1 + static_cast<int>(uniform01(rng) * (height_ - 2));
        x.row(i) << -1.0 + c * hx_, 1.0 - r * hy_;
      }
      return x;
    };
    term.residual = [this, layout = autodiff::StreamLayout(term.spec)](const Eigen::MatrixXd& x) {
      return residual_for(layout, interior_target(x));
    };
    if (stream_) {
      LossTerm border;
      border.name = "stream";
      border.batch_key = "boundary";
      border.weight = stream_weight_;
      border.spec = autodiff::StreamSpec::values(2);
      border.sample = sample_border;
      border.residual = [](const Eigen::MatrixXd& x) {
        const int psi = 1;
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, autodiff::StreamLayout::value(), psi, Eigen::VectorXd::Ones(1)}},
                                                Eigen::MatrixXd::Zero(x.rows(), 1));
      };
      return {term, border};
    }
    if (supervise_ == "gradient" || energy_ || !spline_ || flux_weight_ == 0) return {term};
    return {term, flux_term()};
  }

  // The interior term's target at x: the flux field of the energy form, or the picture's
  // gradient or Laplacian, from its B-spline or by central differences at pixel centres.
  Eigen::MatrixXd interior_target(const Eigen::MatrixXd& x) const {
    const Eigen::Index n = x.rows();
    const bool gradient = supervise_ == "gradient";
    if (energy_) {
      Eigen::MatrixXd target(n, 2);
      for (Eigen::Index i = 0; i < n; ++i) {
        // q in (X, Y) = (c·hx, r·hy); y = 1 − Y points the other way.
        const Eigen::Vector2d q = flux_field_->at(std::clamp((x(i, 0) + 1.0) / hx_, 0.0, width_ - 1.0),
                                                  std::clamp((1.0 - x(i, 1)) / hy_, 0.0, height_ - 1.0));
        target.row(i) << q(0), -q(1);
      }
      return target;
    }
    if (spline_) {
      Eigen::MatrixXd target(n, gradient ? 2 : 1);
      for (Eigen::Index i = 0; i < n; ++i) {
        // Pixel coordinates: column c = (x + 1)/hx, row r = (1 − y)/hy, so ∂/∂y = −∂/∂r / hy.
        const io::BSplineImage::Derivatives d =
            spline_image_->at(std::clamp((x(i, 0) + 1.0) / hx_, 0.0, width_ - 1.0),
                              std::clamp((1.0 - x(i, 1)) / hy_, 0.0, height_ - 1.0));
        if (gradient)
          target.row(i) << d.d_column / hx_, -d.d_row / hy_;
        else
          target(i, 0) = d.dd_column / (hx_ * hx_) + d.dd_row / (hy_ * hy_);
      }
      return target;
    }
    if (gradient) {
      Eigen::MatrixXd target(n, 2);
      for (Eigen::Index i = 0; i < n; ++i) {
        const auto [r, c] = pixel(x.row(i));
        target(i, 0) = (at(r, c + 1) - at(r, c - 1)) / (2 * hx_);
        target(i, 1) = (at(r - 1, c) - at(r + 1, c)) / (2 * hy_);  // y points up
      }
      return target;
    }
    Eigen::MatrixXd target(n, 1);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto [r, c] = pixel(x.row(i));
      target(i, 0) = (at(r, c + 1) - 2 * at(r, c) + at(r, c - 1)) / (hx_ * hx_) +
                     (at(r + 1, c) - 2 * at(r, c) + at(r - 1, c)) / (hy_ * hy_);
    }
    return target;
  }

  // The Laplacian fixes the picture up to a harmonic function; with the flux through the
  // border, up to a constant (the Neumann problem): the flux term.
  LossTerm flux_term() const {
    LossTerm flux;
    flux.name = "flux";
    flux.batch_key = "boundary";
    flux.weight = flux_weight_;
    flux.spec = autodiff::StreamSpec::gradient(2);
    flux.sample = sample_border;
    flux.residual = [this, layout = autodiff::StreamLayout(flux.spec)](const Eigen::MatrixXd& x) {
      const Eigen::Index n = x.rows();
      Eigen::VectorXd nx = Eigen::VectorXd::Zero(n), ny = Eigen::VectorXd::Zero(n);
      Eigen::MatrixXd target(n, 1);
      for (Eigen::Index i = 0; i < n; ++i) {
        // The outward normal of the side the point lies on (a corner takes the x side).
        if (std::abs(x(i, 0)) == 1.0) nx(i) = x(i, 0);
        else ny(i) = x(i, 1);
        const io::BSplineImage::Derivatives d =
            spline_image_->at(std::clamp((x(i, 0) + 1.0) / hx_, 0.0, width_ - 1.0),
                              std::clamp((1.0 - x(i, 1)) / hy_, 0.0, height_ - 1.0));
        target(i, 0) = nx(i) * d.d_column / hx_ - ny(i) * d.d_row / hy_;
      }
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{{0, layout.tangent(0), 0, nx}, {0, layout.tangent(1), 0, ny}}, target);
    };
    return flux;
  }

  void write_outputs(const OutputContext& context,
                     std::vector<std::pair<std::string, double>>& metrics) const override {
    Eigen::MatrixXd x(static_cast<Eigen::Index>(width_) * height_, 2);
    for (int r = 0; r < height_; ++r)
      for (int c = 0; c < width_; ++c) x.row(static_cast<Eigen::Index>(r) * width_ + c) << -1.0 + c * hx_, 1.0 - r * hy_;
    const Eigen::VectorXd u = context.values(x).col(0);
    Eigen::MatrixXd reconstruction(height_, width_);
    for (int r = 0; r < height_; ++r)
      for (int c = 0; c < width_; ++c) reconstruction(r, c) = u(static_cast<Eigen::Index>(r) * width_ + c);
    reconstruction.array() += pixels_.mean() - reconstruction.mean();
    const Eigen::MatrixXd error = reconstruction - pixels_;
    const double mse = error.squaredNorm() / pixels_.size();
    metrics.emplace_back("psnr_db", 10.0 * std::log10(1.0 / mse));
    metrics.emplace_back("max_abs_err", error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
    if (width_ >= 11 && height_ >= 11) {
      // Row-major pixel lists (row r · width + c), as io::Image keeps them.
      const auto rows = [](const Eigen::MatrixXd& m) {
        const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> f = m.cast<float>();
        return Eigen::MatrixXf(Eigen::Map<const Eigen::VectorXf>(f.data(), f.size()));
      };
      metrics.emplace_back("ssim", io::ssim(rows(reconstruction), rows(pixels_), width_, height_));
    }
    io::write_scalar_png(context.dir / "reconstruction.png", reconstruction, {std::pair{0.0, 1.0}, io::Colormap::kGrey});
    io::write_scalar_png(context.dir / "error.png", error.cwiseAbs(),
                         {std::pair{0.0, std::max(error.cwiseAbs().maxCoeff(), 1e-12)}, io::Colormap::kViridis});
  }

 private:
  // ∂u/∂x, ∂u/∂y (target the gradient or the energy's q), with ∂ψ/∂y, −∂ψ/∂x added for the
  // stream function, or Δu, minus the target's columns.
  std::unique_ptr<Residual> residual_for(const autodiff::StreamLayout& layout, const Eigen::MatrixXd& target) const {
    if (stream_ || supervise_ == "gradient" || energy_) {
      const int d_dx = layout.tangent(0), d_dy = layout.tangent(1);
      const int u = 0, psi = 1;
      if (stream_)
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, d_dx, u, Eigen::VectorXd::Ones(1)},
                                              {0, d_dy, psi, Eigen::VectorXd::Ones(1)},
                                              {1, d_dy, u, Eigen::VectorXd::Ones(1)},
                                              {1, d_dx, psi, -Eigen::VectorXd::Ones(1)}},
            target);
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{{0, d_dx, u, Eigen::VectorXd::Ones(1)}, {1, d_dy, u, Eigen::VectorXd::Ones(1)}},
          target);
    }
    return std::make_unique<LinearResidual>(std::vector<LinearResidual::Term>{{0, layout.op(0), 0, Eigen::VectorXd::Ones(1)}},
                                            target);
  }

  // Points on the four sides of [−1, 1]², each side alike.
  static TermPoints sample_border(Random& rng, Eigen::Index n) {
    Eigen::MatrixXd x(n, 2);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double t = -1.0 + 2.0 * uniform01(rng);
      switch (static_cast<int>(uniform01(rng) * 4)) {
        case 0: x.row(i) << -1.0, t; break;
        case 1: x.row(i) << 1.0, t; break;
        case 2: x.row(i) << t, -1.0; break;
        default: x.row(i) << t, 1.0; break;
      }
    }
    return x;
  }

  std::pair<int, int> pixel(const Eigen::RowVectorXd& p) const {
    return {static_cast<int>(std::lround((1.0 - p(1)) / hy_)), static_cast<int>(std::lround((p(0) + 1.0) / hx_))};
  }
  double at(int r, int c) const { return pixels_(r, c); }

  Domain domain_;
  std::string supervise_;
  bool spline_ = true;
  bool energy_ = false;  // laplacian_loss: energy
  bool stream_ = false;  // stream_function: true
  double stream_weight_ = 1.0;
  double flux_weight_ = 1.0;
  std::optional<io::BSplineImage> spline_image_;
  std::optional<io::BSplineLaplacianFlux> flux_field_;
  int width_ = 0, height_ = 0;
  double hx_ = 0, hy_ = 0;
  Eigen::MatrixXd pixels_;
};

}  // namespace

std::unique_ptr<Problem> make_poisson_image(const ProblemContext& context) {
  return std::make_unique<PoissonImage>(context);
}

}  // namespace nfield::solvers
