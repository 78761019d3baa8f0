// SPDX-License-Identifier: MIT
//
// `nfield bench --autoint`: AutoInt volume rendering (problem: autoint_nerf) at K sections
// per ray against NeRF's quadrature at the same training wall time. Trains, one after the
// other and each for `seconds` of Adam:
//
//   nerf_quadrature   NeRF with `nerf_samples` stratified samples per ray, in training and
//                     rendering (configs/nerf_bunny_quadrature.yaml): the reference
//   nerf_grid         optionally NeRF marched through its occupancy grid
//                     (configs/nerf_bunny.yaml), with and without the grid at render time
//   autoint_K         configs/autoint_bunny.yaml with render.sections = K, for each K, and
//                     render.samples_per_section = samples_per_ray / K (at least 1), equal
//                     sections
//   autoint_K_sampler the same with the sampling network placing the sections
//                     (render.sampler: the config's section, or the defaults); a ray then
//                     costs K + 1 evaluations of the field and one of the network ("K+1+S")
//
// and renders each one's test views (`nfield run`'s outputs under OUT/RUN). Prints a table:
// field evaluations per ray, training steps, mean test PSNR, ms to render a frame, the
// speed-up of rendering over the reference, the PSNR lost against it, and the targets
// for K = 8, 16, 32 (speed-up at least, dB lost at most). Writes the rows to OUT/autoint_bench.json
// and prints each as a JSON line:
//   {"bench":"autoint","run", "sections", "evaluations_per_ray", "sampling_network", "steps", "train_s",
//    "psnr_mean", "ssim_mean", "render_ms", "speedup", "psnr_loss_db", "target_speedup",
//    "target_psnr_loss_db", "met"}
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

struct AutointBenchOptions {
  std::filesystem::path autoint_config = "configs/autoint_bunny.yaml";
  std::filesystem::path nerf_config = "configs/nerf_bunny_quadrature.yaml";
  std::filesystem::path grid_config = "configs/nerf_bunny.yaml";
  std::vector<int> sections{4, 8, 16, 32};
  double seconds = 120;     // of training, each run
  int nerf_samples = 128;   // samples per ray of the reference
  // AutoInt's training samples per ray: K sections get max(1, round(this / K)) samples each
  // (render.samples_per_section), so that every K trains at about the same cost a step.
  int samples_per_ray = 64;
  bool with_grid = true;    // also train and time the occupancy-grid NeRF
  std::string sampler = "both";  // AutoInt runs with equal sections (off), sampled (on), or both
  std::filesystem::path out = "out/autoint_bench";
  std::vector<std::string> overrides;  // --set, applied to every run's config
};

// Returns 0, or 130 when a run was interrupted. Throws io::ConfigError for a bad config.
int run_autoint_bench(const AutointBenchOptions& options);

}  // namespace nfield::apps
