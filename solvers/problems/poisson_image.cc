// SPDX-License-Identifier: MIT
//
// Poisson image reconstruction (Sitzmann et al. 2020, Sec. 4.1): fit a field on [−1, 1]² to
// an image's gradient only, or its Laplacian only, and compare the result with the image.
// The supervision cannot see a constant (gradient) or a harmonic function (Laplacian), so
// the PSNR is measured after removing the mean difference.
//
//   problem: poisson_image
//   equation:
//     image: ../data/images/camera.png   # relative to the config file
//     supervise: gradient                # gradient | laplacian
//     crop: 128                          # optional: the central crop of this many pixels
//
// The image's derivatives are central differences in the field's coordinates (x right,
// y up, pixel centres spread over [−1, 1]). The domain is fixed to [−1, 1]²; its `domain:`
// section is not read.
#include <cmath>

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
    const int crop = equation.has("crop") ? equation.get_in_range("crop", 3, 1 << 16) : 0;
    io::Image image;
    try {
      image = io::read_png(path);
    } catch (const std::exception& e) {
      throw equation.error("image", e.what());
    }
    equation.reject_unknown_keys();
    if (crop > 0) image = io::central_crop(image, crop, crop);
    width_ = image.width;
    height_ = image.height;
    // Grey: the mean of the colour channels (alpha dropped), row r of the picture in row r.
    const Eigen::VectorXf grey = io::with_channels(image, 1).pixels.col(0);
    pixels_ = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                  grey.data(), height_, width_).cast<double>();
    hx_ = 2.0 / (width_ - 1);
    hy_ = 2.0 / (height_ - 1);
  }

  const Domain& domain() const override { return domain_; }
  // The supervision lives on pixel centres only; the grid output has no residual.
  int residual_term() const override { return -1; }

  std::vector<LossTerm> loss_terms() const override {
    LossTerm term;
    term.name = supervise_;
    term.batch_key = "interior";
    term.spec = supervise_ == "gradient" ? autodiff::StreamSpec::gradient(2) : autodiff::StreamSpec::laplacian(2);
    // Interior pixel centres, so central differences exist there.
    term.sample = [this](Random& rng, Eigen::Index n) {
      Eigen::MatrixXd x(n, 2);
      for (Eigen::Index i = 0; i < n; ++i) {
        const int c = 1 + static_cast<int>(uniform01(rng) * (width_ - 2));
        const int r = 1 + static_cast<int>(uniform01(rng) * (height_ - 2));
        x.row(i) << -1.0 + c * hx_, 1.0 - r * hy_;
      }
      return x;
    };
    term.residual = [this](const Eigen::MatrixXd& x) {
      const Eigen::Index n = x.rows();
      if (supervise_ == "gradient") {
        Eigen::MatrixXd target(n, 2);
        for (Eigen::Index i = 0; i < n; ++i) {
          const auto [r, c] = pixel(x.row(i));
          target(i, 0) = (at(r, c + 1) - at(r, c - 1)) / (2 * hx_);
          target(i, 1) = (at(r - 1, c) - at(r + 1, c)) / (2 * hy_);  // y points up
        }
        return std::make_unique<LinearResidual>(
            std::vector<LinearResidual::Term>{{0, 1, 0, Eigen::VectorXd::Ones(1)},
                                              {1, 2, 0, Eigen::VectorXd::Ones(1)}},
            target);
      }
      Eigen::MatrixXd target(n, 1);
      for (Eigen::Index i = 0; i < n; ++i) {
        const auto [r, c] = pixel(x.row(i));
        target(i, 0) = (at(r, c + 1) - 2 * at(r, c) + at(r, c - 1)) / (hx_ * hx_) +
                       (at(r + 1, c) - 2 * at(r, c) + at(r - 1, c)) / (hy_ * hy_);
      }
      return std::make_unique<LinearResidual>(
          std::vector<LinearResidual::Term>{{0, 3, 0, Eigen::VectorXd::Ones(1)}}, target);
    };
    return {term};
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
    const double mse = (reconstruction - pixels_).squaredNorm() / pixels_.size();
    metrics.emplace_back("psnr_db", 10.0 * std::log10(1.0 / mse));
    io::write_scalar_png(context.dir / "reconstruction.png", reconstruction, {std::pair{0.0, 1.0}, io::Colormap::kGrey});
  }

 private:
  std::pair<int, int> pixel(const Eigen::RowVectorXd& p) const {
    return {static_cast<int>(std::lround((1.0 - p(1)) / hy_)), static_cast<int>(std::lround((p(0) + 1.0) / hx_))};
  }
  double at(int r, int c) const { return pixels_(r, c); }

  Domain domain_;
  std::string supervise_;
  int width_ = 0, height_ = 0;
  double hx_ = 0, hy_ = 0;
  Eigen::MatrixXd pixels_;
};

}  // namespace

std::unique_ptr<Problem> make_poisson_image(const ProblemContext& context) {
  return std::make_unique<PoissonImage>(context);
}

}  // namespace nfield::solvers
