// SPDX-License-Identifier: MIT
#include "solvers/problems/radiance_scene.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>

#include "integrators/dataset_views.h"
#include "integrators/multiview_dataset.h"
#include "integrators/volume_rendering.h"
#include "io/image_metrics.h"
#include "io/text.h"
#include "io/png_image.h"

namespace nfield::solvers {
namespace {

Domain scene_domain(const io::ConfigNode& scene) {
  const std::vector<double> lower = scene.get_list<double>("lower", 3), upper = scene.get_list<double>("upper", 3);
  for (int a = 0; a < 3; ++a) scene.require("upper", upper[a] > lower[a], "expected upper > lower on every axis");
  // Step lengths, frustum radii and the occupancy grid's cells all come from the diagonal: a
  // box of +-1e300 passes the check above yet has an infinite diagonal.
  double diagonal_squared = 0;
  for (int a = 0; a < 3; ++a) diagonal_squared += (upper[a] - lower[a]) * (upper[a] - lower[a]);
  scene.require("upper", std::isfinite(diagonal_squared),
                "expected a box whose diagonal is a finite number (upper - lower overflows)");
  return Domain(lower, upper);
}

integrators::MultiviewDataset read(const io::ConfigNode& data, const char* key, const std::filesystem::path& dir,
                                   const integrators::DatasetOptions& options) {
  try {
    return integrators::read_transforms(dir / data.get<std::string>(key), options);
  } catch (const integrators::DatasetError& e) {
    throw data.error(key, e.what());
  }
}

integrators::PixelBatch<double> every_other(const integrators::PixelBatch<double>& all, int width, int stride) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index p = 0; p < all.rgb.rows(); ++p)
    if ((p / width) % stride == 0 && (p % width) % stride == 0) keep.push_back(p);
  integrators::PixelBatch<double> some;
  some.rays = all.rays.subset(keep);
  some.rgb = all.rgb(keep, Eigen::all);
  some.background = all.background;
  return some;
}

// data.recolour: each image's colours scaled and shifted per channel (integrators/dataset_views.h).
struct RecolourSettings {
  std::array<double, 2> scale{0.8, 1.2}, shift{-0.2, 0.2};
  std::uint64_t seed = 0;
  // Frames of the training set draw from `seed`, the test set's from seed + 1.
  void apply(integrators::MultiviewDataset& data, std::uint64_t stream) const {
    integrators::recolour(data, integrators::draw_recolouring(static_cast<int>(data.frames.size()), scale[0], scale[1],
                                                              shift[0], shift[1], seed + stream));
  }
};

RecolourSettings read_recolour(const io::ConfigNode& node) {
  RecolourSettings r;
  const auto range = [&](const char* key, std::array<double, 2>& out, double low, double high) {
    if (!node.has(key)) return;
    const std::vector<double> v = node.get_list<double>(key, 2);
    node.require(key, std::isfinite(v[0]) && std::isfinite(v[1]) && v[0] <= v[1] && v[0] >= low && v[1] <= high,
                 "expected [lower, upper] with " + io::format_number(low) + " <= lower <= upper <= " +
                     io::format_number(high));
    out = {v[0], v[1]};
  };
  range("scale", r.scale, 0.0, 100.0);
  range("shift", r.shift, -1.0, 1.0);
  if (node.has("seed")) r.seed = static_cast<std::uint64_t>(node.get_in_range("seed", 0, 1 << 30));
  node.reject_unknown_keys();
  return r;
}

// io::psnr over the columns [begin, end) of a view `width` wide.
double psnr_of_columns(const Eigen::MatrixXf& image, const Eigen::MatrixXf& truth, int width, int begin, int end) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index p = 0; p < image.rows(); ++p)
    if (const int c = static_cast<int>(p % width); c >= begin && c < end) rows.push_back(p);
  return io::psnr(image(rows, Eigen::all), truth(rows, Eigen::all));
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

View composite(const integrators::RaySamples<double>& samples, const Shading& shading, const Eigen::Vector3d& background) {
  const auto result = integrators::render<double>(samples, shading.sigma, shading.rgb, background.transpose());
  View view;
  view.rgb = result.color.cast<float>();
  view.opacity = result.opacity.cast<float>();
  view.depth = (result.depth.array() / result.opacity.array().max(1e-6)).cast<float>();
  return view;
}

RadianceScene::RadianceScene(const ProblemContext& context) : domain_(scene_domain(context.root.child("scene"))) {
  const io::ConfigNode scene = context.root.child("scene");
  box_.lower = Eigen::Vector3d(domain_.lower().data());
  box_.upper = Eigen::Vector3d(domain_.upper().data());
  near_ = scene.get_or("near", 0.0);
  scene.require("near", near_ >= 0 && std::isfinite(near_), "expected a number >= 0");
  scene.reject_unknown_keys();

  const io::ConfigNode data = context.root.child("data");
  const std::string background = data.get_choice("background", {"white", "black", "random"}, "white");
  background_ = background == "white"   ? Background::kWhite
                : background == "black" ? Background::kBlack
                                        : Background::kRandom;
  integrators::DatasetOptions dataset;
  dataset.background = background_ == Background::kBlack ? Eigen::Vector3d::Zero() : Eigen::Vector3d::Ones();
  integrators::MultiviewDataset train = read(data, "train", context.config_dir, dataset);
  std::optional<integrators::MultiviewDataset> test;
  if (data.has("test")) {
    integrators::DatasetOptions options = dataset;
    if (background_ == Background::kRandom) options.background = Eigen::Vector3d::Ones();
    test = read(data, "test", context.config_dir, options);
  }
  if (data.has("recolour")) {
    const RecolourSettings recolour = read_recolour(data.child("recolour"));
    recolour.apply(train, 0);
    if (test) recolour.apply(*test, 1);
  }
  appearance_ = data.get_or("appearance", false);
  if (appearance_ && !test)
    throw data.error("appearance", "expected data.test too: its images are the held-out instances, each scored on "
                                   "its right half after a code is fitted on its left half");
  train_ = std::make_shared<const integrators::MultiviewDataset>(std::move(train));
  if (test) test_ = std::make_shared<const integrators::MultiviewDataset>(std::move(*test));
  data.reject_unknown_keys();
}

RadianceScene RadianceScene::with_views(std::shared_ptr<const integrators::MultiviewDataset> train,
                                        std::shared_ptr<const integrators::MultiviewDataset> test,
                                        std::string view_folder) const {
  RadianceScene scene = *this;
  scene.train_ = std::move(train);
  scene.test_ = std::move(test);
  scene.view_folder_ = std::move(view_folder);
  return scene;
}

void RadianceScene::clip(integrators::Rays<double>& rays) const { integrators::clip_to_box(rays, box_, near_); }

PixelTargets RadianceScene::draw_pixels(Eigen::Index rays, std::mt19937_64& engine) const {
  PixelTargets batch;
  batch.pixels = integrators::sample_pixels<double>(*train_, rays, engine);
  clip(batch.pixels.rays);
  return batch;
}

void RadianceScene::draw_targets(PixelTargets& batch, std::mt19937_64& engine) const {
  const Eigen::Index rays = batch.pixels.rays.size();
  if (background_ == Background::kRandom) {
    batch.background.resize(rays, 3);
    for (Eigen::Index i = 0; i < batch.background.size(); ++i)
      batch.background.data()[i] = static_cast<double>(engine() >> 11) * 0x1.0p-53;
    batch.target = integrators::composite_on<double>(batch.pixels, batch.background);
  } else {
    batch.background = batch.pixels.background.transpose();
    batch.target = batch.pixels.rgb;
  }
}

View RadianceScene::render_view(const integrators::MultiviewDataset& data, int frame, const RenderRays& render,
                                int stride) const {
  integrators::PixelBatch<double> pixels = integrators::frame_pixels<double>(data, frame);
  if (stride > 1) pixels = every_other(pixels, data.intrinsics.width, stride);
  clip(pixels.rays);
  View view = render(pixels.rays, data.background);
  view.truth = pixels.rgb.cast<float>();
  return view;
}

std::vector<std::pair<std::string, double>> RadianceScene::progress_psnr(const RenderRays& render) const {
  if (!test_) return {};
  const View view = render_view(*test_, 0, render, 4);
  return {{"test PSNR", io::psnr(view.rgb, view.truth)}};
}

double RadianceScene::columns_psnr(const RenderRays& render, int first_column) const {
  if (!test_) throw std::logic_error("columns_psnr: the scene has no test view");
  const View view = render_view(*test_, 0, render);
  const int width = test_->intrinsics.width;
  return psnr_of_columns(view.rgb, view.truth, width, first_column, width);
}

void RadianceScene::render_views(const OutputContext& context, const RenderRequest& request,
                                 const RenderRays& render) const {
  std::vector<integrators::Camera> cameras;
  std::vector<Eigen::MatrixXf> truths;
  Eigen::Vector3d background = Eigen::Vector3d::Ones();
  if (!request.poses.empty()) {
    integrators::DatasetOptions options;
    options.background = background_ == Background::kBlack ? Eigen::Vector3d::Zero() : Eigen::Vector3d::Ones();
    const integrators::MultiviewDataset poses = integrators::read_transforms(request.poses, options);
    background = poses.background;
    for (const auto& frame : poses.frames) {
      cameras.push_back(frame.camera);
      truths.push_back(frame.rgb);
    }
  } else {
    cameras = turntable(request);
    if (background_ == Background::kBlack) background.setZero();
  }
  std::filesystem::create_directories(context.dir);
  const int width = cameras.front().intrinsics.width, height = cameras.front().intrinsics.height;
  double psnr_sum = 0;
  for (size_t k = 0; k < cameras.size(); ++k) {
    const auto started = std::chrono::steady_clock::now();
    integrators::Rays<double> rays = integrators::image_rays<double>(cameras[k]);
    clip(rays);
    const View view = render(rays, background);
    const double ms = 1e3 * seconds_since(started);
    char stem[64];
    std::snprintf(stem, sizeof stem, "%s_%03zu", request.poses.empty() ? "turntable" : "view", k);
    write_view(context.dir / stem, view, truths.empty() ? Eigen::MatrixXf() : truths[k], width, height);
    if (truths.empty()) {
      std::printf("%s: %zu/%zu rendered in %.0f ms\n", stem, k + 1, cameras.size(), ms);
    } else {
      const double psnr = io::psnr(view.rgb, truths[k]);
      psnr_sum += psnr;
      std::printf("%s: %zu/%zu rendered in %.0f ms, PSNR %.2f dB\n", stem, k + 1, cameras.size(), ms, psnr);
    }
  }
  if (!truths.empty()) std::printf("mean PSNR %.2f dB over %zu views\n", psnr_sum / cameras.size(), cameras.size());
}

double RadianceScene::write_test_views(const OutputContext& context, const RenderRays& render,
                                       std::vector<std::pair<std::string, double>>& metrics,
                                       const std::function<void(int)>& after_view) const {
  if (!test_) return 0;
  const std::filesystem::path views = context.dir / view_folder_;
  std::filesystem::create_directories(views);
  double psnr_sum = 0, ssim_sum = 0, seconds = 0, left_sum = 0, right_sum = 0;
  const int width = test_->intrinsics.width, height = test_->intrinsics.height;
  for (size_t f = 0; f < test_->frames.size(); ++f) {
    const auto started = std::chrono::steady_clock::now();
    const View view = render_view(*test_, static_cast<int>(f), render);
    seconds += seconds_since(started);
    if (after_view) after_view(static_cast<int>(f));
    const Eigen::MatrixXf& truth = test_->frames[f].rgb;
    const double psnr = io::psnr(view.rgb, truth);
    const double ssim = io::ssim(view.rgb, truth, width, height);
    left_sum += psnr_of_columns(view.rgb, truth, width, 0, width / 2);
    right_sum += psnr_of_columns(view.rgb, truth, width, width / 2, width);
    char name[64];
    std::snprintf(name, sizeof name, "test_%03zu", f);
    metrics.emplace_back(std::string("psnr_") + name, psnr);
    metrics.emplace_back(std::string("ssim_") + name, ssim);
    psnr_sum += psnr;
    ssim_sum += ssim;
    write_view(views / name, view, truth, width, height);
  }
  const auto n = static_cast<double>(test_->frames.size());
  metrics.emplace_back("psnr_mean", psnr_sum / n);
  metrics.emplace_back("ssim_mean", ssim_sum / n);
  metrics.emplace_back("psnr_left_half_mean", left_sum / n);
  metrics.emplace_back("psnr_right_half_mean", right_sum / n);
  metrics.emplace_back("render_ms_mean", 1e3 * seconds / n);
  std::printf("%s: mean PSNR %.2f dB (left halves %.2f, right halves %.2f), mean SSIM %.4f over %zu view%s, %.0f ms "
              "a view (%s)\n",
              view_folder_.c_str(), psnr_sum / n, left_sum / n, right_sum / n, ssim_sum / n, test_->frames.size(),
              test_->frames.size() == 1 ? "" : "s", 1e3 * seconds / n, views.string().c_str());
  return seconds / n;
}

// Cameras on a circle around the scene box's centre at the training cameras' mean distance,
// `elevation` above the x–z plane (the data's up is +y), looking at the centre, with the
// training views' intrinsics.
std::vector<integrators::Camera> RadianceScene::turntable(const RenderRequest& request) const {
  const Eigen::Vector3d centre = 0.5 * (box_.lower + box_.upper);
  double radius = 0;
  for (const auto& frame : train_->frames) radius += (frame.camera.centre() - centre).norm();
  radius /= static_cast<double>(train_->frames.size());
  const double elevation = request.elevation_degrees * std::numbers::pi / 180;
  std::vector<integrators::Camera> cameras;
  for (int k = 0; k < request.turntable_frames; ++k) {
    const double azimuth = 2 * std::numbers::pi * k / request.turntable_frames;
    const Eigen::Vector3d eye = centre + radius * Eigen::Vector3d(std::cos(elevation) * std::sin(azimuth),
                                                                   std::sin(elevation),
                                                                   std::cos(elevation) * std::cos(azimuth));
    // OpenGL camera axes: x right, y up, looking along −z.
    const Eigen::Vector3d back = (eye - centre).normalized();
    const Eigen::Vector3d right = Eigen::Vector3d::UnitY().cross(back).normalized();
    const Eigen::Vector3d up = back.cross(right);
    integrators::Camera camera;
    camera.intrinsics = train_->intrinsics;
    camera.camera_to_world.block<3, 1>(0, 0) = right;
    camera.camera_to_world.block<3, 1>(0, 1) = up;
    camera.camera_to_world.block<3, 1>(0, 2) = back;
    camera.camera_to_world.block<3, 1>(0, 3) = eye;
    cameras.push_back(camera);
  }
  return cameras;
}

void write_view(const std::filesystem::path& stem, const View& view, const Eigen::MatrixXf& truth, int width,
                int height) {
  auto image = [&](Eigen::MatrixXf pixels) {
    io::Image i;
    i.width = width;
    i.height = height;
    i.channels = static_cast<int>(pixels.cols());
    i.pixels = std::move(pixels);
    return i;
  };
  io::write_png(stem.string() + "_render.png", image(view.rgb));
  if (truth.size() > 0) {
    io::write_png(stem.string() + "_truth.png", image(truth));
    // |error| × 4 so that small errors show.
    io::write_png(stem.string() + "_error.png", image((4 * (view.rgb - truth).cwiseAbs()).eval()));
  }
  io::write_png(stem.string() + "_opacity.png", image(view.opacity));
  // Depth of the pixels the object covers, near dark and far light; misses white.
  const Eigen::ArrayXf hit = (view.opacity.array() > 0.5f).cast<float>();
  const float near = (hit > 0).select(view.depth.array(), INFINITY).minCoeff();
  const float far = (hit > 0).select(view.depth.array(), -INFINITY).maxCoeff();
  const Eigen::VectorXf depth = (hit > 0).select((view.depth.array() - near) / std::max(far - near, 1e-6f), 1.0f);
  io::write_png(stem.string() + "_depth.png", image(depth));
}

}  // namespace nfield::solvers
