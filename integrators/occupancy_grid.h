// SPDX-License-Identifier: MIT
//
// An occupancy grid over the scene box, to skip empty space when sampling rays (Instant NGP,
// Müller et al. 2022, Sec. 4 and App. E.2).
//
// State: R³ cells over the box (cell (i, j, k) is index i + R·(j + R·k), x fastest), each
// with a density estimate dᵢ (float, as Instant NGP keeps it) and an occupancy bit. Before
// the first update every cell is occupied, so the marcher samples everywhere while the field
// is still untrained.
//
// update(density, decay) evaluates the field's density at one uniformly jittered point in
// each chosen cell (all cells, or a random subset: cells_per_update drawn uniformly over the
// grid plus as many over the cells occupied now, as Instant NGP does once training is under
// way) and folds it into dᵢ by the rule:
//
//   kDecayedMax     dᵢ ← decay·dᵢ for every cell, then dᵢ ← max(dᵢ, σ) for a chosen cell
//                   (Instant NGP's "EMA": a cell lights up on the first update that sees
//                   density in it and fades by `decay` per update once it stops)
//   kMovingAverage  dᵢ ← decay·dᵢ + (1 − decay)·σ for a chosen cell (a true EMA: smoother,
//                   but a cell needs about 1/(1 − decay) updates to reach its density)
//
// and then marks cell i occupied iff dᵢ > min(mean over all cells of d, threshold). The
// mean caps the threshold so that a field whose densities are all small still keeps its
// densest cells. Pitfall: one point per cell can miss a thin structure or the edge of a
// surface that cuts a corner of the cell; repeated updates with fresh jitter (and the
// decayed max, which remembers a hit for many updates) make that unlikely.
//
// The density function maps points (N × 3, world coordinates) to densities (N), so this
// layer does not know the network; it is called with at most batch_points points at a time.
// The grid works in double (a float network casts at its side of the std::function).
//
// march() samples rays at a fixed step s along t, only inside occupied cells. On each ray's
// [near, far] ∩ box = [t₀, t₁] the intervals are [t₀ + k·s, t₀ + (k+1)·s] (the last one cut at
// t₁), each with one sample at its midpoint and δ = its length, i.e. exactly the samples of
// a dense march at step s minus those in empty cells. On meeting an empty cell the marcher
// jumps to the first interval whose midpoint lies beyond the cell's exit (a DDA step), so
// empty space costs one look-up per cell, not per step. The result is in ray_sampling.h's flat
// layout; a ray through empty space only has no samples and renders as background.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "integrators/ray_sampling.h"
#include "integrators/rays.h"
#include "integrators/scene_box.h"

namespace nfield::integrators {

struct OccupancyGridOptions {
  enum class Rule { kDecayedMax, kMovingAverage };

  int resolution = 128;               // R cells per axis; in [1, 1024]
  double threshold = 0.01;            // density above which a cell is occupied (capped by the mean); ≥ 0
  Rule rule = Rule::kDecayedMax;
  Eigen::Index cells_per_update = 0;  // 0: every cell on every update; else ≥ 1 (see above)
  Eigen::Index batch_points = 65536;  // points per call of the density function; ≥ 1
  std::uint64_t seed = 0;             // the jitter and the subsets of cells

  void validate() const;
};

struct MarchOptions {
  // Step s = box diagonal / steps_per_diagonal (Instant NGP: √3/1024 for the unit cube).
  int steps_per_diagonal = 1024;  // ≥ 1

  void validate() const;
};

class OccupancyGrid {
 public:
  using DensityFunction = std::function<Eigen::VectorXd(const Eigen::MatrixXd&)>;

  explicit OccupancyGrid(const SceneBox& box, const OccupancyGridOptions& options = {});

  // One update (see the top of this file); decay in [0, 1].
  void update(const DensityFunction& density, double decay);

  // Whether the cell holding x is occupied; false outside the box.
  bool occupied(const Eigen::Vector3d& x) const;
  // Cell (i, j, k), each in [0, R): not range-checked (the marcher's inner loop).
  bool cell_occupied(int i, int j, int k) const { return bit(cell_index(i, j, k)); }
  Eigen::Index occupied_cells() const;
  Eigen::Index cells() const { return static_cast<Eigen::Index>(density_.size()); }
  int resolution() const { return options_.resolution; }
  const SceneBox& box() const { return box_; }
  const OccupancyGridOptions& options() const { return options_; }
  // dᵢ per cell, in cell order.
  const std::vector<float>& densities() const { return density_; }
  // The threshold the last update used: min(mean d, options.threshold); 0 before any update.
  double threshold() const { return threshold_; }
  Eigen::Vector3d cell_size() const { return box_.size() / options_.resolution; }
  // The step march() takes.
  double step(const MarchOptions& options) const;

  template <typename Scalar>
  RaySamples<Scalar> march(const Rays<Scalar>& rays, const MarchOptions& options = {}) const;

 private:
  Eigen::Index cell_index(int i, int j, int k) const {
    return i + Eigen::Index{options_.resolution} * (j + Eigen::Index{options_.resolution} * k);
  }
  // The cell holding x, clamped to the grid (x on or just past a face, by rounding).
  void locate(const Eigen::Vector3d& x, int ijk[3]) const;
  bool bit(Eigen::Index cell) const { return (bits_[cell >> 6] >> (cell & 63)) & 1U; }
  // Calls visit(t, delta) for each sample of the ray, in order.
  template <typename Visit>
  void march_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double near,
                 double far, double step, Visit&& visit) const;

  SceneBox box_;
  OccupancyGridOptions options_;
  std::vector<float> density_;
  std::vector<std::uint64_t> bits_;
  double threshold_ = 0;
  std::mt19937_64 rng_;
};

}  // namespace nfield::integrators
