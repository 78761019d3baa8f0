// SPDX-License-Identifier: MIT
//
// The nerf field type (fields/radiance_network.h): the density output does not depend on
// the view direction, the colour does; parameter gradients through the carried columns
// (autodiff::OnColumns) match central differences; per-point Jacobian rows (what
// Levenberg–Marquardt reads) sum to the gradient; checkpoints round-trip bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <random>

#include "autodiff/on_columns.h"
#include "fields/dense.h"
#include "fields/field_io.h"
#include "fields/radiance_network.h"
#include "tests/testing/encoding_options.h"
#include "tests/testing/squares_loss.h"
#include "tests/testing/scratch.h"

namespace nfield::fields {
namespace {

FieldOptions small_nerf(const std::string& encoding = "positional") {
  FieldOptions o;
  o.type = "nerf";
  o.activation = "softplus";  // smooth, so central differences converge
  o.input_dim = kRadianceInputs;
  o.output_dim = kRadianceOutputs;
  o.hidden = {12, 10};
  o.color_hidden = {7};
  o.direction_frequencies = 2;
  o.encoding = testutil::encoding_of(encoding, {.frequencies = 3});
  o.seed = 4;
  return o;
}

Eigen::MatrixXd samples(Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd x(n, 6);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53 - 0.5;
  for (Eigen::Index i = 0; i < n; ++i) x.row(i).tail(3).normalize();
  return x;
}

// A squares loss of the field's four outputs at x (balanced by their values at the current
// parameters), its value at any parameters and its gradient at the current ones.
class ValuesLoss {
 public:
  ValuesLoss(Field<double>& field, Eigen::MatrixXd x) : field_(field), x_(std::move(x)) {
    field_.set_evaluation({5, 2});
    field_.evaluate(layout_, x_, out_);
    loss_ = std::make_unique<testutil::SquaresLoss<double>>(testutil::SquaresLoss<double>::balanced_weights(out_));
  }
  double at(const Eigen::VectorXd& theta) {
    const Eigen::VectorXd kept = field_.parameters();
    field_.parameters() = theta;
    field_.evaluate(layout_, x_, out_);
    field_.parameters() = kept;
    return loss_->value(out_);
  }
  Eigen::VectorXd gradient() {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(field_.parameter_count());
    field_.value_and_gradient(field_.parameters().data(), layout_, autodiff::Batch<double>{x_}, *loss_, g.data());
    return g;
  }

 private:
  Field<double>& field_;
  Eigen::MatrixXd x_;
  autodiff::StreamLayout layout_{autodiff::StreamSpec::values(6)};
  autodiff::Streams<double> out_;
  std::unique_ptr<testutil::SquaresLoss<double>> loss_;
};

TEST(RadianceField, DensityIgnoresTheDirectionAndColourDoesNot) {
  const Field<double> field(small_nerf());
  Eigen::MatrixXd x = samples(20, 1);
  const Eigen::MatrixXd a = field.values(x);
  x.rightCols(3) = samples(20, 2).rightCols(3);
  const Eigen::MatrixXd b = field.values(x);
  ASSERT_EQ(a.cols(), 4);
  EXPECT_EQ(a.col(0), b.col(0));  // bit for bit: d never reaches the density
  EXPECT_GT((a.rightCols(3) - b.rightCols(3)).norm(), 1e-6);
}

TEST(RadianceField, ParameterGradientMatchesCentralDifferences) {
  for (const std::string encoding : {"identity", "positional", "fourier"}) {
    Field<double> field(small_nerf(encoding));
    ValuesLoss loss(field, samples(23, 3));
    const Eigen::VectorXd g = loss.gradient();
    std::mt19937_64 rng(9);
    Eigen::VectorXd u(g.size());
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53 - 0.5;
    const Eigen::VectorXd theta = field.parameters();
    const double h = 1e-5, fd = (loss.at(theta + h * u) - loss.at(theta - h * u)) / (2 * h);
    EXPECT_NEAR(g.dot(u), fd, 1e-6 * (1 + std::abs(fd))) << encoding;
  }
}

// r(x) = the four outputs: the rows of the per-point Jacobian of output c, summed over points,
// are the gradient of Σₙ out_c(xₙ).
class OutputResidual final : public autodiff::StreamResidual<double> {
 public:
  int components() const override { return 4; }
  void evaluate(Eigen::Index, const autodiff::StreamLayout&, const autodiff::Streams<double>& out,
                autodiff::Matrix<double>& r) const override {
    r = out.stream(0);
  }
  void backward(Eigen::Index, const autodiff::StreamLayout&, const autodiff::Streams<double>&,
                const autodiff::Matrix<double>& r_bar, autodiff::Streams<double>& adjoint) const override {
    adjoint.stream(0) += r_bar;
  }
};

// An appearance code (FieldOptions::latent_size) joins the colour layers: it moves the colour
// and never the density, its gradient matches central differences, and the field finds its
// slot behind the carried columns (autodiff::OnColumns).
TEST(RadianceField, AppearanceCodeMovesTheColourOnly) {
  FieldOptions o = small_nerf();
  o.latent_size = 3;
  Field<double> field(o);
  ASSERT_GE(field.latent_offset(), 0);
  EXPECT_EQ(field.parameter_count(), Field<double>(small_nerf()).parameter_count() + 3 + 3 * 7);  // z and its weights
  const Eigen::MatrixXd x = samples(20, 6);
  const Eigen::MatrixXd a = field.values(x);
  field.parameters().segment(field.latent_offset(), 3) << 0.7, -0.4, 0.2;
  const Eigen::MatrixXd b = field.values(x);
  EXPECT_EQ(a.col(0), b.col(0));  // bit for bit
  EXPECT_GT((a.rightCols(3) - b.rightCols(3)).norm(), 1e-3);

  ValuesLoss loss(field, x);
  const Eigen::VectorXd g = loss.gradient(), theta = field.parameters();
  for (int j = 0; j < 3; ++j) {
    Eigen::VectorXd step = Eigen::VectorXd::Zero(theta.size());
    step[field.latent_offset() + j] = 1e-5;
    const double fd = (loss.at(theta + step) - loss.at(theta - step)) / 2e-5;
    EXPECT_NEAR(g[field.latent_offset() + j], fd, 1e-7 * (1 + std::abs(fd))) << "code " << j;
  }
}

TEST(RadianceField, PerPointJacobianRowsSumToTheGradient) {
  Field<double> field(small_nerf());
  const Eigen::MatrixXd x = samples(9, 5);
  const autodiff::StreamLayout layout(autodiff::StreamSpec::values(6));
  const Eigen::Index p = field.parameter_count();
  Eigen::VectorXd r(9 * 4);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian(9 * 4, p);
  const OutputResidual residual;
  field.residuals_and_jacobian(field.parameters().data(), layout, autodiff::Batch<double>{x}, residual,
                               r.data(), jacobian.data());
  for (int c = 0; c < 4; ++c) {
    autodiff::LambdaLoss<double> sum_c([c](Eigen::Index, const autodiff::StreamLayout&,
                                           const autodiff::Streams<double>& out,
                                           autodiff::Streams<double>& adjoint) {
      adjoint.stream(0).col(c).setOnes();
      return out.stream(0).col(c).sum();
    });
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
    field.value_and_gradient(field.parameters().data(), layout, autodiff::Batch<double>{x}, sum_c, g.data());
    Eigen::VectorXd rows = Eigen::VectorXd::Zero(p);
    for (int n = 0; n < 9; ++n) rows += jacobian.row(n * 4 + c).transpose();
    EXPECT_LE((rows - g).norm(), 1e-12 * (1 + g.norm())) << "output " << c;
  }
}

TEST(RadianceField, CheckpointRoundTripIsBitExact) {
  Field<float> field(small_nerf());
  field.parameters().setRandom();
  const auto path = testutil::scratch_dir("radiance_field") / "checkpoint.h5";
  {
    io::H5Writer file(path);
    save_field(file, field);
    file.commit();
  }
  const io::H5Reader file(path);
  const Field<float> loaded = load_field<float>(file);
  ASSERT_EQ(loaded.parameter_count(), field.parameter_count());
  EXPECT_EQ(std::memcmp(loaded.parameters().data(), field.parameters().data(),
                        sizeof(float) * field.parameter_count()), 0);
  EXPECT_EQ(loaded.options().color_hidden, field.options().color_hidden);
  EXPECT_EQ(loaded.options().direction_frequencies, field.options().direction_frequencies);
  const autodiff::Matrix<float> x = samples(7, 8).cast<float>();
  EXPECT_EQ(loaded.values(x), field.values(x));
}

TEST(RadianceField, OptionsAreValidated) {
  FieldOptions o = small_nerf();
  o.input_dim = 3;
  EXPECT_THROW(Field<double>{o}, std::invalid_argument);
  o = small_nerf();
  o.direction_frequencies = 0;
  EXPECT_THROW(Field<double>{o}, std::invalid_argument);
  o = small_nerf();
  o.color_hidden = {4, 0};
  try {
    Field<double> f(o);
    FAIL() << "accepted color_hidden with a zero width";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("field.color_hidden[1] = 0"), std::string::npos) << e.what();
  }
}

TEST(OnColumns, RejectsColumnsOutsideItsInput) {
  EXPECT_THROW(autodiff::OnColumns<double>(std::make_unique<Dense<double>>(2, 3), 3, 4),
               std::invalid_argument);
  EXPECT_THROW(autodiff::OnColumns<double>(nullptr, 0, 4), std::invalid_argument);
  EXPECT_THROW(autodiff::OnColumns<double>(std::make_unique<autodiff::OnColumns<double>>(
                                               std::make_unique<Dense<double>>(2, 3), 0, 3),
                                           0, 4),
               std::invalid_argument);
  const autodiff::OnColumns<double> fits(std::make_unique<Dense<double>>(2, 3), 2, 4);
  EXPECT_EQ(fits.output_width(), 5);
}

}  // namespace
}  // namespace nfield::fields
