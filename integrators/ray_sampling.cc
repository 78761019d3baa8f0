// SPDX-License-Identifier: MIT
#include "integrators/ray_sampling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "integrators/random_bits.h"

namespace nfield::integrators {
namespace {

// δᵢ = tᵢ₊₁ − tᵢ, the last to `far` (never negative, should a sample sit past far).
void interval_lengths(const double* t, Eigen::Index n, double far, double* delta) {
  for (Eigen::Index i = 0; i + 1 < n; ++i) delta[i] = t[i + 1] - t[i];
  if (n > 0) delta[n - 1] = std::max(far - t[n - 1], 0.0);
}


template <typename Scalar>
void check_samples_match(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples,
                         const char* who) {
  samples.validate();
  if (samples.rays() != rays.size())
    throw std::invalid_argument(std::string(who) + ": the samples are of " +
                                std::to_string(samples.rays()) + " rays but the batch has " +
                                std::to_string(rays.size()));
}

}  // namespace

template <typename Scalar>
void RaySamples<Scalar>::validate() const {
  const auto fail = [](const std::string& why) {
    return std::invalid_argument("RaySamples: " + why);
  };
  if (offsets.empty() || offsets.front() != 0) throw fail("offsets must start at 0");
  for (size_t r = 1; r < offsets.size(); ++r)
    if (offsets[r] < offsets[r - 1])
      throw fail("offsets[" + std::to_string(r) + "] = " + std::to_string(offsets[r]) +
                 " is below offsets[" + std::to_string(r - 1) + "] = " +
                 std::to_string(offsets[r - 1]) + ": must not decrease");
  if (offsets.back() != t.size() || delta.size() != t.size())
    throw fail("offsets end at " + std::to_string(offsets.back()) + ", t has " +
               std::to_string(t.size()) + " and delta " + std::to_string(delta.size()) +
               " entries: all three must agree");
}

template <typename Scalar>
Matrix<Scalar> sample_points(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples) {
  check_samples_match(rays, samples, "sample_points");
  Matrix<Scalar> x(samples.size(), 3);
  for (Eigen::Index r = 0; r < samples.rays(); ++r)
    for (Eigen::Index i = samples.begin(r); i < samples.end(r); ++i)
      x.row(i) = rays.origins.row(r) + samples.t(i) * rays.directions.row(r);
  return x;
}

template <typename Scalar>
Matrix<Scalar> sample_directions(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples) {
  check_samples_match(rays, samples, "sample_directions");
  Matrix<Scalar> d(samples.size(), 3);
  for (Eigen::Index r = 0; r < samples.rays(); ++r)
    for (Eigen::Index i = samples.begin(r); i < samples.end(r); ++i)
      d.row(i) = rays.directions.row(r);
  return d;
}

void StratifiedOptions::validate() const {
  if (samples_per_ray < 1)
    throw std::invalid_argument("stratified.samples_per_ray = " + std::to_string(samples_per_ray) +
                                ": must be >= 1");
}

void ImportanceOptions::validate() const {
  if (samples_per_ray < 1)
    throw std::invalid_argument("importance.samples_per_ray = " + std::to_string(samples_per_ray) +
                                ": must be >= 1");
  if (!(weight_floor >= 0 && std::isfinite(weight_floor)))
    throw std::invalid_argument("importance.weight_floor = " + std::to_string(weight_floor) +
                                ": must be finite and >= 0");
}

template <typename Scalar>
RaySamples<Scalar> stratified_samples(const Rays<Scalar>& rays, const StratifiedOptions& options,
                                      std::mt19937_64& rng) {
  options.validate();
  const Eigen::Index n = options.samples_per_ray;
  RaySamples<Scalar> out;
  out.offsets.assign(rays.size() + 1, 0);
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    const double near = rays.near(r), far = rays.far(r);
    if (!std::isfinite(near) || !std::isfinite(far))
      throw std::invalid_argument("stratified_samples: ray " + std::to_string(r) + " has [near, far] = [" +
                                  std::to_string(near) + ", " + std::to_string(far) +
                                  "]: both must be finite (set_bounds or clip_to_box)");
    out.offsets[r + 1] = out.offsets[r] + (far > near ? n : 0);
  }
  out.t.resize(out.offsets.back());
  out.delta.resize(out.offsets.back());
  std::vector<double> t(n), delta(n);
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (out.count(r) == 0) continue;
    const double near = rays.near(r), far = rays.far(r), bin = (far - near) / n;
    for (Eigen::Index i = 0; i < n; ++i)
      t[i] = near + (i + (options.jitter ? uniform01(rng) : 0.5)) * bin;
    interval_lengths(t.data(), n, far, delta.data());
    for (Eigen::Index i = 0; i < n; ++i) {
      out.t(out.begin(r) + i) = static_cast<Scalar>(t[i]);
      out.delta(out.begin(r) + i) = static_cast<Scalar>(delta[i]);
    }
  }
  return out;
}

template <typename Scalar>
RaySamples<Scalar> equal_sections(const Rays<Scalar>& rays, int sections) {
  if (sections < 1) throw std::invalid_argument("equal_sections: sections = " + std::to_string(sections) + ": must be >= 1");
  RaySamples<Scalar> out;
  out.offsets.assign(rays.size() + 1, 0);
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    const double near = rays.near(r), far = rays.far(r);
    if (!std::isfinite(near) || !std::isfinite(far))
      throw std::invalid_argument("equal_sections: ray " + std::to_string(r) + " has [near, far] = [" +
                                  std::to_string(near) + ", " + std::to_string(far) +
                                  "]: both must be finite (set_bounds or clip_to_box)");
    out.offsets[r + 1] = out.offsets[r] + (far > near ? sections : 0);
  }
  out.t.resize(out.offsets.back());
  out.delta.resize(out.offsets.back());
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    if (out.count(r) == 0) continue;
    const double near = rays.near(r), length = (double(rays.far(r)) - near) / sections;
    for (Eigen::Index i = 0; i < sections; ++i) {
      out.t(out.begin(r) + i) = static_cast<Scalar>(near + (i + 0.5) * length);
      out.delta(out.begin(r) + i) = static_cast<Scalar>(length);
    }
  }
  return out;
}

template <typename Scalar>
RaySamples<Scalar> importance_samples(const Rays<Scalar>& rays, const RaySamples<Scalar>& coarse,
                                      const ConstVectorRef<Scalar>& weights,
                                      const ImportanceOptions& options, std::mt19937_64& rng) {
  options.validate();
  check_samples_match(rays, coarse, "importance_samples");
  if (weights.size() != coarse.size())
    throw std::invalid_argument("importance_samples: " + std::to_string(weights.size()) +
                                " weights for " + std::to_string(coarse.size()) +
                                " coarse samples: need one per sample");
  const Eigen::Index n_fine = options.samples_per_ray;
  RaySamples<Scalar> out;
  out.offsets.assign(rays.size() + 1, 0);
  for (Eigen::Index r = 0; r < rays.size(); ++r)
    out.offsets[r + 1] = out.offsets[r] + (coarse.count(r) == 0 ? 0
                                           : n_fine + (options.include_coarse ? coarse.count(r) : 0));
  out.t.resize(out.offsets.back());
  out.delta.resize(out.offsets.back());

  std::vector<double> cdf, coarse_t, fine, merged, delta;
  for (Eigen::Index r = 0; r < rays.size(); ++r) {
    const Eigen::Index first = coarse.begin(r), n = coarse.count(r);
    if (n == 0) continue;
    // The CDF over the coarse intervals; the floor keeps it strictly increasing where set.
    cdf.assign(n + 1, 0.0);
    for (Eigen::Index i = 0; i < n; ++i)
      cdf[i + 1] = cdf[i] + std::max(static_cast<double>(weights(first + i)), 0.0) + options.weight_floor;
    if (!(cdf[n] > 0))
      for (Eigen::Index i = 0; i < n; ++i) cdf[i + 1] = cdf[i] + static_cast<double>(coarse.delta(first + i));
    const double total = cdf[n];
    fine.resize(n_fine);
    Eigen::Index i = 0;
    for (Eigen::Index k = 0; k < n_fine; ++k) {
      const double u = (k + (options.deterministic ? 0.5 : uniform01(rng))) / n_fine * total;
      while (i + 1 < n && u >= cdf[i + 1]) ++i;
      const double mass = cdf[i + 1] - cdf[i];
      const double s = mass > 0 ? std::clamp((u - cdf[i]) / mass, 0.0, 1.0) : 0.0;
      fine[k] = static_cast<double>(coarse.t(first + i)) + s * static_cast<double>(coarse.delta(first + i));
    }
    if (options.include_coarse) {
      merged.resize(n + n_fine);
      coarse_t.resize(n);
      for (Eigen::Index j = 0; j < n; ++j) coarse_t[j] = coarse.t(first + j);
      std::merge(coarse_t.begin(), coarse_t.end(), fine.begin(), fine.end(), merged.begin());
    } else {
      merged = fine;
    }
    delta.resize(merged.size());
    interval_lengths(merged.data(), static_cast<Eigen::Index>(merged.size()),
                     static_cast<double>(rays.far(r)), delta.data());
    for (size_t j = 0; j < merged.size(); ++j) {
      out.t(out.begin(r) + j) = static_cast<Scalar>(merged[j]);
      out.delta(out.begin(r) + j) = static_cast<Scalar>(delta[j]);
    }
  }
  return out;
}

#define NFIELD_INSTANTIATE(Scalar)                                                          \
  template struct RaySamples<Scalar>;                                                       \
  template Matrix<Scalar> sample_points(const Rays<Scalar>&, const RaySamples<Scalar>&);    \
  template Matrix<Scalar> sample_directions(const Rays<Scalar>&, const RaySamples<Scalar>&); \
  template RaySamples<Scalar> stratified_samples(const Rays<Scalar>&, const StratifiedOptions&, \
                                                 std::mt19937_64&);                         \
  template RaySamples<Scalar> equal_sections(const Rays<Scalar>&, int);                        \
  template RaySamples<Scalar> importance_samples<Scalar>(const Rays<Scalar>&, const RaySamples<Scalar>&, \
                                                 const ConstVectorRef<Scalar>&, const ImportanceOptions&, \
                                                 std::mt19937_64&);
NFIELD_INSTANTIATE(float)
NFIELD_INSTANTIATE(double)
#undef NFIELD_INSTANTIATE

template <typename Scalar>
RaySamples<Scalar> ray_range(const RaySamples<Scalar>& samples, Eigen::Index first_ray,
                             Eigen::Index end_ray) {
  RaySamples<Scalar> range;
  const Eigen::Index begin = samples.offsets[first_ray], count = samples.offsets[end_ray] - begin;
  range.offsets.resize(end_ray - first_ray + 1);
  for (Eigen::Index r = first_ray; r <= end_ray; ++r) range.offsets[r - first_ray] = samples.offsets[r] - begin;
  range.t = samples.t.segment(begin, count);
  range.delta = samples.delta.segment(begin, count);
  return range;
}

template RaySamples<float> ray_range(const RaySamples<float>&, Eigen::Index, Eigen::Index);
template RaySamples<double> ray_range(const RaySamples<double>&, Eigen::Index, Eigen::Index);

}  // namespace nfield::integrators
