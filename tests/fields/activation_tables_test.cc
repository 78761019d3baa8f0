// SPDX-License-Identifier: MIT
//
// The derivative tables σ⁽ᵐ⁾(z) of every registered activation: σ⁽ᵐ⁺¹⁾ against central
// differences of σ⁽ᵐ⁾ (Ridders) up to m = 6, against nested jets of the closed forms known
// to tests/testing/reference_field.h, independent of the order requested, and float
// against double.
#include <gtest/gtest.h>

#include <random>

#include "fields/activations.h"
#include "tests/testing/reference_field.h"
#include "tests/testing/stream_checks.h"

namespace nfield::testutil {
namespace {

constexpr int kMaxOrder = 6;

class ActivationTables : public ::testing::TestWithParam<std::string> {
 protected:
  fields::ActivationSpec spec() const { return {GetParam(), 1.7}; }
  // Points in [−2.5, 2.5], none within 0.2 of 0 (ReLU's kink).
  static Eigen::MatrixXd points() {
    std::mt19937_64 rng(5);
    Eigen::MatrixXd z(3, 4);
    for (Eigen::Index i = 0; i < z.size(); ++i) {
      const double u = uniform(rng, 0.2, 2.5);
      z.data()[i] = i % 2 ? u : -u;
    }
    return z;
  }
};

TEST_P(ActivationTables, ShapesAndIndependenceOfOrder) {
  const auto f = fields::make_activation<double>(spec());
  const Eigen::MatrixXd z = points();
  std::vector<Eigen::MatrixXd> full, partial;
  f->derivatives(z, kMaxOrder, full);
  ASSERT_EQ(full.size(), static_cast<size_t>(kMaxOrder + 1));
  for (const auto& t : full) {
    EXPECT_EQ(t.rows(), z.rows());
    EXPECT_EQ(t.cols(), z.cols());
  }
  for (int order = 0; order < kMaxOrder; ++order) {
    partial.assign(9, Eigen::MatrixXd::Constant(1, 1, 123.0));  // stale contents are replaced
    f->derivatives(z, order, partial);
    ASSERT_EQ(partial.size(), static_cast<size_t>(order + 1));
    for (int m = 0; m <= order; ++m) EXPECT_EQ(partial[m], full[m]) << "order " << order << " m " << m;
  }
}

TEST_P(ActivationTables, MatchFiniteDifferences) {
  const auto f = fields::make_activation<double>(spec());
  const Eigen::MatrixXd z = points();
  std::vector<Eigen::MatrixXd> tables;
  f->derivatives(z, kMaxOrder, tables);
  double largest = 0;
  for (const auto& t : tables) largest = std::max(largest, t.cwiseAbs().maxCoeff());
  for (int m = 0; m < kMaxOrder; ++m) {
    auto table_m = [&](double h) -> Eigen::VectorXd {
      std::vector<Eigen::MatrixXd> t;
      f->derivatives((z.array() + h).matrix(), m, t);
      return Eigen::Map<const Eigen::VectorXd>(t[m].data(), t[m].size());
    };
    const RiddersResult fd = ridders(table_m, 0.1);
    const Eigen::MatrixXd estimate = Eigen::Map<const Eigen::MatrixXd>(fd.value.data(), z.rows(), z.cols());
    // Per entry, relative to the entry (floor: 1e-6 of the largest table entry).
    const double err = ((tables[m + 1] - estimate).array().abs() /
                        tables[m + 1].array().abs().max(1e-6 * largest))
                           .maxCoeff();
    WorstErrors::get().record("activation table vs fd", err,
                              GetParam() + " order " + std::to_string(m + 1));
    EXPECT_LE(err, 1e-7) << GetParam() << " σ^(" << m + 1 << ")";
  }
}

TEST_P(ActivationTables, MatchNestedJets) {
  const fields::ActivationSpec s = spec();
  if (!knows_activation(s.name)) GTEST_SKIP() << s.name << " has no closed form in the reference";
  const auto f = fields::make_activation<double>(s);
  const Eigen::MatrixXd z = points();
  std::vector<Eigen::MatrixXd> tables;
  f->derivatives(z, 4, tables);
  using T = ceres::Jet<ceres::Jet<ceres::Jet<ceres::Jet<double, 1>, 1>, 1>, 1>;
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    bool known = false;
    const T y = closed_form_activation<T>(s.name, s.frequency, taylor_variable<T>(z.data()[i]), &known);
    for (int m = 0; m <= 4; ++m) {
      const double expected = taylor_derivative(y, m), actual = tables[m].data()[i];
      const double err = std::abs(actual - expected) / std::max(1e-300, std::abs(expected));
      if (expected == actual) continue;
      WorstErrors::get().record("activation table vs jet", err, s.name + " order " + std::to_string(m));
      EXPECT_LE(err, 1e-12) << s.name << " σ^(" << m << ") at " << z.data()[i];
    }
  }
}

TEST_P(ActivationTables, FloatMatchesDouble) {
  const auto fd = fields::make_activation<double>(spec());
  const auto ff = fields::make_activation<float>(spec());
  const Eigen::MatrixXd z = points().cast<float>().cast<double>();
  std::vector<Eigen::MatrixXd> td;
  std::vector<Eigen::MatrixXf> tf;
  fd->derivatives(z, kMaxOrder, td);
  ff->derivatives(z.cast<float>(), kMaxOrder, tf);
  for (int m = 0; m <= kMaxOrder; ++m) {
    const double err = relative_error(tf[m].cast<double>(), td[m], 0);
    WorstErrors::get().record("activation table float vs double", err,
                              GetParam() + " order " + std::to_string(m));
    // Horner's rule on the fast-growing polynomials of tanh and softplus loses a few digits
    // at high orders (~4e-5 at m = 6 in float): the bound is float's ~1e-4 of scale.
    EXPECT_LE(err, 1e-4) << GetParam() << " σ^(" << m << ")";
  }
}

INSTANTIATE_TEST_SUITE_P(Registered, ActivationTables, ::testing::ValuesIn(fields::activation_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace nfield::testutil
