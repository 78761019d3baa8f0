// SPDX-License-Identifier: MIT
//
// The integrated positional encoding (fields/integrated_positional.h) beyond the
// registered-network harness (tests/autodiff/stream_rules_test.cc and
// parameter_gradient_test.cc run it on every stream kind, against nested jets and central
// differences, at L = 3):
//   * at σ² = 0 it is the positional encoding bit for bit: the module's streams, and a nerf
//     field's values against the same field with `positional` (same seed, same weights), in
//     float and double;
//   * its features are sin/cos(ω μ)·e^{−ω²σ²/2} with ω = 2ˡπ, at L = 10 (the config's);
//   * its gradient along the means and along the variances matches central differences at
//     L = 10 with variances of a sample's size;
//   * a nerf field with it takes [x, d, σ²], and its density ignores d.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "autodiff/streams.h"
#include "fields/encoding_type.h"
#include "fields/field.h"
#include "fields/integrated_positional.h"
#include "fields/positional_encoding.h"
#include "fields/radiance_network.h"
#include "tests/testing/encoding_options.h"

namespace nfield::fields {
namespace {

using autodiff::Matrix;
using autodiff::StreamLayout;
using autodiff::StreamSpec;
using autodiff::Streams;

template <typename Scalar>
Matrix<Scalar> module_streams(const autodiff::Module<Scalar>& module, const StreamLayout& layout,
                              const Matrix<Scalar>& x) {
  Streams<Scalar> in, out;
  autodiff::seed_input_streams<Scalar>(layout, x, in);
  module.forward(layout, nullptr, in, out, nullptr);
  return out.data;
}

Eigen::MatrixXd uniform(Eigen::Index rows, Eigen::Index cols, double lo, double hi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i)
    m.data()[i] = lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return m;
}

template <typename Scalar>
void expect_positional_at_zero_variance() {
  const int k = 3, frequencies = 10;
  const EncodingOptions positional = encoding_options(PositionalOptions{.frequencies = frequencies});
  const EncodingOptions integrated =
      encoding_options(IntegratedPositionalOptions{.frequencies = frequencies});
  const auto plain = make_encoding<Scalar>(positional, k);
  const auto ipe = make_encoding<Scalar>(integrated, 2 * k);
  ASSERT_EQ(ipe->input_width(), 2 * k);
  ASSERT_EQ(ipe->output_width(), plain->output_width());
  Matrix<Scalar> mu = uniform(40, k, -1.5, 1.5, 11).cast<Scalar>();
  Matrix<Scalar> x(mu.rows(), 2 * k);
  x << mu, Matrix<Scalar>::Zero(mu.rows(), k);
  // Values, and the gradient along the means (the tangents along the variances have no
  // positional counterpart).
  StreamSpec plain_spec = StreamSpec::gradient(k);
  StreamSpec ipe_spec = StreamSpec::values(2 * k);
  ipe_spec.tangents = Eigen::MatrixXd::Identity(2 * k, k);
  const Matrix<Scalar> a = module_streams<Scalar>(*plain, StreamLayout(plain_spec), mu);
  const Matrix<Scalar> b = module_streams<Scalar>(*ipe, StreamLayout(ipe_spec), x);
  ASSERT_EQ(a.rows(), b.rows());
  EXPECT_TRUE(a == b) << "largest difference " << (a - b).cwiseAbs().maxCoeff();
}

TEST(IntegratedPositional, IsThePositionalEncodingAtZeroVariance) {
  expect_positional_at_zero_variance<float>();
  expect_positional_at_zero_variance<double>();
}

FieldOptions nerf_options(const std::string& encoding) {
  FieldOptions o;
  o.type = "nerf";
  o.activation = "relu";
  o.input_dim = kRadianceInputs + (encoding == "integrated_positional" ? 3 : 0);
  o.output_dim = kRadianceOutputs;
  o.hidden = {32, 32};
  o.color_hidden = {16};
  o.encoding = testutil::encoding_of(encoding, {.frequencies = 10});
  o.seed = 9;
  return o;
}

template <typename Scalar>
void expect_same_nerf_at_zero_variance() {
  const Field<Scalar> plain(nerf_options("positional"));
  const Field<Scalar> ipe(nerf_options("integrated_positional"));
  ASSERT_EQ(plain.parameter_count(), ipe.parameter_count());
  EXPECT_TRUE(plain.parameters() == ipe.parameters());  // same shapes, same draws
  Matrix<Scalar> x = uniform(64, 6, -0.6, 0.6, 3).cast<Scalar>();
  for (Eigen::Index i = 0; i < x.rows(); ++i) x.row(i).tail(3).normalize();
  Matrix<Scalar> with_variances(x.rows(), 9);
  with_variances << x, Matrix<Scalar>::Zero(x.rows(), 3);
  const Matrix<Scalar> a = plain.values(x), b = ipe.values(with_variances);
  EXPECT_TRUE(a == b) << "largest difference " << (a - b).cwiseAbs().maxCoeff();
  // With variances the fine octaves fade: the field changes.
  with_variances.rightCols(3).setConstant(Scalar(1e-4));
  EXPECT_GT((ipe.values(with_variances) - a).cwiseAbs().maxCoeff(), Scalar(1e-4));
}

TEST(IntegratedPositional, NerfFieldIsThePositionalOneAtZeroVariance) {
  expect_same_nerf_at_zero_variance<float>();
  expect_same_nerf_at_zero_variance<double>();
}

TEST(IntegratedPositional, FeaturesAreExpectedSinusoids) {
  const int k = 3, frequencies = 10;
  const IntegratedPositionalEncoding<double> ipe(k, frequencies, true);
  Eigen::MatrixXd x(5, 2 * k);
  x << uniform(5, k, -0.6, 0.6, 5), uniform(5, k, 0.0, 1e-4, 6);
  const Eigen::MatrixXd y = module_streams<double>(ipe, StreamLayout(StreamSpec::values(2 * k)), x);
  ASSERT_EQ(y.cols(), k + 2 * frequencies * k);
  const int m = frequencies * k;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    for (int i = 0; i < k; ++i) EXPECT_EQ(y(p, i), x(p, i));
    for (int l = 0; l < frequencies; ++l)
      for (int i = 0; i < k; ++i) {
        const double omega = std::ldexp(std::numbers::pi, l);
        const double damping = std::exp(-0.5 * omega * omega * x(p, k + i));
        EXPECT_NEAR(y(p, k + l * k + i), std::sin(omega * x(p, i)) * damping, 1e-14);
        EXPECT_NEAR(y(p, k + m + l * k + i), std::cos(omega * x(p, i)) * damping, 1e-14);
      }
  }
}

// ∂γ/∂μ and ∂γ/∂σ² (tangent streams along every input axis) against central differences
// (step 1e-6 on the means and 1e-9 on the variances, whose scale is 1e-5), at L = 10.
TEST(IntegratedPositional, GradientMatchesCentralDifferences) {
  const int k = 3, frequencies = 10;
  const IntegratedPositionalEncoding<double> ipe(k, frequencies, false);
  Eigen::MatrixXd x(7, 2 * k);
  x << uniform(7, k, -0.6, 0.6, 7), uniform(7, k, 0.0, 2e-5, 8);
  const StreamLayout layout(StreamSpec::gradient(2 * k));
  const StreamLayout values(StreamSpec::values(2 * k));
  const Eigen::MatrixXd streams = module_streams<double>(ipe, layout, x);
  const Eigen::Index n = x.rows();
  for (int j = 0; j < 2 * k; ++j) {
    const double h = j < k ? 1e-6 : 1e-9;
    Eigen::MatrixXd plus = x, minus = x;
    plus.col(j).array() += h;
    minus.col(j).array() -= h;
    const Eigen::MatrixXd fd =
        (module_streams<double>(ipe, values, plus) - module_streams<double>(ipe, values, minus)) / (2 * h);
    const Eigen::MatrixXd tangent = streams.middleRows(layout.tangent(j) * n, n);
    // Features of octave l change at rate up to 2ˡπ along μ and 4ˡπ²/2 along σ².
    const double scale = std::max(1.0, fd.cwiseAbs().maxCoeff());
    EXPECT_LE((tangent - fd).cwiseAbs().maxCoeff() / scale, 1e-5) << "input " << j;
  }
}

TEST(IntegratedPositional, RegisteredAndReadsVariances) {
  EncodingOptions o;
  o.type = "Integrated_Positional";  // names are case-insensitive
  EXPECT_TRUE(reads_variances(o));
  o.type = "positional";
  EXPECT_FALSE(reads_variances(o));
  o.type = "integrated_positional";
  EXPECT_THROW(o.validate(3), std::invalid_argument);  // an odd input: no [μ, σ²] split
  o = encoding_options(IntegratedPositionalOptions{.frequencies = 25});
  EXPECT_THROW(o.validate(), std::invalid_argument);
  FieldOptions nerf = nerf_options("integrated_positional");
  nerf.input_dim = 6;  // a nerf field with it takes [x, d, σ²]
  EXPECT_THROW(nerf.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::fields
