// SPDX-License-Identifier: MIT
// small_gemm against a double product, element by element within the float bound
// |C − C*| ≤ γ_k (|β| |C₀| + |op(A)| |op(B)|), γ_k = k u / (1 − k u), u = 2⁻²⁴, on shapes that
// cross every block edge of the kernel (kc = 256, mc = 128, nc = 264; tiles 16 × 6); and
// the affine layer's three products in float against the same layer in double. Built twice:
// with the kernel this machine runs, and as SmallGemmPortable with NFIELD_GEMM_FORCE_PORTABLE
// (the portable kernel, which an AVX2 build otherwise never calls).
#include "autodiff/small_gemm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "fields/dense.h"

#ifdef NFIELD_GEMM_FORCE_PORTABLE
#define SMALL_GEMM_SUITE SmallGemmPortable
#else
#define SMALL_GEMM_SUITE SmallGemm
#endif

namespace nfield::autodiff {
namespace {

using MatrixF = Eigen::MatrixXf;
using MatrixD = Eigen::MatrixXd;

MatrixF random_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  MatrixF m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = u(rng);
  return m;
}

MatrixD op(GemmOp o, const MatrixF& x) {
  return o == GemmOp::kNone ? MatrixD(x.cast<double>()) : MatrixD(x.cast<double>().transpose());
}

struct Shape {
  Eigen::Index m, n, k;
};

void expect_product(GemmOp op_a, GemmOp op_b, Shape s, float beta, std::mt19937& rng) {
  const MatrixF a = op_a == GemmOp::kNone ? random_matrix(s.m, s.k, rng) : random_matrix(s.k, s.m, rng);
  const MatrixF b = op_b == GemmOp::kNone ? random_matrix(s.k, s.n, rng) : random_matrix(s.n, s.k, rng);
  MatrixF c0 = random_matrix(s.m + 3, s.n, rng);  // leading dimension m + 3: rows below m stay as they are
  if (beta == 0.0f) c0.setConstant(std::numeric_limits<float>::quiet_NaN());
  MatrixF c = c0;
  small_gemm(op_a, op_b, s.m, s.n, s.k, a.data(), a.rows(), b.data(), b.rows(), beta, c.data(), c.rows());

  const MatrixD c_top = c0.topRows(s.m).cast<double>();
  const MatrixD exact = (beta == 0.0f ? MatrixD::Zero(s.m, s.n) : MatrixD(beta * c_top)) + op(op_a, a) * op(op_b, b);
  const MatrixD scale = (beta == 0.0f ? MatrixD::Zero(s.m, s.n) : MatrixD(std::abs(beta) * c_top.cwiseAbs())) +
                        op(op_a, a).cwiseAbs() * op(op_b, b).cwiseAbs();
  const double u = std::ldexp(1.0, -24), gamma = (s.k + 1) * u / (1 - (s.k + 1) * u);
  for (Eigen::Index j = 0; j < s.n; ++j) {
    for (Eigen::Index i = 0; i < s.m; ++i)
      ASSERT_LE(std::abs(c(i, j) - exact(i, j)), gamma * scale(i, j))
          << "m " << s.m << " n " << s.n << " k " << s.k << " at (" << i << ", " << j << ") beta " << beta;
    for (Eigen::Index i = s.m; i < c.rows(); ++i)
      if (beta != 0.0f) ASSERT_EQ(c(i, j), c0(i, j)) << "row " << i << " below m written";
  }
}

TEST(SMALL_GEMM_SUITE, EveryTranspositionOnShapesAcrossBlockEdges) {
  std::mt19937 rng(7);
  const Shape shapes[] = {{1, 1, 1},     {16, 6, 1},   {17, 7, 3},      {15, 5, 8},     {128, 264, 256},
                          {129, 265, 257}, {640, 256, 256}, {300, 40, 600}, {33, 100, 17}, {256, 16, 1000},
                          {48, 30, 9},   {2, 300, 70}};
  for (GemmOp op_a : {GemmOp::kNone, GemmOp::kTranspose})
    for (GemmOp op_b : {GemmOp::kNone, GemmOp::kTranspose})
      for (const Shape& s : shapes)
        for (float beta : {0.0f, 1.0f, -0.5f}) expect_product(op_a, op_b, s, beta, rng);
}

TEST(SMALL_GEMM_SUITE, EmptyInnerDimensionScalesC) {
  MatrixF c = MatrixF::Constant(5, 4, 2.0f);
  small_gemm(GemmOp::kNone, GemmOp::kNone, 5, 4, 0, nullptr, 5, nullptr, 1, 0.5f, c.data(), 5);
  EXPECT_TRUE((c.array() == 1.0f).all());
  c.setConstant(std::numeric_limits<float>::quiet_NaN());
  small_gemm(GemmOp::kNone, GemmOp::kNone, 5, 4, 0, nullptr, 5, nullptr, 1, 0.0f, c.data(), 5);
  EXPECT_TRUE((c.array() == 0.0f).all());
}

TEST(SMALL_GEMM_SUITE, RunsTheKernelOfItsBuild) {
#ifdef NFIELD_GEMM_FORCE_PORTABLE
  EXPECT_STREQ(small_gemm_kernel_name(), "portable 16x6");
#elif defined(__AVX2__) && defined(__FMA__)
  EXPECT_STREQ(small_gemm_kernel_name(), "avx2-fma 16x6");
#endif
}

TEST(SMALL_GEMM_SUITE, PaysOnlyAtTheLayerShapesItWasMeasuredToWin) {
  EXPECT_TRUE(small_gemm_pays(640, 256, 256));
  EXPECT_TRUE(small_gemm_pays(16, 16, 640));  // a 16-wide layer's weight gradient
  EXPECT_FALSE(small_gemm_pays(640, 16, 16));  // its forward product
  EXPECT_FALSE(small_gemm_pays(640, 1, 256));  // an output layer
  EXPECT_FALSE(small_gemm_pays(8, 8, 640));
}

// The affine layer's forward, weight-gradient and input-adjoint products in float (through
// small_gemm at these widths) against the same layer in double, relative to the magnitudes
// summed: the float bound with k = the inner dimension of each product.
TEST(SMALL_GEMM_SUITE, DenseFloatLayerMatchesDouble) {
  std::mt19937 rng(11);
  for (auto [in, out] : {std::pair<Eigen::Index, Eigen::Index>{64, 48}, {32, 256}, {256, 32}}) {
    const Eigen::Index points = 100;
    const int streams = 4;
    fields::Dense<float> layer_f(in, out);
    fields::Dense<double> layer_d(in, out);
    const MatrixF params = random_matrix(layer_f.parameter_count(), 1, rng);
    const Eigen::VectorXd params_d = params.cast<double>();
    Streams<float> a_f, z_f, zbar_f, abar_f;
    Streams<double> a_d, z_d, zbar_d, abar_d;
    a_f.resize(points, streams, in);
    a_f.data = random_matrix(points * streams, in, rng);
    a_d.resize(points, streams, in);
    a_d.data = a_f.data.cast<double>();
    const StreamLayout layout(StreamSpec::values(2));  // Dense reads no layout
    layer_f.forward(layout, params.data(), a_f, z_f, nullptr);
    layer_d.forward(layout, params_d.data(), a_d, z_d, nullptr);
    const double u = std::ldexp(1.0, -24);
    const MatrixD z_scale = a_d.data.cwiseAbs() *
                            Eigen::Map<const MatrixD>(params_d.data(), out, in).cwiseAbs().transpose();
    EXPECT_LE(((z_f.data.cast<double>() - z_d.data).cwiseAbs() - (in + 2) * u * (z_scale.array() + 1).matrix())
                  .maxCoeff(), 0.0);

    zbar_f.resize(points, streams, out);
    zbar_f.data = random_matrix(points * streams, out, rng);
    zbar_d.resize(points, streams, out);
    zbar_d.data = zbar_f.data.cast<double>();
    Eigen::VectorXf grad_f = Eigen::VectorXf::Zero(layer_f.parameter_count());
    Eigen::VectorXd grad_d = Eigen::VectorXd::Zero(layer_d.parameter_count());
    SavedTensors<float> saved_f;
    SavedTensors<double> saved_d;
    layer_f.backward(layout, params.data(), a_f, saved_f, zbar_f, grad_f.data(), &abar_f);
    layer_d.backward(layout, params_d.data(), a_d, saved_d, zbar_d, grad_d.data(), &abar_d);
    const Eigen::Index rows = points * streams;
    const MatrixD w_scale = zbar_d.data.cwiseAbs().transpose() * a_d.data.cwiseAbs();
    const MatrixD w_error = (Eigen::Map<const MatrixF>(grad_f.data(), out, in).cast<double>() -
                             Eigen::Map<const MatrixD>(grad_d.data(), out, in)).cwiseAbs();
    EXPECT_LE((w_error - (rows + 1) * u * w_scale).maxCoeff(), 0.0);
    const MatrixD abar_scale = zbar_d.data.cwiseAbs() * Eigen::Map<const MatrixD>(params_d.data(), out, in).cwiseAbs();
    EXPECT_LE(((abar_f.data.cast<double>() - abar_d.data).cwiseAbs() - (out + 1) * u * abar_scale).maxCoeff(), 0.0);
  }
}

}  // namespace
}  // namespace nfield::autodiff
