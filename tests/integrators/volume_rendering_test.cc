// SPDX-License-Identifier: MIT
//
// Volume rendering against closed forms for a constant density, its reverse pass against
// central finite differences (double), empty rays, early termination, float against double.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "integrators/volume_rendering.h"

namespace nfield::integrators {
namespace {

// One ray whose n samples tile [0, length] exactly: tᵢ the interval midpoints, δ = length/n.
template <typename Scalar>
RaySamples<Scalar> tiling(int n, double length) {
  RaySamples<Scalar> s;
  s.offsets = {0, n};
  s.t.resize(n);
  s.delta.setConstant(n, static_cast<Scalar>(length / n));
  for (int i = 0; i < n; ++i) s.t(i) = static_cast<Scalar>((i + 0.5) * length / n);
  return s;
}

TEST(VolumeRendering, ConstantDensityMatchesClosedForm) {
  const double sigma = 1.7, length = 1.3;
  const Eigen::RowVector3d colour(0.2, 0.5, 0.9), bg(1.0, 0.3, 0.0);
  const int n = 2000;
  const auto samples = tiling<double>(n, length);
  const Eigen::VectorXd s = Eigen::VectorXd::Constant(n, sigma);
  const Eigen::MatrixXd rgb = colour.replicate(n, 1);
  const auto out = render<double>(samples, s, rgb, bg);

  // Piecewise-constant σ is exact for a constant σ: A = 1 − Π e^{−σδ} = 1 − e^{−σL}.
  const double opacity = 1 - std::exp(-sigma * length);
  EXPECT_NEAR(out.opacity(0), opacity, 1e-13);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(out.color(0, k), opacity * colour[k] + (1 - opacity) * bg[k], 1e-13);
  EXPECT_NEAR(out.weights.sum(), opacity, 1e-13);
  // D = ∫₀ᴸ t σ e^{−σt} dt = (1 − e^{−σL}(1 + σL))/σ; midpoints make the quadrature O(δ²).
  const double depth = (1 - std::exp(-sigma * length) * (1 + sigma * length)) / sigma;
  const double h = length / n;
  EXPECT_NEAR(out.depth(0), depth, sigma * h * h);
  EXPECT_GT(std::abs(out.depth(0) - depth), 0.0);  // not trivially equal: a quadrature

  // Float, the training type: T is a running product of n = 2000 factors, each rounded.
  const auto samples_f = tiling<float>(n, length);
  const auto out_f = render<float>(samples_f, s.cast<float>(), rgb.cast<float>(), bg.cast<float>());
  EXPECT_NEAR(out_f.opacity(0), opacity, 2e-5);
  EXPECT_NEAR(out_f.depth(0), depth, 2e-5);
}

TEST(VolumeRendering, StratifiedSamplesConvergeToClosedForm) {
  // Through the sampler: the stretch before the first sample is lost (ray_sampling.h), so the
  // error is O(σ·bin).
  Rays<double> rays;
  rays.resize(1);
  rays.origins.setZero();
  rays.directions << 0, 0, 1;
  set_bounds(rays, 0.0, 2.0);
  std::mt19937_64 rng(3);
  const double sigma = 0.8;
  for (bool jitter : {false, true}) {
    const auto samples = stratified_samples(rays, {.samples_per_ray = 512, .jitter = jitter}, rng);
    const auto out = render<double>(samples, Eigen::VectorXd::Constant(samples.size(), sigma),
                                    Eigen::MatrixXd::Ones(samples.size(), 3),
                                    Eigen::RowVector3d::Zero());
    EXPECT_NEAR(out.opacity(0), 1 - std::exp(-sigma * 2.0), sigma * 2.0 / 512) << jitter;
  }
}

// L = Σ_r C̄_r·C_r + Ā_r A_r + D̄_r D_r for fixed adjoints: its derivatives are σ̄ and c̄.
double loss(const RaySamples<double>& samples, const Eigen::VectorXd& sigma,
            const Eigen::MatrixXd& rgb, const Eigen::MatrixXd& bg, const RenderAdjoint<double>& a) {
  const auto out = render<double>(samples, sigma, rgb, bg);
  double l = (out.color.array() * a.color.array()).sum();
  if (a.opacity.size()) l += out.opacity.dot(a.opacity);
  if (a.depth.size()) l += out.depth.dot(a.depth);
  return l;
}

void check_against_differences(bool per_ray_background, bool all_terms) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<int> counts = {5, 0, 1, 12, 3, 30};  // rays of different lengths, one empty
  RaySamples<double> samples;
  for (int c : counts) samples.offsets.push_back(samples.offsets.back() + c);
  const Eigen::Index n = samples.offsets.back(), rays = static_cast<Eigen::Index>(counts.size());
  samples.t.resize(n);
  samples.delta.resize(n);
  for (Eigen::Index r = 0; r < rays; ++r) {
    double t = 0.5 + u(rng);
    for (Eigen::Index i = samples.begin(r); i < samples.end(r); ++i) {
      samples.t(i) = t;
      samples.delta(i) = 0.02 + 0.3 * u(rng);
      t += samples.delta(i);
    }
  }
  Eigen::VectorXd sigma(n);
  Eigen::MatrixXd rgb(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    sigma(i) = 4 * u(rng);
    for (int k = 0; k < 3; ++k) rgb(i, k) = u(rng);
  }
  Eigen::MatrixXd bg(per_ray_background ? rays : 1, 3);
  for (Eigen::Index i = 0; i < bg.size(); ++i) bg(i) = u(rng);
  RenderAdjoint<double> a;
  a.color.resize(rays, 3);
  for (Eigen::Index i = 0; i < a.color.size(); ++i) a.color(i) = u(rng) - 0.5;
  if (all_terms) {
    a.opacity.resize(rays);
    a.depth.resize(rays);
    for (Eigen::Index r = 0; r < rays; ++r) a.opacity(r) = u(rng) - 0.5, a.depth(r) = u(rng) - 0.5;
  }

  Eigen::VectorXd sigma_bar(n);
  Eigen::MatrixXd rgb_bar(n, 3);
  render_backward<double>(samples, sigma, rgb, bg, a, sigma_bar, rgb_bar);

  const double h = 1e-6;
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::VectorXd plus = sigma, minus = sigma;
    plus(i) += h;
    minus(i) -= h;
    const double fd = (loss(samples, plus, rgb, bg, a) - loss(samples, minus, rgb, bg, a)) / (2 * h);
    EXPECT_NEAR(sigma_bar(i), fd, 1e-8) << "sigma " << i;
    for (int k = 0; k < 3; ++k) {
      Eigen::MatrixXd cp = rgb, cm = rgb;
      cp(i, k) += h;
      cm(i, k) -= h;
      const double fdc = (loss(samples, sigma, cp, bg, a) - loss(samples, sigma, cm, bg, a)) / (2 * h);
      EXPECT_NEAR(rgb_bar(i, k), fdc, 1e-8) << "rgb " << i << "," << k;
    }
  }
}

TEST(VolumeRendering, ReversePassMatchesFiniteDifferences) {
  check_against_differences(/*per_ray_background=*/true, /*all_terms=*/true);
  check_against_differences(/*per_ray_background=*/false, /*all_terms=*/false);
}

TEST(VolumeRendering, RayWithoutSamplesShowsTheBackground) {
  RaySamples<double> samples;
  samples.offsets = {0, 2, 2, 3};  // ray 1 has no samples
  samples.t = Eigen::Vector3d(1.0, 1.5, 0.7);
  samples.delta = Eigen::Vector3d(0.5, 0.5, 0.2);
  const Eigen::Vector3d sigma(2.0, 3.0, 1.0);
  const Eigen::MatrixXd rgb = Eigen::MatrixXd::Constant(3, 3, 0.25);
  Eigen::MatrixXd bg(3, 3);
  bg << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9;
  const auto out = render<double>(samples, sigma, rgb, bg);
  EXPECT_EQ(out.color.row(1), bg.row(1));
  EXPECT_EQ(out.opacity(1), 0.0);
  EXPECT_EQ(out.depth(1), 0.0);

  RenderAdjoint<double> a{Eigen::MatrixXd::Zero(3, 3), Eigen::VectorXd(), Eigen::VectorXd()};
  a.color.row(1).setOnes();  // only the empty ray's colour matters to this loss
  Eigen::VectorXd sigma_bar(3);
  Eigen::MatrixXd rgb_bar(3, 3);
  render_backward<double>(samples, sigma, rgb, bg, a, sigma_bar, rgb_bar);
  EXPECT_EQ(sigma_bar.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(rgb_bar.cwiseAbs().maxCoeff(), 0.0);

  // A batch of empty rays only.
  RaySamples<double> none;
  none.offsets = {0, 0, 0};
  const auto empty = render<double>(none, Eigen::VectorXd(), Eigen::MatrixXd(0, 3), bg.topRows(1));
  EXPECT_EQ(empty.color.row(0), bg.row(0));
  EXPECT_EQ(empty.color.row(1), bg.row(0));
}

TEST(VolumeRendering, EarlyTerminationOnlyDropsInvisibleSamples) {
  const int n = 400;
  const auto samples = tiling<double>(n, 4.0);
  Eigen::VectorXd sigma = Eigen::VectorXd::Constant(n, 8.0);  // T < 1e-4 after t ≈ 1.15
  Eigen::MatrixXd rgb(n, 3);
  for (int i = 0; i < n; ++i) rgb.row(i).setConstant(std::sin(0.1 * i) * 0.5 + 0.5);
  const Eigen::RowVector3d bg(0.3, 0.6, 0.9);
  const auto full = render<double>(samples, sigma, rgb, bg);
  const auto fast = render<double>(samples, sigma, rgb, bg, {.early_termination = true});
  EXPECT_LT((full.color - fast.color).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_NEAR(full.opacity(0), fast.opacity(0), 1e-4);
  EXPECT_EQ(fast.weights.tail(n / 2).cwiseAbs().maxCoeff(), 0.0);  // stopped early
  EXPECT_GT(full.weights.tail(n / 2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_THROW(RenderOptions{.termination_threshold = 1.5}.validate(), std::invalid_argument);
}

TEST(VolumeRendering, FloatAgreesWithDouble) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RaySamples<double> samples;
  for (int r = 0; r < 20; ++r) samples.offsets.push_back(samples.offsets.back() + 64);
  const Eigen::Index n = samples.offsets.back();
  samples.t.resize(n);
  samples.delta.setConstant(n, 0.03);
  for (Eigen::Index i = 0; i < n; ++i) samples.t(i) = 2.0 + 0.03 * (i % 64);
  Eigen::VectorXd sigma(n);
  Eigen::MatrixXd rgb(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) sigma(i) = 30 * u(rng) * u(rng), rgb.row(i) << u(rng), u(rng), u(rng);
  const Eigen::RowVector3d bg(1, 1, 1);
  const auto d = render<double>(samples, sigma, rgb, bg);
  RaySamples<float> sf{samples.offsets, samples.t.cast<float>(), samples.delta.cast<float>()};
  const auto f = render<float>(sf, sigma.cast<float>(), rgb.cast<float>(), bg.cast<float>());
  EXPECT_LT((d.color - f.color.cast<double>()).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((d.depth - f.depth.cast<double>()).cwiseAbs().maxCoeff(), 1e-5);

  RenderAdjoint<double> a{Eigen::MatrixXd::Ones(20, 3), Eigen::VectorXd::Ones(20), Eigen::VectorXd::Ones(20)};
  RenderAdjoint<float> af{a.color.cast<float>(), a.opacity.cast<float>(), a.depth.cast<float>()};
  Eigen::VectorXd sb(n);
  Eigen::MatrixXd cb(n, 3);
  Eigen::VectorXf sbf(n);
  Eigen::MatrixXf cbf(n, 3);
  render_backward<double>(samples, sigma, rgb, bg, a, sb, cb);
  render_backward<float>(sf, sigma.cast<float>(), rgb.cast<float>(), bg.cast<float>(), af, sbf, cbf);
  EXPECT_LT((sb - sbf.cast<double>()).cwiseAbs().maxCoeff(), 1e-5 * sb.cwiseAbs().maxCoeff());
  EXPECT_LT((cb - cbf.cast<double>()).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(VolumeRendering, ReadsBlocksOfANetworkOutput) {
  // σ and rgb as column blocks of one N × 4 output, the adjoint written into the same layout.
  const int n = 10;
  const auto samples = tiling<double>(n, 1.0);
  Eigen::MatrixXd output = Eigen::MatrixXd::Constant(n, 4, 0.5);
  Eigen::MatrixXd output_bar(n, 4);
  const auto out = render<double>(samples, output.col(0), output.rightCols(3), Eigen::RowVector3d::Zero());
  RenderAdjoint<double> a{Eigen::MatrixXd::Ones(1, 3), {}, {}};
  render_backward<double>(samples, output.col(0), output.rightCols(3), Eigen::RowVector3d::Zero(), a,
                          output_bar.col(0), output_bar.rightCols(3));
  EXPECT_NEAR(out.opacity(0), 1 - std::exp(-0.5), 1e-14);
  EXPECT_NEAR(output_bar.rightCols(3).sum(), 3 * out.opacity(0), 1e-14);
}

TEST(VolumeRendering, RejectsMismatchedShapes) {
  const auto samples = tiling<double>(4, 1.0);
  EXPECT_THROW(render<double>(samples, Eigen::VectorXd::Ones(3), Eigen::MatrixXd::Ones(4, 3),
                              Eigen::RowVector3d::Zero()),
               std::invalid_argument);
  EXPECT_THROW(render<double>(samples, Eigen::VectorXd::Ones(4), Eigen::MatrixXd::Ones(4, 3),
                              Eigen::MatrixXd::Zero(2, 3)),
               std::invalid_argument);
}

}  // namespace
}  // namespace nfield::integrators
