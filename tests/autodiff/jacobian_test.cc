// SPDX-License-Identifier: MIT
//
// Per-point residual Jacobians from Sequential::residuals_and_jacobian, on random SIREN and
// tanh-MLP fields in double: every column against Ridders-extrapolated central differences
// of the residuals, Jᵀr against value_and_gradient's gradient of Σ‖r‖², independence of
// the block size and thread count, and float against double.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "autodiff/sequential.h"
#include "fields/field.h"
#include "tests/testing/stream_checks.h"

namespace nfield::testutil {
namespace {

using autodiff::Matrix;
using autodiff::StreamResidual;

// r = Δu − f(x), f = sin(x₀) + x₁², on a scalar field.
template <typename Scalar>
class LaplacianResidual final : public StreamResidual<Scalar> {
 public:
  LaplacianResidual(const StreamLayout& layout, const Eigen::MatrixXd& x)
      : laplacian_(layout.op(0)),
        source_((x.col(0).array().sin() + x.col(1).array().square()).matrix().cast<Scalar>()) {}
  int components() const override { return 1; }
  void evaluate(Eigen::Index first, const StreamLayout&, const Streams<Scalar>& out,
                Matrix<Scalar>& r) const override {
    r = out.stream(laplacian_).col(0) - source_.segment(first, out.points);
  }
  void backward(Eigen::Index, const StreamLayout&, const Streams<Scalar>&,
                const Matrix<Scalar>& r_bar, Streams<Scalar>& adjoint) const override {
    adjoint.stream(laplacian_).col(0) += r_bar.col(0);
  }

 private:
  int laplacian_;
  autodiff::Vector<Scalar> source_;
};

// A two-component (real, imaginary) residual on a field with two outputs: a Helmholtz
// operator with a rotation term, plus a product that makes it nonlinear in the streams,
//   r₀ = Δu₀ + k²u₀ − ω u₁ − f
//   r₁ = Δu₁ + k²u₁ + ω u₀ + u₀ ∂ₓu₁
template <typename Scalar>
class ComplexResidual final : public StreamResidual<Scalar> {
 public:
  ComplexResidual(const StreamLayout& layout, const Eigen::MatrixXd& x)
      : laplacian_(layout.op(0)),
        dx_(layout.tangent(0)),
        source_((x.col(0).array() * x.col(1).array()).cos().matrix().cast<Scalar>()) {}
  int components() const override { return 2; }
  void evaluate(Eigen::Index first, const StreamLayout&, const Streams<Scalar>& out,
                Matrix<Scalar>& r) const override {
    const auto u = out.stream(0), lap = out.stream(laplacian_), dx = out.stream(dx_);
    r.resize(out.points, 2);
    r.col(0) = lap.col(0) + k2 * u.col(0) - w * u.col(1) - source_.segment(first, out.points);
    r.col(1) = lap.col(1) + k2 * u.col(1) + w * u.col(0) +
               u.col(0).cwiseProduct(dx.col(1));
  }
  void backward(Eigen::Index, const StreamLayout&, const Streams<Scalar>& out,
                const Matrix<Scalar>& r_bar, Streams<Scalar>& adjoint) const override {
    const auto u = out.stream(0), dx = out.stream(dx_);
    adjoint.stream(laplacian_).col(0) += r_bar.col(0);
    adjoint.stream(laplacian_).col(1) += r_bar.col(1);
    adjoint.stream(0).col(0) += k2 * r_bar.col(0) + w * r_bar.col(1) +
                                r_bar.col(1).cwiseProduct(dx.col(1));
    adjoint.stream(0).col(1) += k2 * r_bar.col(1) - w * r_bar.col(0);
    adjoint.stream(dx_).col(1) += r_bar.col(1).cwiseProduct(u.col(0));
  }

 private:
  static constexpr Scalar k2 = Scalar(2.25), w = Scalar(0.7);
  int laplacian_, dx_;
  autodiff::Vector<Scalar> source_;
};

struct JacobianCase {
  NetworkCase network;
  int components;  // 1: LaplacianResidual, 2: ComplexResidual
  std::string name() const { return network.name() + (components == 1 ? "_laplacian" : "_complex"); }
};
void PrintTo(const JacobianCase& c, std::ostream* os) { *os << c.name(); }

template <typename Scalar>
std::unique_ptr<StreamResidual<Scalar>> make_residual(int components, const StreamLayout& layout,
                                                      const Eigen::MatrixXd& x) {
  if (components == 1) return std::make_unique<LaplacianResidual<Scalar>>(layout, x);
  return std::make_unique<ComplexResidual<Scalar>>(layout, x);
}

class Jacobians : public ::testing::TestWithParam<JacobianCase> {
 protected:
  void SetUp() override {
    const std::uint64_t seed = fnv1a(GetParam().name()) % 100000;
    std::mt19937_64 rng(seed);
    options_ = small_options(GetParam().network, 2, GetParam().components, seed, {6, 5});
    if (options_.type == "siren") options_.first_omega = 3;  // keeps FD steps well scaled
    if (options_.type == "bacon") {  // the loss of the output scale alone, as the Jacobian's
      fields::BaconOptions b = fields::bacon_options(options_);
      b.train_all_scales = false;
      options_.extension = b;
    }
    x_ = random_matrix(7, 2, rng);
    residual_ = make_residual<double>(GetParam().components, layout_, x_);
  }

  // r and J with the given evaluation options.
  void residuals_and_jacobian(const fields::Field<double>& field, Eigen::VectorXd& r,
                              Eigen::MatrixXd* jacobian, const Eigen::VectorXd* theta = nullptr) {
    const Eigen::Index m = x_.rows() * residual_->components();
    r.resize(m);
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    // NaN wherever nothing was written.
    RowMajor j = RowMajor::Constant(jacobian ? m : 0, field.parameter_count(),
                                    std::numeric_limits<double>::quiet_NaN());
    r.setConstant(std::numeric_limits<double>::quiet_NaN());
    // Through the field, which shows a multiscale field's output scale (fields/field.h).
    field.residuals_and_jacobian(theta ? theta->data() : field.parameters().data(), layout_,
                                 autodiff::Batch<double>{x_}, *residual_, r.data(),
                                 jacobian ? j.data() : nullptr);
    if (jacobian) *jacobian = j;
  }

  fields::FieldOptions options_;
  StreamLayout layout_{autodiff::StreamSpec::laplacian(2)};
  Eigen::MatrixXd x_;
  std::unique_ptr<StreamResidual<double>> residual_;
};

TEST_P(Jacobians, MatchCentralDifferences) {
  const fields::Field<double> field(options_, {.block_points = 3, .threads = 1});
  Eigen::VectorXd r;
  Eigen::MatrixXd jacobian;
  residuals_and_jacobian(field, r, &jacobian);
  ASSERT_TRUE(jacobian.allFinite());
  ASSERT_TRUE(r.allFinite());

  // Residuals against the plain evaluation of the streams.
  Streams<double> out;
  field.evaluate(layout_, x_, out);
  Eigen::MatrixXd expected_r;
  residual_->evaluate(0, layout_, out, expected_r);
  const Eigen::MatrixXd r_points = Eigen::Map<const Eigen::MatrixXd>(
      r.data(), residual_->components(), x_.rows()).transpose();
  EXPECT_LE((r_points - expected_r).cwiseAbs().maxCoeff(), 1e-14 * expected_r.cwiseAbs().maxCoeff());

  Eigen::MatrixXd fd(jacobian.rows(), jacobian.cols());
  const Eigen::VectorXd theta = field.parameters();
  for (Eigen::Index p = 0; p < theta.size(); ++p) {
    auto at = [&](double tau) {
      Eigen::VectorXd shifted = theta, values;
      shifted(p) += tau;
      residuals_and_jacobian(field, values, nullptr, &shifted);
      return values;
    };
    fd.col(p) = ridders(at, 0.05, 1, 8, 1.6).value;
  }
  const double scale = fd.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0);
  Eigen::Index row, col;
  const double error = (jacobian - fd).cwiseAbs().maxCoeff(&row, &col) / scale;
  EXPECT_LE(error, 1e-6) << "worst at residual " << row << ", parameter " << col << ": "
                         << jacobian(row, col) << " vs " << fd(row, col);
}

TEST_P(Jacobians, TransposeTimesResidualIsHalfTheGradient) {
  const fields::Field<double> field(options_, {.block_points = 3, .threads = 1});
  Eigen::VectorXd r;
  Eigen::MatrixXd jacobian;
  residuals_and_jacobian(field, r, &jacobian);

  // Σₙ ‖r(xₙ)‖² through the reverse pass of the summed gradient.
  const autodiff::LambdaLoss<double> loss([&](Eigen::Index first, const StreamLayout& layout,
                                              const Streams<double>& out,
                                              Streams<double>& adjoint) {
    Eigen::MatrixXd block_r;
    residual_->evaluate(first, layout, out, block_r);
    residual_->backward(first, layout, out, (2.0 * block_r).eval(), adjoint);
    return block_r.squaredNorm();
  });
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(field.parameter_count());
  const double value = field.value_and_gradient(field.parameters().data(), layout_,
                                                autodiff::Batch<double>{x_}, loss, gradient.data());
  EXPECT_NEAR(value, r.squaredNorm(), 1e-13 * value);
  const Eigen::VectorXd from_jacobian = 2.0 * jacobian.transpose() * r;
  EXPECT_LE((from_jacobian - gradient).cwiseAbs().maxCoeff(),
            1e-12 * gradient.cwiseAbs().maxCoeff());
}

TEST_P(Jacobians, IndependentOfBlocksAndThreads) {
  fields::Field<double> field(options_, {.block_points = 1, .threads = 1});
  Eigen::VectorXd r1, r2;
  Eigen::MatrixXd j1, j2;
  residuals_and_jacobian(field, r1, &j1);
  field.network().set_options({.block_points = 4, .threads = 2});
  residuals_and_jacobian(field, r2, &j2);
  EXPECT_LE((j1 - j2).cwiseAbs().maxCoeff(), 1e-13 * j1.cwiseAbs().maxCoeff());
  EXPECT_LE((r1 - r2).cwiseAbs().maxCoeff(), 1e-13 * r1.cwiseAbs().maxCoeff());
}

TEST_P(Jacobians, FloatAgreesWithDouble) {
  const fields::Field<double> field(options_, {.block_points = 3, .threads = 1});
  Eigen::VectorXd r;
  Eigen::MatrixXd jacobian;
  residuals_and_jacobian(field, r, &jacobian);

  const fields::Field<float> single = field.cast<float>();
  const auto residual = make_residual<float>(GetParam().components, layout_, x_);
  const Eigen::Index m = r.size();
  Eigen::VectorXf rf(m);
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jf(m, field.parameter_count());
  const Eigen::MatrixXf xf = x_.cast<float>();
  single.residuals_and_jacobian(single.parameters().data(), layout_, autodiff::Batch<float>{xf},
                                *residual, rf.data(), jf.data());
  EXPECT_LE((jf.cast<double>() - jacobian).cwiseAbs().maxCoeff(),
            1e-4 * jacobian.cwiseAbs().maxCoeff());
}

std::vector<JacobianCase> jacobian_cases() {
  std::vector<JacobianCase> cases;
  for (int components : {1, 2}) {
    cases.push_back({{"siren", "sine", "identity"}, components});
    cases.push_back({{"mlp", "tanh", "identity"}, components});
  }
  cases.push_back({{"siren", "sine", "fourier"}, 2});  // a parameter-free module before the first Dense
  cases.push_back({{"mlp", "tanh", "hash_grid"}, 1});  // an encoding with parameters
  cases.push_back({{"mlp", "tanh", "hash_grid", "cubic"}, 1});  // 4^d vertices per level
  // A multiplicative filter network, its finest scale (the last of the network's columns).
  cases.push_back({{"bacon", "sine", "identity"}, 1});
  cases.push_back({{"bacon", "sine", "identity"}, 2});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Fields, Jacobians, ::testing::ValuesIn(jacobian_cases()),
                         [](const auto& info) { return info.param.name(); });

// A module with parameters but no per-point gradients is refused up front, not inside the
// parallel region.
class OpaqueScale final : public autodiff::Module<double> {
 public:
  std::string name() const override { return "opaque scale"; }
  Eigen::Index input_width() const override { return 2; }
  Eigen::Index output_width() const override { return 2; }
  Eigen::Index parameter_count() const override { return 1; }
  void forward(const StreamLayout&, const double* params, const Streams<double>& in,
               Streams<double>& out, autodiff::SavedTensors<double>*) const override {
    out = in;
    out.data *= params[0];
  }
  void backward(const StreamLayout&, const double*, const Streams<double>&,
                const autodiff::SavedTensors<double>&, Streams<double>&, double*,
                Streams<double>*) const override {}
};

TEST(JacobianModules, ModuleWithoutPerPointGradientsIsRefused) {
  autodiff::Sequential<double> network({.block_points = 2, .threads = 2});
  network.add(std::make_unique<OpaqueScale>());
  const StreamLayout layout(autodiff::StreamSpec::values(2));
  const Eigen::MatrixXd x = Eigen::MatrixXd::Ones(3, 2);
  const double theta = 2.0;
  class Value final : public StreamResidual<double> {
   public:
    int components() const override { return 1; }
    void evaluate(Eigen::Index, const StreamLayout&, const Streams<double>& out,
                  Matrix<double>& r) const override {
      r = out.stream(0).col(0);
    }
    void backward(Eigen::Index, const StreamLayout&, const Streams<double>&,
                  const Matrix<double>& r_bar, Streams<double>& adjoint) const override {
      adjoint.stream(0).col(0) += r_bar.col(0);
    }
  } residual;
  Eigen::VectorXd r(3), j(3);
  network.residuals_and_jacobian(&theta, layout, x, residual, r.data(), nullptr);
  EXPECT_EQ(r, Eigen::VectorXd::Constant(3, 2.0));
  EXPECT_THROW(network.residuals_and_jacobian(&theta, layout, x, residual, r.data(), j.data()),
               std::logic_error);
}

}  // namespace
}  // namespace nfield::testutil
