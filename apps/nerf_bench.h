// SPDX-License-Identifier: MIT
//
// `nfield bench --nerf`: training rays per second and the time to render one test view of a
// radiance field (configs/nerf_bunny.yaml by default), for bench/compare_nerf.sh to set
// beside the PyTorch peer bench/torch_nerf.py.
//
// A training step here is the one `nfield run` takes on that config, taken by the library's
// own solvers::Trainer (one Adam stage): the problem's loss terms draw the rays (random pixels
// of all training images, clipped to the scene box, jittered stratified samples),
// solvers::ResidualLoss wraps the ray residual (volume rendering and its adjoint,
// solvers/problems/nerf.cc), Field::value_and_gradient runs the forward and reverse passes
// over groups of samples, and Adam updates θ. No callback updates the problem's occupancy
// grid, so every step samples `render.samples` stratified points per ray, as the PyTorch peer
// does. Where the time goes is measured by a second run of the same calls (draw, passes, Adam)
// timed apart, on a field of the same initialization.
//
// Reported: rays/s and the median step of the trainer; from the timed-apart run, the share
// of the steps' time spent drawing rays, in the network's passes, in the rendering loss
// (thread time in its callback / threads) and in Adam; the GFLOP/s of the dense layers' products over the time of the network passes
// against plain Eigen products of the same shapes on the step's sample count (apps/gemm_rate.h)
// and against the machine's float FMA peak on the same threads (the ceiling of any
// implementation: the step's GFLOP of products over it is the shortest step possible);
// and the median time to render the first test view (every pixel, or every k-th of every
// k-th row, at the stratified midpoints). Ends with one JSON line:
//   {"impl": "nfield", "bench": "nerf", "rays_per_s", "median_step_ms" (the trainer's),
//    "anatomy_median_step_ms" (the timed-apart run's), "share_network",
//    "share_rendering", "mlp_gflops", "gemm_gflops", "mlp_gemm_ratio", "fma_peak_gflops",
//    "mlp_peak_ratio", "step_gflop", "frame_ms", …}
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace nfield::apps {

struct NerfBenchOptions {
  std::filesystem::path config = "configs/nerf_bunny.yaml";
  std::vector<std::string> overrides;  // --set, applied to the config
  long rays = 0;                       // rays per step; 0: the config's training.batch.rays
  int steps = 20;                      // timed steps
  int warmup = 3;                      // untimed steps first
  int threads = 0;                     // 0: the config's training.threads (0: all cores)
  int render_stride = 1;               // render every k-th pixel of every k-th row
  int render_repeats = 3;              // timed renders
  bool json_only = false;
};

// Throws io::ConfigError for a bad config, CLI::ValidationError for a config without a
// radiance field.
void run_nerf_bench(const NerfBenchOptions& options);

}  // namespace nfield::apps
