// SPDX-License-Identifier: MIT
//
// Field construction and initialization (the SIREN reference network of Sitzmann et al.,
// mlp initializations, seeds), casts between scalar types, and float streams against double
// streams.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fields/cusp_encoding.h"
#include "fields/field.h"
#include "fields/fourier_encoding.h"
#include "fields/positional_encoding.h"
#include "tests/testing/squares_loss.h"
#include "tests/testing/stream_checks.h"

namespace nfield::fields {
namespace {

using testutil::random_matrix;
using testutil::relative_error;
using testutil::WorstErrors;

struct DenseSlice {
  Eigen::Index in, out, offset;
};

template <typename Scalar>
std::vector<DenseSlice> dense_slices(const Field<Scalar>& f) {
  std::vector<DenseSlice> out;
  const auto& modules = f.network().modules();
  for (size_t m = 0; m < modules.size(); ++m)
    if (modules[m]->parameter_count() > 0)
      out.push_back({modules[m]->input_width(), modules[m]->output_width(),
                     f.network().parameter_offset(m)});
  return out;
}

TEST(FieldInitialization, SirenReferenceNetwork) {
  const FieldOptions o;  // the defaults are the reference network: 2 → 256 ×4 → 1, ω₀ = 30
  ASSERT_EQ(o.type, "siren");
  ASSERT_EQ(o.input_dim, 2);
  ASSERT_EQ(o.hidden, (std::vector<int>{256, 256, 256, 256}));
  const Field<double> f(o);
  EXPECT_EQ(f.parameter_count(), 198401);
  EXPECT_EQ(f.parameters().size(), 198401);

  const std::vector<DenseSlice> slices = dense_slices(f);
  ASSERT_EQ(slices.size(), 5u);
  for (size_t l = 0; l < slices.size(); ++l) {
    const auto [in, out, offset] = slices[l];
    const Eigen::VectorXd w = f.parameters().segment(offset, in * out);
    const Eigen::VectorXd b = f.parameters().segment(offset + in * out, out);
    const double bound = l == 0 ? 0.5 : std::sqrt(6.0 / 256) / 30;
    EXPECT_EQ(in, l == 0 ? 2 : 256);
    EXPECT_LE(w.cwiseAbs().maxCoeff(), bound) << "layer " << l;
    // Uniform draws fill the interval: the extremes come close to the bound.
    EXPECT_GE(w.maxCoeff(), 0.9 * bound) << "layer " << l;
    EXPECT_LE(w.minCoeff(), -0.9 * bound) << "layer " << l;
    EXPECT_LE(std::abs(w.mean()), 0.1 * bound) << "layer " << l;
    const double bias_bound = 1 / std::sqrt(static_cast<double>(in));
    EXPECT_LE(b.cwiseAbs().maxCoeff(), bias_bound) << "layer " << l;
    EXPECT_GT(b.cwiseAbs().maxCoeff(), 0) << "layer " << l;
  }
}

TEST(FieldInitialization, SameSeedSameParameters) {
  FieldOptions o;
  o.hidden = {32, 32};
  Field<double> a(o), b(o);
  EXPECT_EQ(a.parameters(), b.parameters());
  const Eigen::VectorXd first = a.parameters();
  a.parameters().setZero();
  a.initialize();
  EXPECT_EQ(a.parameters(), first);
  o.seed = 1;
  const Field<double> c(o);
  EXPECT_NE(c.parameters(), first);
  // float draws the same numbers, rounded.
  o.seed = 0;
  const Field<float> f(o);
  EXPECT_EQ(f.parameters(), first.cast<float>());
}

TEST(FieldInitialization, MlpBoundsAndZeroBiases) {
  for (const char* activation : {"relu", "tanh", "softplus", "sine", "identity"}) {
    FieldOptions o;
    o.type = "mlp";
    o.activation = activation;
    o.input_dim = 3;
    o.hidden = {64, 32};
    o.output_dim = 2;
    const Field<double> f(o);
    for (const auto& [in, out, offset] : dense_slices(f)) {
      const Eigen::VectorXd w = f.parameters().segment(offset, in * out);
      const double bound = std::string(activation) == "relu" ? std::sqrt(6.0 / in)
                                                             : std::sqrt(6.0 / (in + out));
      EXPECT_LE(w.cwiseAbs().maxCoeff(), bound) << activation;
      EXPECT_GE(w.cwiseAbs().maxCoeff(), 0.7 * bound) << activation;
      EXPECT_TRUE(f.parameters().segment(offset + in * out, out).isZero(0)) << activation;
    }
  }
}

TEST(FieldCast, FloatToDoubleMatches) {
  FieldOptions o;
  o.hidden = {16, 16};
  o.output_dim = 2;
  o.encoding = encoding_options(FourierOptions{.features = 6, .scale = 1.0});
  const Field<float> f(o, {.block_points = 5, .threads = 1});
  const Field<double> d = f.cast<double>();
  EXPECT_EQ(d.parameters(), f.parameters().cast<double>());
  EXPECT_EQ(d.encoding_matrix(), f.encoding_matrix());
  EXPECT_EQ(d.options().hidden, o.hidden);
  EXPECT_EQ(d.options().encoding.type, "fourier");
  EXPECT_EQ(d.network().options().block_points, 5);
  EXPECT_EQ(d.parameter_count(), f.parameter_count());

  std::mt19937_64 rng(3);
  const Eigen::MatrixXf xf = random_matrix(20, 2, rng).cast<float>();
  const Eigen::MatrixXd vd = d.values(xf.cast<double>());
  const Eigen::MatrixXd vf = f.values(xf).cast<double>();
  EXPECT_LE(relative_error(vf, vd, 0), 1e-5);

  // And back: double → float rounds each parameter.
  const Field<float> back = d.cast<float>();
  EXPECT_EQ(back.parameters(), f.parameters());
}

// Cusp features with `from_stage: 2`: their first-layer weights start at zero (the other
// parameters as drawn without from_stage); before stage 2 they are switched off, so those
// weights get exactly zero gradients and do not change the field's values; from stage 2 on
// they are trained like any other weight.
TEST(LateCuspFeatures, ZeroWeightsAndNoGradientBeforeTheirStage) {
  FieldOptions o;
  o.type = "mlp";
  o.activation = "tanh";
  o.hidden = {6, 5};
  o.encoding = encoding_options(CuspOptions{.axis = 1, .at = {0.5}});
  const Field<double> from_start(o);
  o.encoding = encoding_options(CuspOptions{.axis = 1, .at = {0.5}, .from_stage = 2});
  Field<double> f(o);
  const DenseSlice first = dense_slices(f).at(0);
  ASSERT_EQ(first.in, 3);  // x, y, |y − 0.5|
  // W is out × in column-major: the cusp column is the last `out` entries of the weights.
  const Eigen::Index cusp_begin = first.offset + 2 * first.out, cusp_end = first.offset + 3 * first.out;
  for (Eigen::Index i = 0; i < f.parameter_count(); ++i) {
    if (i >= cusp_begin && i < cusp_end)
      EXPECT_EQ(f.parameters()(i), 0) << i;
    else
      EXPECT_EQ(f.parameters()(i), from_start.parameters()(i)) << i;
  }

  std::mt19937_64 rng(4);
  const Eigen::MatrixXd x = random_matrix(30, 2, rng);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  auto gradient_of = [&](const Field<double>& field) {
    autodiff::Streams<double> out;
    field.evaluate(layout, x, out);
    const testutil::SquaresLoss<double> loss(testutil::SquaresLoss<double>::balanced_weights(out));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(field.parameter_count());
    field.network().value_and_gradient(field.parameters().data(), layout, x, loss, g.data());
    return g;
  };
  // Nonzero cusp weights, so that a switched-on feature would show in values and gradients.
  for (Eigen::Index i = cusp_begin; i < cusp_end; ++i) f.parameters()(i) = 0.3;
  Field<double> without = Field<double>(o);  // the same weights with the cusp column at zero
  without.parameters() = f.parameters();
  without.parameters().segment(cusp_begin, cusp_end - cusp_begin).setZero();
  for (const int stage : {0, 1}) {
    f.begin_stage(stage);
    EXPECT_EQ(f.values(x), without.values(x)) << "stage " << stage;
    const Eigen::VectorXd g = gradient_of(f);
    EXPECT_EQ(g.segment(cusp_begin, cusp_end - cusp_begin).norm(), 0) << "stage " << stage;
    EXPECT_GT(g.head(cusp_begin).norm(), 0);
  }
  f.begin_stage(2);
  EXPECT_GT((f.values(x) - without.values(x)).norm(), 1e-3);
  EXPECT_GT(gradient_of(f).segment(cusp_begin, cusp_end - cusp_begin).norm(), 0);
  f.begin_stage(0);
  const Eigen::MatrixXd off = f.values(x);
  f.begin_stage(5);
  EXPECT_NE(f.values(x), off);
}

// A SIREN with hidden [64, 64] (ω₀ = 30) in float against the same parameters in double:
// every stream within float rounding, relative to its own scale.
// encoding.normalize scales octave l of the positional encoding by 2⁻ˡ: the same field as
// the plain encoding with the first layer's weights on those features divided by 2ˡ, in
// every stream (value, tangents, Laplacian).
TEST(NormalizedPositionalEncoding, ScalesOctaveLByTwoToTheMinusL) {
  FieldOptions o;
  o.type = "mlp";
  o.activation = "tanh";
  o.input_dim = 2;
  o.hidden = {6};
  const int frequencies = 4;
  o.encoding = encoding_options(PositionalOptions{.frequencies = frequencies});
  const Field<double> plain(o);
  o.encoding = encoding_options(PositionalOptions{.frequencies = frequencies, .normalize = true});
  Field<double> normalized(o);
  normalized.parameters() = plain.parameters();
  const DenseSlice first = dense_slices(plain).front();
  const int d = o.input_dim, m = frequencies * d;
  ASSERT_EQ(first.in, d + 2 * m);
  Eigen::Map<Eigen::MatrixXd> w(normalized.parameters().data() + first.offset, first.out, first.in);
  for (int l = 0; l < frequencies; ++l)
    for (int i = 0; i < d; ++i)
      for (int phase = 0; phase < 2; ++phase) w.col(d + phase * m + l * d + i) *= std::ldexp(1.0, l);
  std::mt19937_64 rng(3);
  const Eigen::MatrixXd x = random_matrix(5, d, rng);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(d));
  autodiff::Streams<double> a, b;
  plain.evaluate(layout, x, a);
  normalized.evaluate(layout, x, b);
  EXPECT_LT(relative_error(b.data, a.data, 1e-12), 1e-13);
  // Without the compensation the high octaves are damped: the fields differ.
  Field<double> damped(o);
  damped.parameters() = plain.parameters();
  damped.evaluate(layout, x, b);
  EXPECT_GT(relative_error(b.data, a.data, 1e-12), 1e-3);
}

TEST(FloatStreams, MatchDoubleWithinFloatRounding) {
  for (int dim = 2; dim <= 3; ++dim) {
    FieldOptions o;
    o.input_dim = dim;
    o.output_dim = dim - 1;
    o.hidden = {64, 64};
    o.seed = 10 + dim;
    const Field<float> ff(o, {.block_points = 16, .threads = 1});
    const Field<double> fd = ff.cast<double>();
    std::mt19937_64 rng(dim);
    const Eigen::MatrixXf xf = random_matrix(50, dim, rng).cast<float>();
    const Eigen::MatrixXd xd = xf.cast<double>();
    for (const testutil::NamedSpec& named :
         {testutil::NamedSpec{"axes", testutil::axes_spec(dim, rng, 4)},
          testutil::NamedSpec{"directions", testutil::directions_spec(dim, rng)}}) {
      const autodiff::StreamLayout layout(named.spec);
      autodiff::Streams<float> sf;
      autodiff::Streams<double> sd;
      ff.evaluate(layout, xf, sf);
      fd.evaluate(layout, xd, sd);
      for (int s = 0; s < layout.count(); ++s) {
        const double err =
            relative_error(sf.stream(s).cast<double>(), sd.stream(s), 0);
        const std::string where = "d=" + std::to_string(dim) + " " + named.name + ": " +
                                  testutil::stream_name(layout, s);
        WorstErrors::get().record("float vs double: " + testutil::stream_kind(layout, s), err,
                                  where);
        EXPECT_LE(err, 1e-4) << where;
      }

      // The parameter gradient of a loss of all streams, likewise.
      const testutil::SquaresLoss<double> loss_d(testutil::SquaresLoss<double>::balanced_weights(sd));
      const testutil::SquaresLoss<float> loss_f(testutil::SquaresLoss<double>::balanced_weights(sd));
      Eigen::VectorXd gd = Eigen::VectorXd::Zero(fd.parameter_count());
      Eigen::VectorXf gf = Eigen::VectorXf::Zero(ff.parameter_count());
      const double ld = fd.network().value_and_gradient(fd.parameters().data(), layout, xd, loss_d,
                                                        gd.data());
      const double lf = ff.network().value_and_gradient(ff.parameters().data(), layout, xf, loss_f,
                                                        gf.data());
      const double err_g = (gf.cast<double>() - gd).cwiseAbs().maxCoeff() / gd.cwiseAbs().maxCoeff();
      WorstErrors::get().record("float vs double: loss", std::abs(lf - ld) / ld, named.name);
      WorstErrors::get().record("float vs double: gradient", err_g, named.name);
      EXPECT_LE(std::abs(lf - ld) / ld, 1e-4) << named.name;
      EXPECT_LE(err_g, 1e-3) << named.name;
    }
  }
}

}  // namespace
}  // namespace nfield::fields
