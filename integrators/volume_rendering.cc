// SPDX-License-Identifier: MIT
#include "integrators/volume_rendering.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nfield::integrators {
namespace {

template <typename Scalar>
void check_inputs(const char* who, const RaySamples<Scalar>& samples,
                  const ConstVectorRef<Scalar>& sigma,
                  const ConstMatrixRef<Scalar>& rgb,
                  const ConstMatrixRef<Scalar>& background) {
  samples.validate();
  const auto fail = [&](const std::string& what, Eigen::Index rows, Eigen::Index cols,
                        const std::string& expected) {
    std::ostringstream out;
    out << who << ": " << what << " is " << rows << " x " << cols << ", expected " << expected;
    return std::invalid_argument(out.str());
  };
  const Eigen::Index n = samples.size(), r = samples.rays();
  if (sigma.size() != n)
    throw fail("sigma", sigma.size(), 1, std::to_string(n) + " x 1 (one per sample)");
  if (rgb.rows() != n || rgb.cols() != 3)
    throw fail("rgb", rgb.rows(), rgb.cols(), std::to_string(n) + " x 3 (one per sample)");
  if ((background.rows() != 1 && background.rows() != r) || background.cols() != 3)
    throw fail("background", background.rows(), background.cols(),
               "1 x 3 or " + std::to_string(r) + " x 3 (one per ray)");
}

}  // namespace

void RenderOptions::validate() const {
  if (!(termination_threshold > 0 && termination_threshold < 1)) {
    std::ostringstream out;
    out << "render.termination_threshold = " << termination_threshold << ": must be in (0, 1)";
    throw std::invalid_argument(out.str());
  }
}

template <typename Scalar>
RenderResult<Scalar> render(const RaySamples<Scalar>& samples,
                            const ConstVectorRef<Scalar>& sigma,
                            const ConstMatrixRef<Scalar>& rgb,
                            const ConstMatrixRef<Scalar>& background,
                            const RenderOptions& options) {
  options.validate();
  check_inputs("render", samples, sigma, rgb, background);
  const Eigen::Index rays = samples.rays();
  const bool shared_background = background.rows() == 1;
  const Scalar stop = options.early_termination ? static_cast<Scalar>(options.termination_threshold)
                                                : Scalar(0);
  RenderResult<Scalar> out;
  out.color.resize(rays, 3);
  out.opacity.resize(rays);
  out.depth.resize(rays);
  out.weights.setZero(samples.size());
#pragma omp parallel for schedule(static) if (samples.size() > 16384)
  for (Eigen::Index r = 0; r < rays; ++r) {
    Scalar transmittance(1), depth(0), c0(0), c1(0), c2(0);
    for (Eigen::Index i = samples.begin(r); i < samples.end(r); ++i) {
      if (transmittance < stop) break;  // stop is 0 without early termination
      const Scalar tau = sigma(i) * samples.delta(i);
      const Scalar w = transmittance * -std::expm1(-tau);
      out.weights(i) = w;
      c0 += w * rgb(i, 0);
      c1 += w * rgb(i, 1);
      c2 += w * rgb(i, 2);
      depth += w * samples.t(i);
      transmittance *= std::exp(-tau);
    }
    const Eigen::Index b = shared_background ? 0 : r;
    out.color(r, 0) = c0 + transmittance * background(b, 0);
    out.color(r, 1) = c1 + transmittance * background(b, 1);
    out.color(r, 2) = c2 + transmittance * background(b, 2);
    out.opacity(r) = Scalar(1) - transmittance;
    out.depth(r) = depth;
  }
  return out;
}

template <typename Scalar>
void render_backward(const RaySamples<Scalar>& samples,
                     const ConstVectorRef<Scalar>& sigma,
                     const ConstMatrixRef<Scalar>& rgb,
                     const ConstMatrixRef<Scalar>& background,
                     const RenderAdjoint<Scalar>& adjoint, VectorRef<Scalar> sigma_bar,
                     MatrixRef<Scalar> rgb_bar) {
  check_inputs("render_backward", samples, sigma, rgb, background);
  const Eigen::Index rays = samples.rays(), n = samples.size();
  const auto fail = [](const std::string& what) {
    return std::invalid_argument("render_backward: " + what);
  };
  if (adjoint.color.rows() != rays || adjoint.color.cols() != 3)
    throw fail("adjoint.color must be " + std::to_string(rays) + " x 3 (one per ray)");
  if (adjoint.opacity.size() != 0 && adjoint.opacity.size() != rays)
    throw fail("adjoint.opacity must be empty or of " + std::to_string(rays) + " entries");
  if (adjoint.depth.size() != 0 && adjoint.depth.size() != rays)
    throw fail("adjoint.depth must be empty or of " + std::to_string(rays) + " entries");
  if (sigma_bar.size() != n || rgb_bar.rows() != n || rgb_bar.cols() != 3)
    throw fail("sigma_bar and rgb_bar must be " + std::to_string(n) + " and " +
               std::to_string(n) + " x 3 (one per sample)");
  const bool shared_background = background.rows() == 1;
  const bool has_opacity = adjoint.opacity.size() != 0, has_depth = adjoint.depth.size() != 0;

#pragma omp parallel for schedule(static) if (n > 16384)
  for (Eigen::Index r = 0; r < rays; ++r) {
    const Eigen::Index first = samples.begin(r), last = samples.end(r);
    if (first == last) continue;
    // Forward sweep: the weights, parked in sigma_bar until the reverse sweep reads them.
    Scalar transmittance(1);
    for (Eigen::Index i = first; i < last; ++i) {
      const Scalar tau = sigma(i) * samples.delta(i);
      sigma_bar(i) = transmittance * -std::expm1(-tau);
      transmittance *= std::exp(-tau);
    }
    const Scalar cb0 = adjoint.color(r, 0), cb1 = adjoint.color(r, 1), cb2 = adjoint.color(r, 2);
    const Scalar ab = has_opacity ? adjoint.opacity(r) : Scalar(0);
    const Scalar db = has_depth ? adjoint.depth(r) : Scalar(0);
    const Eigen::Index b = shared_background ? 0 : r;
    // Reverse sweep: R = what lies behind sample i, T_next = Tᵢ₊₁ rebuilt from the back.
    Scalar behind = transmittance * (cb0 * background(b, 0) + cb1 * background(b, 1) +
                                     cb2 * background(b, 2));
    Scalar t_next = transmittance;
    for (Eigen::Index i = last - 1; i >= first; --i) {
      const Scalar w = sigma_bar(i);
      const Scalar g = cb0 * rgb(i, 0) + cb1 * rgb(i, 1) + cb2 * rgb(i, 2) + ab + db * samples.t(i);
      sigma_bar(i) = samples.delta(i) * (t_next * g - behind);
      rgb_bar(i, 0) = w * cb0;
      rgb_bar(i, 1) = w * cb1;
      rgb_bar(i, 2) = w * cb2;
      behind += w * g;
      t_next += w;
    }
  }
}

#define NFIELD_INSTANTIATE(Scalar)                                                            \
  template RenderResult<Scalar> render<Scalar>(const RaySamples<Scalar>&,                             \
                                       const ConstVectorRef<Scalar>&,               \
                                       const ConstMatrixRef<Scalar>&,               \
                                       const ConstMatrixRef<Scalar>&,               \
                                       const RenderOptions&);                                 \
  template void render_backward<Scalar>(const RaySamples<Scalar>&,                                    \
                                const ConstVectorRef<Scalar>&,                      \
                                const ConstMatrixRef<Scalar>&,                      \
                                const ConstMatrixRef<Scalar>&,                      \
                                const RenderAdjoint<Scalar>&, VectorRef<Scalar>,     \
                                MatrixRef<Scalar>);
NFIELD_INSTANTIATE(float)
NFIELD_INSTANTIATE(double)
#undef NFIELD_INSTANTIATE

}  // namespace nfield::integrators
