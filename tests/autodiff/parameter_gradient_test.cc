// SPDX-License-Identifier: MIT
//
// Parameter gradients from Sequential::value_and_gradient (the reverse pass of every stream
// rule) of a loss of ALL output streams, ½ Σ w_s out_s², against central finite
// differences of the parameters (Ridders-extrapolated), for every registered activation ×
// encoding; and their independence of SequentialOptions (block_points 1, 7, 128; threads 1,
// 2) up to rounding, bit-identical between two runs with the same settings.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <random>

#include "autodiff/sequential.h"
#include "fields/activation_layer.h"
#include "fields/dense.h"
#include "fields/encodings.h"
#include "fields/field.h"
#include "tests/testing/reference_field.h"
#include "tests/testing/squares_loss.h"
#include "tests/testing/stream_checks.h"

namespace nfield::testutil {
namespace {

constexpr double kGradientTolerance = 1e-6;

// Everything one gradient check needs: a Sequential, its parameters, points and a loss.
struct Problem {
  const autodiff::Sequential<double>* network;
  Eigen::VectorXd theta;
  StreamLayout layout;
  Eigen::MatrixXd x;
  SquaresLoss<double> loss;
};

Problem make_problem(const autodiff::Sequential<double>& network, Eigen::VectorXd theta,
                     StreamSpec spec, Eigen::MatrixXd x) {
  StreamLayout layout(std::move(spec));
  Streams<double> out;
  network.evaluate(theta.data(), layout, x, out);
  SquaresLoss<double> loss(SquaresLoss<double>::balanced_weights(out));
  return {&network, std::move(theta), std::move(layout), std::move(x), std::move(loss)};
}

double loss_at(const Problem& p, const Eigen::VectorXd& theta) {
  Streams<double> out;
  p.network->evaluate(theta.data(), p.layout, p.x, out);
  return p.loss.value(out);
}

Eigen::VectorXd reverse_gradient(const Problem& p, double* loss = nullptr) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(p.theta.size());
  const double l = p.network->value_and_gradient(p.theta.data(), p.layout, p.x, p.loss, g.data());
  if (loss) *loss = l;
  return g;
}

// Central differences of the loss along parameter direction u; `step_ok(h)` may veto a step
// (ReLU kinks), which is then halved.
double directional_fd(const Problem& p, const Eigen::VectorXd& u, double h,
                      const std::function<bool(double)>& step_ok = {}) {
  while (step_ok && !step_ok(h)) h /= 2;
  auto f = [&](double tau) {
    return Eigen::VectorXd::Constant(1, loss_at(p, p.theta + tau * u));
  };
  return ridders(f, h, 1, 4, 2.0).value[0];
}

double max_relative(const Eigen::VectorXd& actual, const Eigen::VectorXd& expected) {
  return (actual - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff();
}

class ParameterGradients : public ::testing::TestWithParam<NetworkCase> {};

TEST_P(ParameterGradients, MatchFiniteDifferences) {
  const std::uint64_t seed = fnv1a(GetParam().name()) % 100000;
  std::mt19937_64 rng(seed);
  const fields::FieldOptions options = small_options(GetParam(), 2, 2, seed);
  const fields::Field<double> field(options, {.block_points = 2, .threads = 1});
  const ReferenceField ref(field);
  const bool kinks = has_kinks(options);
  const Eigen::MatrixXd x = sample_points(ref, kinks, 3, rng);
  const std::vector<bool> pattern = kinks ? kink_pattern(ref, x) : std::vector<bool>{};
  const double h0 = GetParam().type == "siren" ? 1e-3 : 1e-2;
  auto no_kink_crossed = [&](const Eigen::VectorXd& u) {
    return [&, u](double h) {
      return !kinks || (kink_pattern(ref.with_parameters(field.parameters() + h * u), x) == pattern &&
                        kink_pattern(ref.with_parameters(field.parameters() - h * u), x) == pattern);
    };
  };

  // Every parameter on the richest spec: axes tangents, four operators, Taylor order 4 (the
  // gradient alone for a field without operator and Taylor streams).
  {
    const Problem p = make_problem(field.network(), field.parameters(),
                                   richest_spec(GetParam(), 2, rng), x);
    const Eigen::VectorXd g = reverse_gradient(p);
    Eigen::VectorXd fd(g.size());
    for (Eigen::Index i = 0; i < g.size(); ++i) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(g.size(), i);
      fd[i] = directional_fd(p, e, h0, no_kink_crossed(e));
    }
    const double err = max_relative(g, fd);
    WorstErrors::get().record("gradient vs fd, every parameter", err, GetParam().name());
    EXPECT_LE(err, kGradientTolerance);
  }
  // Random parameter directions on the other forward orders.
  std::vector<NamedSpec> specs = all_specs(2, rng);
  for (const NamedSpec& named : specs) {
    if (!supports(GetParam(), StreamLayout(named.spec))) continue;  // refused (stream_rules_test)
    const Problem p = make_problem(field.network(), field.parameters(), named.spec, x);
    const Eigen::VectorXd g = reverse_gradient(p);
    Eigen::VectorXd actual(2), expected(2);
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd u = random_matrix(g.size(), 1, rng).normalized();
      actual[k] = g.dot(u);
      expected[k] = directional_fd(p, u, h0, no_kink_crossed(u));
    }
    const double err = max_relative(actual, expected);
    WorstErrors::get().record("gradient vs fd, directions", err,
                              GetParam().name() + " " + named.name);
    EXPECT_LE(err, kGradientTolerance) << named.name;
  }
}

TEST_P(ParameterGradients, IndependentOfBlocksAndThreads) {
  const std::uint64_t seed = fnv1a(GetParam().name()) % 100000 + 3;
  std::mt19937_64 rng(seed);
  const int d = takes_input_dim(GetParam(), 3) ? 3 : 4;
  fields::Field<double> field(small_options(GetParam(), d, 2, seed));
  Eigen::MatrixXd x = random_matrix(37, d, rng);
  const int variances = d - ReferenceField(field).variance_begin();  // in [0, kHighestVariance]
  x.rightCols(variances) = (x.rightCols(variances).array() + 1) * (kHighestVariance / 2);
  field.network().set_options({.block_points = 128, .threads = 1});
  const Problem p = make_problem(field.network(), field.parameters(),
                                   richest_spec(GetParam(), d, rng), x);
  Streams<double> reference_out;
  field.evaluate(p.layout, x, reference_out);
  double reference_loss = 0;
  const Eigen::VectorXd reference = reverse_gradient(p, &reference_loss);

  // value_and_gradient adds into the gradient it is given.
  {
    Eigen::VectorXd g = Eigen::VectorXd::Ones(reference.size());
    field.network().value_and_gradient(p.theta.data(), p.layout, x, p.loss, g.data());
    EXPECT_LE((g - reference - Eigen::VectorXd::Ones(g.size())).cwiseAbs().maxCoeff(),
              1e-14 * (1 + reference.cwiseAbs().maxCoeff()));
  }
  for (Eigen::Index block : {1, 7, 128})
    for (int threads : {1, 2}) {
      field.network().set_options({.block_points = block, .threads = threads});
      const std::string where = GetParam().name() + " block_points=" + std::to_string(block) +
                                " threads=" + std::to_string(threads);
      Streams<double> out;
      field.evaluate(p.layout, x, out);
      double l1 = 0, l2 = 0;
      const Eigen::VectorXd g1 = reverse_gradient(p, &l1);
      const Eigen::VectorXd g2 = reverse_gradient(p, &l2);
      // Same settings: bit for bit.
      EXPECT_EQ(std::memcmp(g1.data(), g2.data(), sizeof(double) * g1.size()), 0) << where;
      EXPECT_EQ(std::memcmp(&l1, &l2, sizeof(double)), 0) << where;
      // Other settings: rounding only.
      const double err_g = max_relative(g1, reference);
      const double err_l = std::abs(l1 - reference_loss) / reference_loss;
      double err_out = 0;
      for (int s = 0; s < p.layout.count(); ++s)
        err_out = std::max(err_out, relative_error(out.stream(s), reference_out.stream(s), 0.0));
      WorstErrors::get().record("gradient across blocks/threads", err_g, where);
      WorstErrors::get().record("loss across blocks/threads", err_l, where);
      WorstErrors::get().record("streams across blocks/threads", err_out, where);
      EXPECT_LE(err_g, 1e-12) << where;
      EXPECT_LE(err_l, 1e-12) << where;
      EXPECT_LE(err_out, 1e-12) << where;
    }
}

INSTANTIATE_TEST_SUITE_P(Registered, ParameterGradients,
                         ::testing::ValuesIn(registered_network_cases()), case_name);

// The reverse rules of an encoding and an activation in the middle of a network (a Field
// always puts the encoding first, where no input adjoint is asked of it).
TEST(ParameterGradients, EncodingInsideTheNetwork) {
  for (const char* encoding_name : {"positional", "fourier"})
    for (const std::string& activation : fields::activation_names()) {
      const std::string encoding = encoding_name;
      std::mt19937_64 rng(fnv1a(encoding + activation));
      const fields::EncodingOptions eo =
          testutil::encoding_of(encoding, {.frequencies = 2, .features = 4, .scale = 0.5, .seed = 3});
      autodiff::Sequential<double> net({.block_points = 2, .threads = 1});
      net.add(std::make_unique<fields::Dense<double>>(2, 3));
      net.add(std::make_unique<fields::ActivationLayer<double>>(
          fields::ActivationSpec{activation, 1.5}, 3));
      net.add(fields::make_encoding<double>(eo, 3));
      net.add(std::make_unique<fields::Dense<double>>(net.output_width(), 5));
      net.add(std::make_unique<fields::ActivationLayer<double>>(fields::ActivationSpec{"tanh", 1}, 5));
      net.add(std::make_unique<fields::Dense<double>>(5, 2));
      const Eigen::VectorXd theta = 0.6 * random_matrix(net.parameter_count(), 1, rng);
      const Eigen::MatrixXd x = random_matrix(3, 2, rng, 0.2, 1.0);
      for (const NamedSpec& named : {NamedSpec{"axes", axes_spec(2, rng, 4)}}) {
        const Problem p = make_problem(net, theta, named.spec, x);
        const Eigen::VectorXd g = reverse_gradient(p);
        // Signs of the first layer's pre-activations: a parameter step must not flip one
        // (ReLU kinks).
        auto first_layer_signs = [&](const Eigen::VectorXd& t) {
          const Eigen::Map<const Eigen::MatrixXd> w(t.data(), 3, 2);
          const Eigen::MatrixXd z = (x * w.transpose()).rowwise() +
                                    Eigen::Map<const Eigen::RowVectorXd>(t.data() + 6, 3);
          std::vector<bool> signs;
          for (Eigen::Index i = 0; i < z.size(); ++i) signs.push_back(z.data()[i] > 0);
          return signs;
        };
        const std::vector<bool> signs = first_layer_signs(theta);
        Eigen::VectorXd fd(g.size());
        for (Eigen::Index i = 0; i < g.size(); ++i) {
          const Eigen::VectorXd e = Eigen::VectorXd::Unit(g.size(), i);
          fd[i] = directional_fd(p, e, 1e-2, [&](double h) {
            return first_layer_signs(theta + h * e) == signs &&
                   first_layer_signs(theta - h * e) == signs;
          });
        }
        const double err = max_relative(g, fd);
        WorstErrors::get().record("gradient vs fd, encoding inside", err,
                                  encoding + " " + activation + " " + named.name);
        EXPECT_LE(err, kGradientTolerance) << encoding << " " << activation << " " << named.name;
      }
    }
}

}  // namespace
}  // namespace nfield::testutil
