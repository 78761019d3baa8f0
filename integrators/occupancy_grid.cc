// SPDX-License-Identifier: MIT
#include "integrators/occupancy_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "integrators/random_bits.h"

namespace nfield::integrators {
namespace {

template <typename T>
std::invalid_argument invalid(const std::string& field, T value, const std::string& rule) {
  std::ostringstream out;
  out << field << " = " << value << ": " << rule;
  return std::invalid_argument(out.str());
}

}  // namespace

void OccupancyGridOptions::validate() const {
  if (resolution < 1 || resolution > 1024)
    throw invalid("occupancy_grid.resolution", resolution, "must be in [1, 1024]");
  if (!(threshold >= 0 && std::isfinite(threshold)))
    throw invalid("occupancy_grid.threshold", threshold, "must be finite and >= 0");
  if (cells_per_update < 0)
    throw invalid("occupancy_grid.cells_per_update", cells_per_update,
                  "must be >= 0 (0: every cell)");
  if (batch_points < 1) throw invalid("occupancy_grid.batch_points", batch_points, "must be >= 1");
}

void MarchOptions::validate() const {
  if (steps_per_diagonal < 1)
    throw invalid("march.steps_per_diagonal", steps_per_diagonal, "must be >= 1");
}

OccupancyGrid::OccupancyGrid(const SceneBox& box, const OccupancyGridOptions& options)
    : box_(box), options_(options), rng_(options.seed) {
  box_.validate();
  options_.validate();
  const Eigen::Index n = Eigen::Index{options_.resolution} * options_.resolution * options_.resolution;
  density_.assign(n, 0.f);
  bits_.assign((n + 63) / 64, ~std::uint64_t{0});
  if (n % 64 != 0) bits_.back() = (std::uint64_t{1} << (n % 64)) - 1;  // no bits past the grid
}

void OccupancyGrid::update(const DensityFunction& density, double decay) {
  if (!(decay >= 0 && decay <= 1)) throw invalid("occupancy_grid update: decay", decay, "must be in [0, 1]");
  const Eigen::Index n = cells();
  const int res = options_.resolution;

  // The cells to evaluate, in the order their jitter is drawn.
  std::vector<Eigen::Index> chosen;
  if (options_.cells_per_update == 0 || options_.cells_per_update >= n) {
    chosen.resize(n);
    for (Eigen::Index c = 0; c < n; ++c) chosen[c] = c;
  } else {
    std::vector<Eigen::Index> occupied;
    for (Eigen::Index c = 0; c < n; ++c)
      if (bit(c)) occupied.push_back(c);
    for (Eigen::Index m = 0; m < options_.cells_per_update; ++m)
      chosen.push_back(static_cast<Eigen::Index>(uniform_index(rng_, n)));
    if (!occupied.empty())
      for (Eigen::Index m = 0; m < options_.cells_per_update; ++m)
        chosen.push_back(occupied[uniform_index(rng_, occupied.size())]);
  }

  if (options_.rule == OccupancyGridOptions::Rule::kDecayedMax)
    for (float& d : density_) d = static_cast<float>(decay * d);

  const Eigen::Vector3d cell = cell_size();
  const Eigen::Index batch = options_.batch_points;
  Eigen::MatrixXd points;
  for (size_t first = 0; first < chosen.size(); first += batch) {
    const Eigen::Index count = std::min<Eigen::Index>(batch, chosen.size() - first);
    points.resize(count, 3);
    for (Eigen::Index m = 0; m < count; ++m) {
      const Eigen::Index c = chosen[first + m];
      const Eigen::Index ijk[3] = {c % res, (c / res) % res, c / (Eigen::Index{res} * res)};
      for (int a = 0; a < 3; ++a)
        points(m, a) = box_.lower[a] + (ijk[a] + uniform01(rng_)) * cell[a];
    }
    const Eigen::VectorXd sigma = density(points);
    if (sigma.size() != count)
      throw std::runtime_error("OccupancyGrid::update: the density function returned " +
                               std::to_string(sigma.size()) + " values for " +
                               std::to_string(count) + " points");
    for (Eigen::Index m = 0; m < count; ++m) {
      const double s = std::isnan(sigma(m)) ? 0.0 : sigma(m);
      float& d = density_[chosen[first + m]];
      if (options_.rule == OccupancyGridOptions::Rule::kDecayedMax)
        d = std::max(d, static_cast<float>(s));
      else
        d = static_cast<float>(decay * d + (1 - decay) * s);
    }
  }

  double sum = 0;
  for (float d : density_) sum += d;
  threshold_ = std::min(sum / static_cast<double>(n), options_.threshold);
  std::fill(bits_.begin(), bits_.end(), 0);
  for (Eigen::Index c = 0; c < n; ++c)
    if (density_[c] > threshold_) bits_[c >> 6] |= std::uint64_t{1} << (c & 63);
}

void OccupancyGrid::locate(const Eigen::Vector3d& x, int ijk[3]) const {
  const int res = options_.resolution;
  for (int a = 0; a < 3; ++a)
    ijk[a] = std::clamp(
        static_cast<int>(std::floor((x[a] - box_.lower[a]) / (box_.upper[a] - box_.lower[a]) * res)),
        0, res - 1);
}

bool OccupancyGrid::occupied(const Eigen::Vector3d& x) const {
  if (!box_.contains(x)) return false;
  int ijk[3];
  locate(x, ijk);
  return cell_occupied(ijk[0], ijk[1], ijk[2]);
}

Eigen::Index OccupancyGrid::occupied_cells() const {
  Eigen::Index count = 0;
  for (std::uint64_t word : bits_) count += std::popcount(word);
  return count;
}

double OccupancyGrid::step(const MarchOptions& options) const {
  options.validate();
  return box_.size().norm() / options.steps_per_diagonal;
}

template <typename Visit>
void OccupancyGrid::march_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                              double near, double far, double step, Visit&& visit) const {
  const auto [enter, exit] = box_.intersect(origin, direction);
  const double t0 = std::max(near, enter), t1 = std::min(far, exit);
  if (!(t0 < t1)) return;
  const Eigen::Vector3d cell = cell_size();
  // Intervals [t0 + k·s, min(t0 + (k+1)·s, t1)], sampled at their midpoints.
  for (Eigen::Index k = 0;;) {
    const double a = t0 + static_cast<double>(k) * step;
    if (a >= t1) break;
    const double b = std::min(a + step, t1);
    const double t = 0.5 * (a + b);
    const Eigen::Vector3d x = origin + t * direction;
    int ijk[3];
    locate(x, ijk);
    if (cell_occupied(ijk[0], ijk[1], ijk[2])) {
      visit(t, b - a);
      ++k;
      continue;
    }
    // Empty cell: leave it. Its exit along the ray is the nearest far face over the axes.
    double cell_exit = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      if (direction[axis] == 0) continue;
      const double face = box_.lower[axis] + (ijk[axis] + (direction[axis] > 0 ? 1 : 0)) * cell[axis];
      cell_exit = std::min(cell_exit, (face - origin[axis]) / direction[axis]);
    }
    // The first interval whose midpoint t0 + (k' + ½)s lies beyond the exit.
    const double next = std::floor((cell_exit - t0) / step - 0.5) + 1;
    if (!(next < static_cast<double>(std::numeric_limits<Eigen::Index>::max() / 2))) break;
    k = std::max(k + 1, static_cast<Eigen::Index>(next));
  }
}

template <typename Scalar>
RaySamples<Scalar> OccupancyGrid::march(const Rays<Scalar>& rays, const MarchOptions& options) const {
  const double s = step(options);
  const Eigen::Index n_rays = rays.size();
  const auto ray = [&](Eigen::Index r) {
    return std::pair<Eigen::Vector3d, Eigen::Vector3d>{
        rays.origins.row(r).transpose().template cast<double>(),
        rays.directions.row(r).transpose().template cast<double>()};
  };
  // Two passes over the rays, counting then writing, so both run in parallel over rays.
  RaySamples<Scalar> out;
  out.offsets.assign(n_rays + 1, 0);
#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index r = 0; r < n_rays; ++r) {
    const auto [o, d] = ray(r);
    Eigen::Index count = 0;
    march_ray(o, d, rays.near(r), rays.far(r), s, [&](double, double) { ++count; });
    out.offsets[r + 1] = count;
  }
  for (Eigen::Index r = 0; r < n_rays; ++r) out.offsets[r + 1] += out.offsets[r];
  out.t.resize(out.offsets.back());
  out.delta.resize(out.offsets.back());
#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index r = 0; r < n_rays; ++r) {
    const auto [o, d] = ray(r);
    Eigen::Index i = out.offsets[r];
    march_ray(o, d, rays.near(r), rays.far(r), s, [&](double t, double delta) {
      out.t(i) = static_cast<Scalar>(t);
      out.delta(i) = static_cast<Scalar>(delta);
      ++i;
    });
  }
  return out;
}

template RaySamples<float> OccupancyGrid::march(const Rays<float>&, const MarchOptions&) const;
template RaySamples<double> OccupancyGrid::march(const Rays<double>&, const MarchOptions&) const;

}  // namespace nfield::integrators
