// SPDX-License-Identifier: MIT
//
// The hash-grid encoding (fields/hash_grid.h) beyond the registered-network harness of
// tests/autodiff (every stream rule against jets and finite differences, parameter
// gradients, Jacobians, with a small smoothstep grid):
//   * level resolutions, dense and hashed tables, table rows by hand;
//   * the value (and with smoothstep the gradient) continuous across cell faces; with linear
//     weights no ∂²/∂x_j² inside a cell but mixed partials;
//   * inside a network (dense → tanh → hash grid → dense), so that its input streams are
//     general directions that differ per point and carry operator inputs: streams against
//     central differences of the network, parameter gradients (its tables and, through its
//     input adjoint, the layer before it) from value, tangent and operator losses against
//     central differences, per-point Jacobian rows against per-point gradients, for dense
//     and hashed levels and both interpolations;
//   * a field on [−1, 1]² saved and loaded bit for bit; config keys read, written back and
//     rejected with file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <random>

#include "autodiff/sequential.h"
#include "fields/activation_layer.h"
#include "fields/dense.h"
#include "fields/field_config.h"
#include "fields/field_io.h"
#include "fields/hash_grid.h"
#include "tests/testing/squares_loss.h"
#include "tests/testing/stream_checks.h"
#include "tests/testing/scratch.h"

namespace nfield::fields {
namespace {

using autodiff::LambdaLoss;
using autodiff::Matrix;
using autodiff::StreamLayout;
using autodiff::Streams;
using autodiff::StreamSpec;
using testutil::random_matrix;
using testutil::ridders;

// The hash grid's own options in `o` (its defaults put there first when it holds none).
HashGridOptions& hg(EncodingOptions& o) {
  if (!o.own.has_value()) o.own = HashGridOptions{};
  return std::any_cast<HashGridOptions&>(o.own);
}
const HashGridOptions& hg(const EncodingOptions& o) { return own_options<HashGridOptions>(o); }

EncodingOptions grid(const std::string& interpolation, int levels, int log2_table_size,
                     int base, int finest, int dim, double lo = 0, double hi = 1) {
  EncodingOptions o;
  o.type = "hash_grid";
  hg(o).interpolation = interpolation;
  hg(o).levels = levels;
  hg(o).features_per_level = 2;
  hg(o).log2_table_size = log2_table_size;
  hg(o).base_resolution = base;
  hg(o).finest_resolution = finest;
  hg(o).include_input = false;
  o.lower.assign(dim, lo);
  o.upper.assign(dim, hi);
  o.validate(dim);
  return o;
}

// Streams of a module alone at points x.
Matrix<double> module_streams(const autodiff::Module<double>& module, const double* params,
                              const StreamLayout& layout, const Eigen::MatrixXd& x) {
  Streams<double> in, out;
  autodiff::seed_input_streams<double>(layout, x, in);
  module.forward(layout, params, in, out, nullptr);
  return out.data;
}

TEST(HashGridLevels, ResolutionsGrowGeometricallyAndTablesAreDenseWhileTheyFit) {
  EncodingOptions o;
  o.type = "hash_grid";  // defaults: 16 levels, 16 … 512, T = 2^19, F = 2
  for (int d : {2, 3}) {
    const std::vector<HashGridLevel> levels = hash_grid_levels(o, d);
    ASSERT_EQ(levels.size(), 16u);
    Eigen::Index rows = 0;
    for (int l = 0; l < 16; ++l) {
      // b = 32^(1/15): N_l = ⌊16 · 2^(l/3)⌋.
      EXPECT_EQ(levels[l].resolution, static_cast<int>(std::floor(16 * std::pow(2.0, l / 3.0) + 1e-6)))
          << "level " << l;
      const double vertices = std::pow(levels[l].resolution + 2.0, d);
      EXPECT_EQ(levels[l].dense, vertices <= 524288.0) << "level " << l;
      EXPECT_EQ(levels[l].rows, levels[l].dense ? static_cast<Eigen::Index>(vertices) : 524288);
      EXPECT_EQ(levels[l].first_row, rows);
      rows += levels[l].rows;
    }
    EXPECT_EQ(levels.back().resolution, 512);
    EXPECT_EQ(levels.front().dense, true);
    EXPECT_EQ(levels.back().dense, d == 2);  // 514² fits 2^19, 514³ does not
    hg(o).include_input = d == 3;
    const HashGridEncoding<float> encoding(o, d);
    EXPECT_EQ(encoding.parameter_count(), 2 * rows);
    EXPECT_EQ(encoding.output_width(), (d == 3 ? 3 : 0) + 32);
  }
}

TEST(HashGridRows, DenseAndHashedRowsByHand) {
  // Level 0: N = 2, 4² = 16 rows, dense; level 1: N = 40, 42² > 2^10, hashed.
  const EncodingOptions o = grid("linear", 2, 10, 2, 40, 2);
  HashGridEncoding<double> encoding(o, 2);
  ASSERT_TRUE(encoding.levels()[0].dense);
  ASSERT_FALSE(encoding.levels()[1].dense);
  const int v0[2] = {3, 1};
  EXPECT_EQ(encoding.row(0, v0), 3u + 1u * 4u);
  const int v1[2] = {5, 7};
  EXPECT_EQ(encoding.row(1, v1), (5u ^ (7u * 2654435761u)) & 1023u);

  // A table that is zero but for vertex (5, 7) of level 1, feature 1: at a point of the cell
  // whose lowest corner is (5, 7), that feature is the corner's weight (1 − t₀)(1 − t₁).
  const double t0 = 0.25, t1 = 0.6;
  Eigen::MatrixXd x(1, 2);
  x << (5 + t0 - 0.5) / 40, (7 + t1 - 0.5) / 40;  // p = N x + 1/2
  std::vector<std::uint32_t> corners;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const int v[2] = {5 + a, 7 + b};
      corners.push_back(encoding.row(1, v));
    }
  std::sort(corners.begin(), corners.end());
  ASSERT_EQ(std::unique(corners.begin(), corners.end()), corners.end()) << "corners collide";
  Eigen::VectorXd params = Eigen::VectorXd::Zero(encoding.parameter_count());
  params[(encoding.levels()[1].first_row + encoding.row(1, v1)) * 2 + 1] = 1;
  const StreamLayout layout(StreamSpec::gradient(2));
  const Matrix<double> out = module_streams(encoding, params.data(), layout, x);
  EXPECT_NEAR(out(0, 3), (1 - t0) * (1 - t1), 1e-14);
  EXPECT_EQ(out(0, 0), 0);
  EXPECT_EQ(out(0, 2), 0);
  // ∂/∂x = N ∂/∂t.
  EXPECT_NEAR(out(1, 3), -40 * (1 - t1), 1e-12);
  EXPECT_NEAR(out(2, 3), -40 * (1 - t0), 1e-12);
}

// Values on both sides of a face of each level (a dense and a hashed one), along each axis.
TEST(HashGridContinuity, ValueAcrossFacesAndSmoothstepAndCubicGradientToo) {
  for (const char* interpolation : {"linear", "smoothstep", "cubic"})
    for (int d : {2, 3}) {
      const EncodingOptions o = grid(interpolation, 2, 10, 3, 40, d, -1, 1);
      HashGridEncoding<double> encoding(o, d);
      ASSERT_TRUE(encoding.levels()[0].dense);
      ASSERT_FALSE(encoding.levels()[1].dense);
      std::mt19937_64 rng(5 + d);
      const Eigen::VectorXd params = random_matrix(encoding.parameter_count(), 1, rng);
      const StreamLayout layout(StreamSpec::gradient(d));
      for (int l = 0; l < 2; ++l)
        for (int axis = 0; axis < d; ++axis) {
          const int n = encoding.levels()[l].resolution;
          Eigen::MatrixXd x = random_matrix(2, d, rng, -0.9, 0.9);
          // p = N (x + 1)/2 + 1/2 = 2 (a face), just below and above.
          const double face = (2 - 0.5) * 2.0 / n - 1;
          x(0, axis) = face - 1e-9;
          x(1, axis) = face + 1e-9;
          x(1, (axis + 1) % d) = x(0, (axis + 1) % d);
          if (d == 3) x(1, (axis + 2) % d) = x(0, (axis + 2) % d);
          const Matrix<double> s = module_streams(encoding, params.data(), layout, x);
          const auto value = s.middleRows(0, 2);
          const auto slope = s.middleRows(layout.tangent(axis) * 2, 2);
          const std::string where = std::string(interpolation) + " d=" + std::to_string(d) +
                                    " level " + std::to_string(l) + " axis " + std::to_string(axis);
          EXPECT_LE((value.row(0) - value.row(1)).cwiseAbs().maxCoeff(), 1e-6) << where;
          const Eigen::RowVectorXd jump = slope.row(0) - slope.row(1);
          const double slope_jump = jump.segment(2 * l, 2).cwiseAbs().maxCoeff();
          if (std::string(interpolation) != "linear")
            EXPECT_LE(slope_jump, 1e-5 * n) << where;
          else
            EXPECT_GE(slope_jump, 1e-2) << where;  // linear weights: the gradient jumps
        }
    }
}

// Cubic levels are C²: ∂²/∂x_j² is continuous across faces (smoothstep's jumps there).
TEST(HashGridCubic, SecondDerivativesContinuousAcrossFaces) {
  for (int d : {2, 3}) {
    const EncodingOptions o = grid("cubic", 2, 10, 3, 40, d, -1, 1);
    HashGridEncoding<double> encoding(o, d);
    ASSERT_TRUE(encoding.levels()[0].dense);
    ASSERT_FALSE(encoding.levels()[1].dense);
    std::mt19937_64 rng(7 + d);
    const Eigen::VectorXd params = random_matrix(encoding.parameter_count(), 1, rng);
    for (int axis = 0; axis < d; ++axis) {
      StreamSpec spec = StreamSpec::gradient(d);
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(d, d);
      c(axis, axis) = 1;
      spec.add_operator(c);
      const StreamLayout layout(spec);
      for (int l = 0; l < 2; ++l) {
        const int n = encoding.levels()[l].resolution;
        Eigen::MatrixXd x = random_matrix(2, d, rng, -0.9, 0.9);
        const double face = (2 - 0.5) * 2.0 / n - 1;
        x(0, axis) = face - 1e-9;
        x(1, axis) = face + 1e-9;
        for (int k = 1; k < d; ++k) x(1, (axis + k) % d) = x(0, (axis + k) % d);
        const Matrix<double> s = module_streams(encoding, params.data(), layout, x);
        const auto curvature = s.middleRows(layout.op(0) * 2, 2).middleCols(2 * l, 2);
        const double scale = curvature.cwiseAbs().maxCoeff();
        EXPECT_GT(scale, 1e-3 * n * n);
        EXPECT_LE((curvature.row(0) - curvature.row(1)).cwiseAbs().maxCoeff(), 1e-6 * scale)
            << "d=" << d << " level " << l << " axis " << axis;
      }
    }
  }
}

// Dense rows of a cubic level: vertices −1 … N + 2 per axis, stored one further.
TEST(HashGridCubic, RowsStartOneVertexBeforeTheBox) {
  const EncodingOptions o = grid("cubic", 2, 10, 2, 40, 2);
  HashGridEncoding<double> encoding(o, 2);
  ASSERT_TRUE(encoding.levels()[0].dense);
  EXPECT_EQ(encoding.levels()[0].rows, 6 * 6);  // (N + 4)²
  ASSERT_FALSE(encoding.levels()[1].dense);
  const int first[2] = {-1, -1}, last[2] = {4, 4}, v[2] = {2, -1};
  EXPECT_EQ(encoding.row(0, first), 0u);
  EXPECT_EQ(encoding.row(0, last), 35u);
  EXPECT_EQ(encoding.row(0, v), 3u);
  const int h[2] = {5, 7};
  EXPECT_EQ(encoding.row(1, h), (6u ^ (8u * 2654435761u)) & 1023u);
}

// B-splines reproduce quadratics: with level coefficients c_i = f(i) − (f_{p₀p₀} + f_{p₁p₁})/6
// for a quadratic f of the level's coordinates p = N x + 1/2, the feature is f everywhere in
// the box, outer half cells included (they reach the vertices −1 and N + 2), and so are its
// gradient and its constant Laplacian, which smoothstep's weights cannot carry.
TEST(HashGridCubic, ALevelReproducesAQuadratic) {
  const int n = 5;
  const EncodingOptions o = grid("cubic", 1, 10, n, n, 2);
  HashGridEncoding<double> encoding(o, 2);
  ASSERT_TRUE(encoding.levels()[0].dense);
  // f(p) = a + b·p + ½ pᵀ H p.
  const double a = 0.3, b0 = -1.1, b1 = 0.7, h00 = 0.9, h01 = -0.4, h11 = 2.3;
  auto f = [&](double p0, double p1) {
    return a + b0 * p0 + b1 * p1 + 0.5 * (h00 * p0 * p0 + 2 * h01 * p0 * p1 + h11 * p1 * p1);
  };
  Eigen::VectorXd params = Eigen::VectorXd::Zero(encoding.parameter_count());
  for (int i = -1; i <= n + 2; ++i)
    for (int j = -1; j <= n + 2; ++j) {
      const int v[2] = {i, j};
      params[encoding.row(0, v) * 2] = f(i, j) - (h00 + h11) / 6;
      params[encoding.row(0, v) * 2 + 1] = 1;  // partition of unity
    }
  const StreamLayout layout(StreamSpec::laplacian(2));
  std::mt19937_64 rng(3);
  Eigen::MatrixXd x = random_matrix(40, 2, rng, 0, 1);
  x.row(0) << 0, 0;
  x.row(1) << 1, 1;
  x.row(2) << 0, 1;
  const Matrix<double> s = module_streams(encoding, params.data(), layout, x);
  const Eigen::Index m = x.rows();
  for (Eigen::Index p = 0; p < m; ++p) {
    const double p0 = n * x(p, 0) + 0.5, p1 = n * x(p, 1) + 0.5;
    EXPECT_NEAR(s(p, 0), f(p0, p1), 1e-12) << p;
    EXPECT_NEAR(s(p, 1), 1, 1e-14) << p;
    EXPECT_NEAR(s(layout.tangent(0) * m + p, 0), n * (b0 + h00 * p0 + h01 * p1), 1e-11) << p;
    EXPECT_NEAR(s(layout.tangent(1) * m + p, 0), n * (b1 + h01 * p0 + h11 * p1), 1e-11) << p;
    EXPECT_NEAR(s(layout.op(0) * m + p, 0), n * n * (h00 + h11), 1e-10) << p;
    EXPECT_NEAR(s(layout.tangent(0) * m + p, 1), 0, 1e-12) << p;
    EXPECT_NEAR(s(layout.op(0) * m + p, 1), 0, 1e-10) << p;
  }
}

// Over one cell, ∂²/∂x₀² of a smoothstep level averages to zero for any table; a cubic
// level's does not (midpoint rule, exact for smoothstep's s'' linear in t).
TEST(HashGridCubic, MeanCurvatureOverACellIsZeroOnlyForSmoothstep) {
  for (const char* interpolation : {"smoothstep", "cubic"}) {
    const int n = 4;
    const EncodingOptions o = grid(interpolation, 1, 10, n, n, 2);
    HashGridEncoding<double> encoding(o, 2);
    std::mt19937_64 rng(17);
    const Eigen::VectorXd params = random_matrix(encoding.parameter_count(), 1, rng);
    StreamSpec spec = StreamSpec::gradient(2);
    spec.add_operator(Eigen::Matrix2d{{1, 0}, {0, 0}});
    const StreamLayout layout(spec);
    const int k = 64;  // points across the cell p₀ ∈ [2, 3), at p₁ = 2.3
    Eigen::MatrixXd x(k, 2);
    for (int i = 0; i < k; ++i) x.row(i) << (2 + (i + 0.5) / k - 0.5) / n, (2.3 - 0.5) / n;
    const Matrix<double> s = module_streams(encoding, params.data(), layout, x);
    const Eigen::MatrixXd curvature = s.middleRows(layout.op(0) * k, k);
    const double mean = curvature.col(0).mean(), size = curvature.col(0).cwiseAbs().maxCoeff();
    ASSERT_GT(size, 0.1);
    if (std::string(interpolation) == "smoothstep")
      EXPECT_LE(std::abs(mean), 1e-12 * size);
    else
      EXPECT_GE(std::abs(mean), 1e-2 * size);
  }
}

TEST(HashGridLinear, NoPureSecondDerivativesInsideCellsButMixedOnes) {
  const EncodingOptions o = grid("linear", 3, 10, 2, 12, 2);
  HashGridEncoding<double> encoding(o, 2);
  std::mt19937_64 rng(11);
  const Eigen::VectorXd params = random_matrix(encoding.parameter_count(), 1, rng);
  StreamSpec spec = StreamSpec::gradient(2);
  spec.add_operator(Eigen::Matrix2d{{1, 0}, {0, 0}});
  spec.add_operator(Eigen::Matrix2d{{0, 0}, {0, 1}});
  spec.add_operator(Eigen::Matrix2d{{0, 1}, {1, 0}});
  const StreamLayout layout(spec);
  const Eigen::MatrixXd x = random_matrix(6, 2, rng, 0.05, 0.95);
  const Matrix<double> s = module_streams(encoding, params.data(), layout, x);
  EXPECT_EQ(s.middleRows(layout.op(0) * 6, 6).cwiseAbs().maxCoeff(), 0);
  EXPECT_EQ(s.middleRows(layout.op(1) * 6, 6).cwiseAbs().maxCoeff(), 0);
  EXPECT_GT(s.middleRows(layout.op(2) * 6, 6).cwiseAbs().minCoeff(), 0);
}

// ---------------------------------------------------------------------------------------
// Inside a network: z = tanh(W x + b) ∈ (−1, 1)³ feeds a hash grid on [−1, 1]³.

struct Network {
  autodiff::Sequential<double> net{{.block_points = 2, .threads = 1}};
  autodiff::Sequential<double> inner{{.block_points = 2, .threads = 1}};  // dense → tanh
  const HashGridEncoding<double>* encoding = nullptr;
  Eigen::VectorXd theta;

  // sin(π p) of every level and axis at every point: its signs change on cell faces.
  std::vector<bool> face_pattern(const Eigen::VectorXd& t, const Eigen::MatrixXd& x) const {
    Streams<double> z;
    inner.evaluate(t.data(), StreamLayout(StreamSpec::values(2)), x, z);
    std::vector<bool> signs;
    for (const HashGridLevel& level : encoding->levels())
      for (Eigen::Index i = 0; i < z.data.size(); ++i)
        signs.push_back(std::sin(std::numbers::pi * (level.resolution * (z.data(i) + 1) / 2 + 0.5)) > 0);
    return signs;
  }
};

Network make_network(const std::string& interpolation, std::uint64_t seed) {
  Network n;
  // N = 2, 4, 9: (N + 2)³ = 64, 216 rows dense, 1331 > 2^10 hashed.
  EncodingOptions o = grid(interpolation, 3, 10, 2, 9, 3, -1, 1);
  auto encoding = std::make_unique<HashGridEncoding<double>>(o, 3);
  n.encoding = encoding.get();
  n.net.add(std::make_unique<Dense<double>>(2, 3));
  n.net.add(std::make_unique<ActivationLayer<double>>(ActivationSpec{"tanh", 1}, 3));
  n.net.add(std::move(encoding));
  n.net.add(std::make_unique<Dense<double>>(n.net.output_width(), 2));
  n.inner.add(std::make_unique<Dense<double>>(2, 3));
  n.inner.add(std::make_unique<ActivationLayer<double>>(ActivationSpec{"tanh", 1}, 3));
  std::mt19937_64 rng(seed);
  n.theta = random_matrix(n.net.parameter_count(), 1, rng);
  n.theta.head(9) *= 1.5;  // W, b of the first layer: z spread over the grid
  return n;
}

// Points whose z stays away from every face.
Eigen::MatrixXd points_off_faces(const Network& n, int count, std::mt19937_64& rng) {
  Eigen::MatrixXd x(count, 2);
  for (int p = 0; p < count; ++p)
    for (;;) {
      const Eigen::MatrixXd candidate = random_matrix(1, 2, rng, -0.9, 0.9);
      Streams<double> z;
      n.inner.evaluate(n.theta.data(), StreamLayout(StreamSpec::values(2)), candidate, z);
      bool ok = true;
      for (const HashGridLevel& level : n.encoding->levels())
        for (Eigen::Index i = 0; i < 3; ++i) {
          const double pos = level.resolution * (z.data(i) + 1) / 2 + 0.5;
          ok = ok && std::abs(pos - std::round(pos)) > 0.05;
        }
      if (ok) {
        x.row(p) = candidate;
        break;
      }
    }
  return x;
}

StreamSpec rich_spec(std::mt19937_64& rng) {
  StreamSpec s = StreamSpec::values(2);
  s.tangents = random_matrix(2, 3, rng);  // three general directions
  s.add_operator(Eigen::MatrixXd::Identity(3, 3));
  s.add_operator(testutil::random_symmetric(3, rng));
  s.set_taylor(random_matrix(2, 2, rng), 3);
  return s;
}

class HashGridInNetwork : public ::testing::TestWithParam<const char*> {};

TEST_P(HashGridInNetwork, StreamsMatchCentralDifferences) {
  std::mt19937_64 rng(21);
  const Network n = make_network(GetParam(), 3);
  const Eigen::MatrixXd x = points_off_faces(n, 4, rng);
  const std::vector<bool> pattern = n.face_pattern(n.theta, x);
  for (StreamSpec spec : {StreamSpec::laplacian(2), rich_spec(rng)}) {
    if (spec.operators.size() == 1) spec.add_operator(testutil::random_symmetric(2, rng));
    const StreamLayout layout(spec);
    const Eigen::Index points = x.rows(), count = layout.count();
    Streams<double> out;
    n.net.evaluate(n.theta.data(), layout, x, out);
    auto stream = [&](const Eigen::MatrixXd& m, int s) { return m.middleRows(s * points, points); };
    // All streams differentiated along u, never across a face.
    auto along = [&](const Eigen::VectorXd& u) {
      double h = 0.02 / u.norm();
      while (n.face_pattern(n.theta, x.rowwise() + h * u.transpose()) != pattern ||
             n.face_pattern(n.theta, x.rowwise() - h * u.transpose()) != pattern)
        h /= 2;
      const auto r = ridders(
          [&](double tau) -> Eigen::VectorXd {
            Streams<double> s;
            n.net.evaluate(n.theta.data(), layout, x.rowwise() + tau * u.transpose(), s);
            return Eigen::Map<const Eigen::VectorXd>(s.data.data(), s.data.size());
          },
          h);
      return Eigen::MatrixXd(Eigen::Map<const Eigen::MatrixXd>(r.value.data(), count * points, 2));
    };
    auto expect_close = [&](const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected,
                            const std::string& what) {
      const double err = testutil::relative_error(actual, expected, 1e-6);
      EXPECT_LE(err, 1e-6) << GetParam() << " " << what;
    };
    std::vector<Eigen::MatrixXd> d_tangent;
    for (int j = 0; j < layout.tangents(); ++j) d_tangent.push_back(along(spec.tangents.col(j)));
    for (int j = 0; j < layout.tangents(); ++j)
      expect_close(stream(out.data, layout.tangent(j)), stream(d_tangent[j], 0),
                   "tangent " + std::to_string(j));
    for (int q = 0; q < layout.operators(); ++q) {
      Eigen::MatrixXd op = Eigen::MatrixXd::Zero(points, 2);
      for (int i = 0; i < layout.tangents(); ++i)
        for (int j = 0; j < layout.tangents(); ++j)
          op += spec.operators[q](i, j) * stream(d_tangent[j], layout.tangent(i));
      expect_close(stream(out.data, layout.op(q)), op, "operator " + std::to_string(q));
    }
    for (int p = 0; p < layout.taylor_dirs(); ++p) {
      const Eigen::MatrixXd d1 = along(spec.taylor_directions.col(p));
      for (int k = 1; k <= layout.taylor_order(); ++k)
        expect_close(k * stream(out.data, layout.taylor(p, k)),
                     stream(d1, k == 1 ? 0 : layout.taylor(p, k - 1)),
                     "taylor " + std::to_string(p) + " order " + std::to_string(k));
    }
  }
}

// ½ Σ w_s out_s² over the streams of one kind (value, tangents, operators, Taylor).
Eigen::MatrixXd weights_of(const StreamLayout& layout, const std::string& kind) {
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(layout.count(), 2);
  for (int s = 0; s < layout.count(); ++s) {
    const bool on = kind == "all" || testutil::stream_kind(layout, s).rfind(kind, 0) == 0;
    if (on) w.row(s).setConstant(1.0 / (1 + s));
  }
  return w;
}

TEST_P(HashGridInNetwork, ParameterGradientsFromEveryStreamMatchCentralDifferences) {
  std::mt19937_64 rng(33);
  const Network n = make_network(GetParam(), 4);
  const Eigen::MatrixXd x = points_off_faces(n, 3, rng);
  const StreamLayout layout(rich_spec(rng));
  const Eigen::Index first_table = n.net.parameter_offset(2);
  const std::vector<bool> pattern = n.face_pattern(n.theta, x);
  // Central differences of the loss along parameter direction u, never moving a point's z
  // across a face.
  auto directional = [&](const testutil::SquaresLoss<double>& loss, const Eigen::VectorXd& u) {
    double h = 1e-2;
    while (n.face_pattern(n.theta + h * u, x) != pattern || n.face_pattern(n.theta - h * u, x) != pattern)
      h /= 2;
    return ridders(
               [&](double tau) {
                 const Eigen::VectorXd t = n.theta + tau * u;
                 Streams<double> out;
                 n.net.evaluate(t.data(), layout, x, out);
                 return Eigen::VectorXd::Constant(1, loss.value(out));
               },
               h, 1, 4, 2.0)
        .value[0];
  };
  for (const std::string kind : {"value", "tangent", "operator", "taylor", "all"}) {
    const testutil::SquaresLoss<double> loss(weights_of(layout, kind));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n.theta.size());
    n.net.value_and_gradient(n.theta.data(), layout, x, loss, g.data());
    // Each loss reaches the tables and, through the encoding's input adjoint, the first layer.
    EXPECT_GT(g.head(9).cwiseAbs().maxCoeff(), 0) << kind;
    EXPECT_GT(g.segment(first_table, n.encoding->parameter_count()).cwiseAbs().maxCoeff(), 0) << kind;
    Eigen::VectorXd fd(g.size());
    for (Eigen::Index i = 0; i < g.size(); ++i) {
      if (i >= first_table && i < first_table + n.encoding->parameter_count() && g[i] == 0) {
        fd[i] = 0;  // a table row no point touches: checked by the directions below
        continue;
      }
      fd[i] = directional(loss, Eigen::VectorXd::Unit(g.size(), i));
    }
    const double err = (g - fd).cwiseAbs().maxCoeff() / fd.cwiseAbs().maxCoeff();
    EXPECT_LE(err, 1e-6) << GetParam() << " " << kind;
    // Random directions over all parameters, untouched rows included.
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd u = random_matrix(g.size(), 1, rng).normalized();
      const double expected = directional(loss, u);
      EXPECT_NEAR(g.dot(u), expected, 1e-6 * std::abs(expected)) << GetParam() << " " << kind;
    }
  }
}

// Values alone take a faster path (forward_values): the same values, and the same gradient
// as the general path (checked above) for a loss of the value.
TEST_P(HashGridInNetwork, ValuesAloneMatchTheGeneralPath) {
  std::mt19937_64 rng(55);
  const Network n = make_network(GetParam(), 6);
  const Eigen::MatrixXd x = random_matrix(37, 2, rng, -0.9, 0.9);
  const StreamLayout values(StreamSpec::values(2)), rich(rich_spec(rng));
  Streams<double> a, b;
  n.net.evaluate(n.theta.data(), values, x, a);
  n.net.evaluate(n.theta.data(), rich, x, b);
  EXPECT_LE((a.data - b.stream(0)).cwiseAbs().maxCoeff(), 1e-14 * b.stream(0).cwiseAbs().maxCoeff());
  Eigen::VectorXd ga = Eigen::VectorXd::Zero(n.theta.size()), gb = ga;
  n.net.value_and_gradient(n.theta.data(), values, x, testutil::SquaresLoss<double>(weights_of(values, "value")),
                           ga.data());
  n.net.value_and_gradient(n.theta.data(), rich, x, testutil::SquaresLoss<double>(weights_of(rich, "value")),
                           gb.data());
  EXPECT_LE((ga - gb).cwiseAbs().maxCoeff(), 1e-13 * gb.cwiseAbs().maxCoeff()) << GetParam();
  EXPECT_GT(gb.segment(n.net.parameter_offset(2), n.encoding->parameter_count()).cwiseAbs().maxCoeff(), 0);
}

// r(x) = Δu₀ + u₁ ∂u₀/∂x: one residual per point.
class Residual final : public autodiff::StreamResidual<double> {
 public:
  int components() const override { return 1; }
  void evaluate(Eigen::Index, const StreamLayout& layout, const Streams<double>& out,
                Matrix<double>& r) const override {
    r = out.stream(layout.op(0)).col(0) +
        out.stream(0).col(1).cwiseProduct(out.stream(layout.tangent(0)).col(0));
  }
  void backward(Eigen::Index, const StreamLayout& layout, const Streams<double>& out,
                const Matrix<double>& r_bar, Streams<double>& adjoint) const override {
    adjoint.stream(layout.op(0)).col(0) += r_bar.col(0);
    adjoint.stream(0).col(1) += r_bar.col(0).cwiseProduct(out.stream(layout.tangent(0)).col(0));
    adjoint.stream(layout.tangent(0)).col(0) += r_bar.col(0).cwiseProduct(out.stream(0).col(1));
  }
};

TEST_P(HashGridInNetwork, JacobianRowsArePerPointGradients) {
  std::mt19937_64 rng(44);
  Network n = make_network(GetParam(), 5);
  const Eigen::MatrixXd x = points_off_faces(n, 5, rng);
  const StreamLayout layout(StreamSpec::laplacian(2));
  const Residual residual;
  const Eigen::Index p = n.net.parameter_count();
  Eigen::VectorXd r(x.rows());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian =
      Eigen::MatrixXd::Constant(x.rows(), p, std::nan(""));
  n.net.residuals_and_jacobian(n.theta.data(), layout, x, residual, r.data(), jacobian.data());
  ASSERT_TRUE(jacobian.allFinite());
  for (Eigen::Index point = 0; point < x.rows(); ++point) {
    const LambdaLoss<double> loss([&](Eigen::Index first, const StreamLayout& l,
                                      const Streams<double>& out, Streams<double>& adjoint) {
      Matrix<double> value;
      residual.evaluate(first, l, out, value);
      residual.backward(first, l, out, Matrix<double>::Ones(1, 1), adjoint);
      return value(0, 0);
    });
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
    const double value = n.net.value_and_gradient(n.theta.data(), layout, x.row(point), loss, g.data());
    EXPECT_NEAR(value, r[point], 1e-12 * std::abs(r[point]));
    EXPECT_LE((jacobian.row(point).transpose() - g).cwiseAbs().maxCoeff(),
              1e-12 * g.cwiseAbs().maxCoeff())
        << GetParam() << " point " << point;
  }
  // Blocks of other sizes and two threads write the same rows.
  n.net.set_options({.block_points = 3, .threads = 2});
  Eigen::VectorXd r2(x.rows());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> j2(x.rows(), p);
  n.net.residuals_and_jacobian(n.theta.data(), layout, x, residual, r2.data(), j2.data());
  EXPECT_LE((j2 - jacobian).cwiseAbs().maxCoeff(), 1e-13 * jacobian.cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(Interpolations, HashGridInNetwork,
                         ::testing::Values("linear", "smoothstep", "cubic"));

// ---------------------------------------------------------------------------------------
// Field, checkpoint and config.

FieldOptions hash_field() {
  FieldOptions o;
  o.type = "mlp";
  o.activation = "softplus";
  o.hidden = {8};
  o.encoding = grid("smoothstep", 4, 10, 4, 40, 2, -1, 1);
  hg(o.encoding).include_input = true;
  hg(o.encoding).init_scale = 0.25;
  return o;
}

TEST(HashGridField, TablesComeFirstAndDrawTheirOwnInitialization) {
  const Field<double> a(hash_field());
  const Eigen::Index tables = a.network().modules()[0]->parameter_count();
  ASSERT_GT(tables, 0);
  const Eigen::VectorXd t = a.parameters().head(tables);
  EXPECT_LE(t.cwiseAbs().maxCoeff(), 0.25);
  EXPECT_GE(t.cwiseAbs().maxCoeff(), 0.24);
  const Field<double> b(hash_field());
  EXPECT_EQ(a.parameters(), b.parameters());
  // The dense layer after the tables still draws Xavier-uniform weights.
  const Eigen::Index in = 2 + 4 * 2;
  const Eigen::VectorXd w = a.parameters().segment(tables, 8 * in);
  EXPECT_LE(w.cwiseAbs().maxCoeff(), std::sqrt(6.0 / (in + 8)));
}

TEST(HashGridField, SaveLoadRoundTripIsBitExact) {
  const auto dir = testutil::scratch_dir("hash_grid");
  for (const char* precision : {"float", "double"}) {
    const auto path = dir / (std::string(precision) + ".h5");
    auto round_trip = [&]<typename Scalar>(Field<Scalar> field) {
      field.parameters().setRandom();
      {
        io::H5Writer file(path);
        save_field(file, field);
        file.commit();
      }
      const io::H5Reader file(path);
      const FieldOptions o = load_field_options(file);
      EXPECT_EQ(o.encoding.type, "hash_grid");
      EXPECT_EQ(hg(o.encoding).levels, 4);
      EXPECT_EQ(hg(o.encoding).log2_table_size, 10);
      EXPECT_EQ(hg(o.encoding).base_resolution, 4);
      EXPECT_EQ(hg(o.encoding).finest_resolution, 40);
      EXPECT_EQ(hg(o.encoding).interpolation, "smoothstep");
      EXPECT_EQ(hg(o.encoding).init_scale, 0.25);
      EXPECT_TRUE(hg(o.encoding).include_input);
      EXPECT_EQ(o.encoding.lower, (std::vector<double>{-1, -1}));
      EXPECT_EQ(o.encoding.upper, (std::vector<double>{1, 1}));
      const Field<Scalar> loaded = load_field<Scalar>(file);
      ASSERT_EQ(loaded.parameter_count(), field.parameter_count());
      EXPECT_EQ(std::memcmp(loaded.parameters().data(), field.parameters().data(),
                            sizeof(Scalar) * field.parameter_count()), 0);
      EXPECT_EQ(file.shape("field/encoding_parameters")[0],
                static_cast<std::uint64_t>(field.network().modules()[0]->parameter_count()));
      EXPECT_EQ(file.shape("field/layers/0/weight")[1], 10u);  // x and 4 levels × 2 features
      const Matrix<Scalar> x = Matrix<Scalar>::Random(9, 2);
      EXPECT_EQ(loaded.values(x), field.values(x));
    };
    if (std::string(precision) == "float")
      round_trip(Field<float>(hash_field()));
    else
      round_trip(Field<double>(hash_field()));
  }
}

constexpr const char* kConfig =
    "field:\n"                                 // 1
    "  type: mlp\n"                            // 2
    "  hidden: [16]\n"                         // 3
    "  encoding:\n"                            // 4
    "    type: Hash_Grid\n"                    // 5
    "    levels: 6\n"                          // 6
    "    features_per_level: 4\n"              // 7
    "    log2_table_size: 12\n"                // 8
    "    base_resolution: 8\n"                 // 9
    "    finest_resolution: 64\n"              // 10
    "    interpolation: smoothstep\n"          // 11
    "    include_input: false\n"               // 12
    "    init_scale: 0.01\n";                  // 13

FieldOptions read(const std::string& text) {
  const io::ConfigNode root = io::parse_config(text, "hash.yaml");
  FieldOptions o = field_options_from_config(root.child("field"), 2, 1, 7);
  root.reject_unknown_keys_recursive();
  return o;
}

TEST(HashGridConfig, KeysAreReadAndWrittenBack) {
  const FieldOptions o = read(kConfig);
  EXPECT_EQ(o.encoding.type, "hash_grid");
  EXPECT_EQ(hg(o.encoding).levels, 6);
  EXPECT_EQ(hg(o.encoding).features_per_level, 4);
  EXPECT_EQ(hg(o.encoding).log2_table_size, 12);
  EXPECT_EQ(hg(o.encoding).base_resolution, 8);
  EXPECT_EQ(hg(o.encoding).finest_resolution, 64);
  EXPECT_EQ(hg(o.encoding).interpolation, "smoothstep");
  EXPECT_FALSE(hg(o.encoding).include_input);
  EXPECT_EQ(hg(o.encoding).init_scale, 0.01);
  YAML::Node root;
  root["field"] = to_yaml(o);
  const FieldOptions again = read(io::to_yaml(root));
  EXPECT_EQ(io::to_yaml(root["field"]), io::to_yaml(to_yaml(again)));
  // Defaults.
  const FieldOptions d = read("field: {type: mlp, encoding: {type: hash_grid}}\n");
  EXPECT_EQ(hg(d.encoding).levels, 16);
  EXPECT_EQ(hg(d.encoding).log2_table_size, 19);
  EXPECT_EQ(hg(d.encoding).interpolation, "linear");
  EXPECT_TRUE(hg(d.encoding).include_input);
}

void expect_error(const std::string& text, int line, const std::string& key,
                  const std::string& part) {
  try {
    read(text);
    ADD_FAILURE() << "no error for " << key;
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.file(), "hash.yaml");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.key_path(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

std::string edited(const std::string& from, const std::string& to) {
  std::string text = kConfig;
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(HashGridConfig, BadValuesNameFileLineAndKey) {
  expect_error(edited("interpolation: smoothstep", "interpolation: quintic"), 11,
               "field.encoding.interpolation", "linear, smoothstep, cubic");
  expect_error(edited("log2_table_size: 12", "log2_table_size: 25"), 8,
               "field.encoding.log2_table_size", "10");
  expect_error(edited("log2_table_size: 12", "log2_table_size: 9"), 8,
               "field.encoding.log2_table_size", "24");
  expect_error(edited("finest_resolution: 64", "finest_resolution: 4"), 10,
               "field.encoding.finest_resolution", "base_resolution = 8");
  expect_error(edited("init_scale: 0.01", "init_scale: 0"), 13, "field.encoding.init_scale", "> 0");
  expect_error(edited("levels: 6", "level: 6"), 6, "field.encoding.level", "unknown key 'level'");
}

TEST(HashGridOptions, ValidationNamesTheOptionAndTheRule) {
  EncodingOptions o;
  o.type = "hash_grid";
  auto message = [&] {
    try {
      o.validate(2);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  hg(o).log2_table_size = 30;
  EXPECT_NE(message().find("encoding.log2_table_size = 30: must be in [10, 24]"), std::string::npos);
  o = {};
  o.type = "hash_grid";
  hg(o).interpolation = "quintic";
  EXPECT_NE(message().find("encoding.interpolation = 'quintic': must be linear, smoothstep or cubic"),
            std::string::npos) << message();
  o = {};
  o.type = "hash_grid";
  o.lower = {0, 0};
  o.upper = {1, 0};
  EXPECT_NE(message().find("encoding.lower[1]"), std::string::npos) << message();
  o.upper = {1};
  EXPECT_NE(message().find("one per input"), std::string::npos) << message();
  o = {};
  o.type = "hash_grid";
  FieldOptions f;
  f.input_dim = 4;
  f.encoding = o;
  EXPECT_NO_THROW(f.validate());
}

}  // namespace
}  // namespace nfield::fields
