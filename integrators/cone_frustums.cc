// SPDX-License-Identifier: MIT
#include "integrators/cone_frustums.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace nfield::integrators {

FrustumMoments frustum_moments(double t0, double t1, double radius) {
  if (!(t0 >= 0 && t1 >= t0))
    throw std::invalid_argument("frustum_moments: needs 0 <= t0 <= t1, got [" + std::to_string(t0) + ", " +
                                std::to_string(t1) + "]");
  const double m = 0.5 * (t0 + t1), h = 0.5 * (t1 - t0);
  const double m2 = m * m, h2 = h * h, d = 3 * m2 + h2;
  if (d == 0) return {};  // the apex: a point
  FrustumMoments out;
  out.mean = m + 2 * m * h2 / d;
  out.along = h2 / 3 - (4.0 / 15.0) * h2 * h2 * (12 * m2 - h2) / (d * d);
  out.across = radius * radius * (m2 / 4 + 5 * h2 / 12 - 4 * h2 * h2 / (15 * d));
  return out;
}

template <typename Scalar>
SampleGaussians<Scalar> sample_gaussians(const Rays<Scalar>& rays, const RaySamples<Scalar>& samples) {
  samples.validate();
  if (samples.rays() != rays.size() || rays.radius.size() != rays.size())
    throw std::invalid_argument("sample_gaussians: the samples are of " + std::to_string(samples.rays()) +
                                " rays, the batch has " + std::to_string(rays.size()) + " and " +
                                std::to_string(rays.radius.size()) + " radii");
  SampleGaussians<Scalar> out;
  out.mean.resize(samples.size(), 3);
  out.variance.resize(samples.size(), 3);
  for (Eigen::Index r = 0; r < samples.rays(); ++r) {
    const Eigen::RowVector3d o = rays.origins.row(r).template cast<double>();
    const Eigen::RowVector3d d = rays.directions.row(r).template cast<double>();
    const Eigen::RowVector3d d2 = d.cwiseProduct(d);
    const double radius = static_cast<double>(rays.radius(r));
    for (Eigen::Index i = samples.begin(r); i < samples.end(r); ++i) {
      const double t = static_cast<double>(samples.t(i)), half = 0.5 * static_cast<double>(samples.delta(i));
      const FrustumMoments f = frustum_moments(std::max(t - half, 0.0), std::max(t + half, 0.0), radius);
      out.mean.row(i) = (o + f.mean * d).template cast<Scalar>();
      out.variance.row(i) =
          (f.along * d2 + f.across * (Eigen::RowVector3d::Ones() - d2)).template cast<Scalar>();
    }
  }
  return out;
}

template SampleGaussians<float> sample_gaussians(const Rays<float>&, const RaySamples<float>&);
template SampleGaussians<double> sample_gaussians(const Rays<double>&, const RaySamples<double>&);

}  // namespace nfield::integrators
