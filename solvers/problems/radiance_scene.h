// SPDX-License-Identifier: MIT
//
// What the problems that render a field along rays share (solvers/problems/nerf.cc, and
// solvers/problems/autoint_nerf.cc, which reads the same field's integral): the `data` and `scene`
// config sections, training pixels and their targets on the chosen background, the output
// activations of density and colour, and the outputs after training (test views with PSNR
// and SSIM, `nfield render` of a transforms.json or a turntable).
//
// A problem supplies how a batch of rays, already clipped to the scene box, is rendered
// (RenderRays); everything around that lives here.
#pragma once

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "integrators/camera.h"
#include "integrators/multiview_dataset.h"
#include "integrators/radiance_activations.h"
#include "integrators/ray_batch.h"
#include "integrators/ray_sampling.h"
#include "integrators/scene_box.h"
#include "solvers/core/problem.h"

namespace nfield::solvers {

enum class Background { kWhite, kBlack, kRandom };

using integrators::DensityActivation;

// σ and c from raw outputs [s, r, g, b] (rows of `raw`).
struct Shading {
  Eigen::VectorXd sigma;
  Eigen::MatrixXd rgb;
};
template <typename Raw>
Shading shade(const Raw& raw, const DensityActivation& density) {
  return {raw.col(0).unaryExpr([&density](double s) { return density.value(s); }),
          raw.middleCols(1, 3).unaryExpr([](double z) { return integrators::colour_activation(z); })};
}

// A rendered batch of rays (one per pixel).
struct View {
  Eigen::MatrixXf truth;    // pixels × 3: the ground truth of the pixels rendered
  Eigen::MatrixXf rgb;      // pixels × 3
  Eigen::VectorXf opacity;  // pixels
  Eigen::VectorXf depth;    // pixels: expected distance given a hit
};

// The rays of `samples` rendered with `shading` on `background` (1 × 3): colour, opacity and
// expected distance given a hit.
View composite(const integrators::RaySamples<double>& samples, const Shading& shading, const Eigen::Vector3d& background);

// Rays clipped to the scene box (near bound applied), rendered on `background`.
using RenderRays = std::function<View(const integrators::Rays<double>& rays, const Eigen::Vector3d& background)>;

// Training pixels and the colours a ray's rendering is compared with.
struct PixelTargets {
  integrators::PixelBatch<double> pixels;  // rays clipped to the scene box
  Eigen::MatrixXd target;                  // R × 3
  Eigen::MatrixXd background;              // 1 × 3, or R × 3 (random backgrounds)
};

class RadianceScene {
 public:
  // Reads `scene` and `data` (strictly: unknown keys there are errors); dataset errors are
  // reported at their key with the file they name.
  explicit RadianceScene(const ProblemContext& context);

  const Domain& domain() const { return domain_; }
  const integrators::SceneBox& box() const { return box_; }
  double near() const { return near_; }
  Background background() const { return background_; }
  const integrators::MultiviewDataset& train() const { return *train_; }
  const integrators::MultiviewDataset* test() const { return test_.get(); }
  // data.appearance: each training image an instance with its own appearance code (nerf.cc).
  bool appearance() const { return appearance_; }

  // This scene with other views: `train` to draw pixels from, `test` (may be null) to render
  // and score into context.dir/`view_folder`.
  RadianceScene with_views(std::shared_ptr<const integrators::MultiviewDataset> train,
                           std::shared_ptr<const integrators::MultiviewDataset> test, std::string view_folder) const;

  // `rays` random training pixels (rays clipped); then, after the problem has drawn its
  // samples from the same engine, their targets and backgrounds (random ones drawn here).
  PixelTargets draw_pixels(Eigen::Index rays, std::mt19937_64& engine) const;
  void draw_targets(PixelTargets& batch, std::mt19937_64& engine) const;
  void clip(integrators::Rays<double>& rays) const;

  // Every `stride`-th pixel of every `stride`-th row of a frame of `data`, rendered.
  View render_view(const integrators::MultiviewDataset& data, int frame, const RenderRays& render,
                   int stride = 1) const;
  // The PSNR of the first test view at every 4th pixel (progress lines); none without tests.
  std::vector<std::pair<std::string, double>> progress_psnr(const RenderRays& render) const;
  // The PSNR of the first test view's columns from `first_column` on, every pixel rendered.
  double columns_psnr(const RenderRays& render, int first_column) const;

  // `nfield render`: the request's cameras rendered into context.dir.
  void render_views(const OutputContext& context, const RenderRequest& request, const RenderRays& render) const;

  // Every test view rendered into context.dir/test_views with PSNR and SSIM per view and
  // their means, the mean PSNRs of the views' left and right halves (columns below and from
  // ⌊width/2⌋: NeRF-W's protocol scores the right halves), and render_ms_mean, added to
  // `metrics`; `after_view(f)`, if given, runs after view f (untimed). Returns the mean
  // seconds per view (0 without test views).
  double write_test_views(const OutputContext& context, const RenderRays& render,
                          std::vector<std::pair<std::string, double>>& metrics,
                          const std::function<void(int)>& after_view = {}) const;

 private:
  std::vector<integrators::Camera> turntable(const RenderRequest& request) const;

  Domain domain_;
  integrators::SceneBox box_;
  double near_ = 0;
  Background background_ = Background::kWhite;
  bool appearance_ = false;
  std::string view_folder_ = "test_views";
  std::shared_ptr<const integrators::MultiviewDataset> train_, test_;
};

// The view's colour, ground truth (when given), error, opacity and depth PNGs at stem_*.png.
void write_view(const std::filesystem::path& stem, const View& view, const Eigen::MatrixXf& truth,
                int width, int height);

}  // namespace nfield::solvers
