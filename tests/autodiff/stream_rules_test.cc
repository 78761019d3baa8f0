// SPDX-License-Identifier: MIT
//
// Every stream rule (value, tangents along axes and arbitrary directions, operator streams,
// Taylor coefficients of order 1–4) of every registered activation × encoding, BACON and
// ACORN, on random small networks (hidden [8, 8], input dims 1–4, output dims 1–2), in
// double (ACORN: dims 1–3, its value and tangent streams only, and that it refuses the rest):
//
//   * against nested ceres::Jet (tests/testing/reference_field.h): relative error ≤ 1e-10
//     (both sides are exact up to rounding; the worst seen is ~1e-13, and 1e-10 still
//     catches a 1e-9 slip such as a wrong phase constant);
//   * against central finite differences, extrapolated by Ridders' method:
//       - first differences of the library's own lower-order streams: tangent vᵢ from the
//         value, vᵢᵀ H vⱼ (hence every operator stream) from the tangents, k·z_k from z_{k−1};
//         relative error ≤ 1e-6;
//       - second differences of the value alone (operators by polarization along vᵢ ± vⱼ,
//         2 z₂ along w): FD roundoff ε|f|/h² limits these to ~1e-7…1e-6, so the bound is
//         1e-5.
//
// Relative errors are per stream and output, max over points, relative to the stream's own
// largest magnitude but never to less than 1e-3 of that derivative's natural size
// (max(S_k, Ω S_{k−1}), S_k the largest stream of order k, Ω the field's frequency
// estimate), so streams that vanish identically (ReLU's second derivatives) are compared
// against a meaningful absolute scale.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "autodiff/streams.h"
#include "fields/field.h"
#include "tests/testing/reference_field.h"
#include "tests/testing/stream_checks.h"

namespace nfield::testutil {
namespace {

constexpr double kJetTolerance = 1e-10;
constexpr double kFirstDifferenceTolerance = 1e-6;
constexpr double kSecondDifferenceTolerance = 1e-5;

int output_dim_for(int d) { return 1 + d % 2; }

class StreamRules : public ::testing::TestWithParam<NetworkCase> {
 protected:
  std::uint64_t seed(int d) const { return fnv1a(GetParam().name()) % 100000 + 7919 * d; }
};

TEST_P(StreamRules, MatchNestedJets) {
  for (int d = 1; d <= 4; ++d) {
    if (!takes_input_dim(GetParam(), d)) continue;
    std::mt19937_64 rng(seed(d));
    const fields::FieldOptions options = small_options(GetParam(), d, output_dim_for(d), seed(d));
    const fields::Field<double> field(options, {.block_points = 3, .threads = 1});
    const ReferenceField ref(field);
    const Eigen::MatrixXd x = sample_points(ref, has_kinks(options), 5, rng);
    for (const NamedSpec& named : all_specs(d, rng)) {
      const StreamLayout layout(named.spec);
      if (!supports(GetParam(), layout)) continue;  // refused: UnsupportedStreamsAreRefused
      const Eigen::MatrixXd actual = field_streams(field, layout, x);
      const Eigen::MatrixXd expected = reference_streams(ref, layout, x);
      const std::vector<double> scale = order_scales(layout, expected, x.rows());
      for (int s = 0; s < layout.count(); ++s) {
        const int k = stream_order(layout, s);
        const double err = relative_error(actual.middleRows(s * x.rows(), x.rows()),
                                          expected.middleRows(s * x.rows(), x.rows()),
                                          1e-3 * scale[k]);
        const std::string where = GetParam().name() + " d=" + std::to_string(d) + " " +
                                  named.name + ": " + stream_name(layout, s);
        WorstErrors::get().record("jet: " + stream_kind(layout, s), err, where);
        EXPECT_LE(err, kJetTolerance) << where;
      }
    }
  }
}

// Largest Taylor growth rate along the axes: Ω = max_k (S_k / S_0)^(1/k) (k = 1 only, the
// gradient, for a field without Taylor streams).
double frequency_estimate(const fields::Field<double>& field, const Eigen::MatrixXd& x,
                          bool taylor = true) {
  const int d = field.input_dim();
  StreamSpec spec = StreamSpec::gradient(d);
  if (taylor) {
    spec = StreamSpec::values(d);
    spec.set_taylor(Eigen::MatrixXd::Identity(d, d), 4);
  }
  const StreamLayout layout(spec);
  const Eigen::MatrixXd s = field_streams(field, layout, x);
  const std::vector<double> scale = order_scales(layout, s, x.rows());
  double omega = 1;
  for (int k = 1; k <= std::min(4, layout.forward_order()); ++k) omega = std::max(omega, std::pow(scale[k] / scale[0], 1.0 / k));
  return omega;
}

class FiniteDifferences {
 public:
  FiniteDifferences(const fields::Field<double>& field, const ReferenceField& ref, bool kinks,
                    const StreamLayout& layout, const Eigen::MatrixXd& x, double h0)
      : field_(field), ref_(ref), kinks_(kinks), layout_(layout), x_(x), h0_(h0) {
    if (kinks_) pattern_ = kink_pattern(ref_, x_);
  }

  // Derivative (order 1) or second derivative (order 2) of all streams along u.
  Eigen::MatrixXd along(const Eigen::VectorXd& u, int order) const {
    double h = h0_ / u.norm();
    // Never straddle a ReLU kink: shrink the largest step until the signs of all
    // pre-activations agree at both ends.
    while (kinks_ && (kink_pattern(ref_, shifted(h, u)) != pattern_ ||
                      kink_pattern(ref_, shifted(-h, u)) != pattern_))
      h /= 2;
    auto f = [&](double tau) -> Eigen::VectorXd {
      const Eigen::MatrixXd s = field_streams(field_, layout_, shifted(tau, u));
      return Eigen::Map<const Eigen::VectorXd>(s.data(), s.size());
    };
    const RiddersResult r = ridders(f, h, order);
    return Eigen::Map<const Eigen::MatrixXd>(r.value.data(), layout_.count() * x_.rows(),
                                             field_.output_dim());
  }

 private:
  Eigen::MatrixXd shifted(double tau, const Eigen::VectorXd& u) const {
    return x_.rowwise() + tau * u.transpose();
  }
  const fields::Field<double>& field_;
  const ReferenceField& ref_;
  bool kinks_;
  const StreamLayout& layout_;
  Eigen::MatrixXd x_;
  double h0_;
  std::vector<bool> pattern_;
};

TEST_P(StreamRules, MatchFiniteDifferences) {
  for (int d = 1; d <= 4; ++d) {
    if (!takes_input_dim(GetParam(), d)) continue;
    std::mt19937_64 rng(seed(d) + 1);
    const fields::FieldOptions options = small_options(GetParam(), d, output_dim_for(d), seed(d));
    const fields::Field<double> field(options, {.block_points = 128, .threads = 1});
    const ReferenceField ref(field);
    const bool kinks = has_kinks(options);
    const Eigen::MatrixXd x = sample_points(ref, kinks, 4, rng);
    const Eigen::Index n = x.rows();
    const bool all_streams = unsupported_streams(GetParam()).empty();
    const double omega = frequency_estimate(field, x, all_streams);
    std::vector<NamedSpec> specs = {{"axes", axes_spec(d, rng, 4)},
                                    {"directions", directions_spec(d, rng)}};
    if (!all_streams) {  // the tangents alone, along the axes and arbitrary directions
      specs[0].spec = StreamSpec::gradient(d);
      specs[1].spec = StreamSpec::values(d);
      specs[1].spec.tangents = random_matrix(d, d + 1, rng);
    }
    for (const NamedSpec& named : specs) {
      const StreamLayout layout(named.spec);
      const StreamSpec& spec = layout.spec();
      const Eigen::MatrixXd streams = field_streams(field, layout, x);
      const std::vector<double> scale = order_scales(layout, streams, n);
      auto natural = [&](int k) { return std::max(scale[k], omega * scale[k - 1]); };
      auto stream = [&](const Eigen::MatrixXd& m, int s) { return m.middleRows(s * n, n); };
      const std::string where0 = GetParam().name() + " d=" + std::to_string(d) + " " + named.name;
      auto check = [&](const std::string& what, const Eigen::MatrixXd& actual,
                       const Eigen::MatrixXd& fd, double floor, double tolerance,
                       const std::string& where) {
        const double err = relative_error(actual, fd, 1e-3 * floor);
        WorstErrors::get().record("fd: " + what, err, where0 + ": " + where);
        EXPECT_LE(err, tolerance) << what << ", " << where0 << ": " << where;
      };
      FiniteDifferences fd(field, ref, kinks, layout, x, 0.1 / omega);
      const int t_count = layout.tangents();

      // First differences along every tangent direction vⱼ: ∂/∂vⱼ of the value is tangent j,
      // of tangent i is vᵢᵀ H vⱼ.
      std::vector<Eigen::MatrixXd> along_tangent;
      for (int j = 0; j < t_count; ++j) along_tangent.push_back(fd.along(spec.tangents.col(j), 1));
      for (int j = 0; j < t_count; ++j)
        check("tangent vs d(value)", stream(streams, layout.tangent(j)),
              stream(along_tangent[j], 0), natural(1), kFirstDifferenceTolerance,
              stream_name(layout, layout.tangent(j)));
      for (int q = 0; q < layout.operators(); ++q) {
        Eigen::MatrixXd op = Eigen::MatrixXd::Zero(n, field.output_dim());
        for (int i = 0; i < t_count; ++i)
          for (int j = 0; j < t_count; ++j)
            op += spec.operators[q](i, j) * stream(along_tangent[j], layout.tangent(i));
        check("operator vs d(tangents)", stream(streams, layout.op(q)), op, natural(2),
              kFirstDifferenceTolerance, stream_name(layout, layout.op(q)));
      }

      // Second differences of the value alone: vᵢᵀ H vᵢ along vᵢ, off-diagonals by
      // polarization, vᵢᵀ H vⱼ = (D²(vᵢ + vⱼ) − D²(vᵢ − vⱼ)) / 4.
      if (layout.operators() > 0) {
        Eigen::MatrixXd second(t_count * t_count * n, field.output_dim());
        auto block = [&](int i, int j) { return second.middleRows((i * t_count + j) * n, n); };
        for (int i = 0; i < t_count; ++i) {
          block(i, i) = stream(fd.along(spec.tangents.col(i), 2), 0);
          for (int j = i + 1; j < t_count; ++j) {
            const Eigen::VectorXd vi = spec.tangents.col(i), vj = spec.tangents.col(j);
            block(i, j) = (stream(fd.along(vi + vj, 2), 0) - stream(fd.along(vi - vj, 2), 0)) / 4;
            block(j, i) = block(i, j);
          }
        }
        for (int q = 0; q < layout.operators(); ++q) {
          Eigen::MatrixXd op = Eigen::MatrixXd::Zero(n, field.output_dim());
          for (int i = 0; i < t_count; ++i)
            for (int j = 0; j < t_count; ++j) op += spec.operators[q](i, j) * block(i, j);
          check("operator vs second differences", stream(streams, layout.op(q)), op, natural(2),
                kSecondDifferenceTolerance, stream_name(layout, layout.op(q)));
        }
      }

      // Taylor series along each w: d/dτ z_{k−1} = k z_k (z₀ the value), and the second
      // difference of the value is 2 z₂.
      for (int p = 0; p < layout.taylor_dirs(); ++p) {
        const Eigen::VectorXd w = spec.taylor_directions.col(p);
        const Eigen::MatrixXd d1 = fd.along(w, 1);
        for (int k = 1; k <= layout.taylor_order(); ++k) {
          const int lower = k == 1 ? 0 : layout.taylor(p, k - 1);
          check("taylor order " + std::to_string(k) + " vs d(order " + std::to_string(k - 1) + ")",
                k * stream(streams, layout.taylor(p, k)), stream(d1, lower), natural(k),
                kFirstDifferenceTolerance, stream_name(layout, layout.taylor(p, k)));
        }
        if (layout.taylor_order() >= 2)
          check("taylor order 2 vs second differences", 2 * stream(streams, layout.taylor(p, 2)),
                stream(fd.along(w, 2), 0), natural(2), kSecondDifferenceTolerance,
                stream_name(layout, layout.taylor(p, 2)));
      }
    }
  }
}

// A field that lacks some streams refuses every layout that asks for them, saying which.
TEST_P(StreamRules, UnsupportedStreamsAreRefused) {
  const std::string reason = unsupported_streams(GetParam());
  if (reason.empty()) GTEST_SKIP() << GetParam().name() << " gives every stream";
  std::mt19937_64 rng(seed(2) + 2);
  const fields::Field<double> field(small_options(GetParam(), 2, 1, seed(2)));
  const Eigen::MatrixXd x = random_matrix(3, 2, rng);
  int refused = 0;
  for (const NamedSpec& named : all_specs(2, rng)) {
    const StreamLayout layout(named.spec);
    if (supports(GetParam(), layout)) continue;
    ++refused;
    try {
      field_streams(field, layout, x);
      ADD_FAILURE() << named.name << ": no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("operator and Taylor"), std::string::npos)
          << named.name << ": " << e.what();
    }
  }
  EXPECT_GT(refused, 0);
  std::cout << GetParam().name() << ": operator and Taylor streams not checked: " << reason << "\n";
}

// The closed-form jets of the reference agree with the library's derivative tables applied
// as a Taylor expansion, so a reference built either way checks the same function.
TEST_P(StreamRules, ReferenceActivationMatchesTables) {
  const fields::FieldOptions options = small_options(GetParam(), 2, 1, 5);
  const fields::Field<double> field(options);
  const ReferenceField ref(field);
  for (size_t l = 0; l < options.hidden.size(); ++l) {
    const fields::ActivationSpec spec = ref.activation(l);
    if (!knows_activation(spec.name)) GTEST_SKIP() << spec.name << " has no closed form here";
    const auto f = fields::make_activation<double>(spec);
    using T = ceres::Jet<ceres::Jet<ceres::Jet<double, 1>, 1>, 1>;
    for (double z0 : {-0.7, 0.3, 1.1}) {
      const T z = taylor_variable<T>(z0);
      bool known = false;
      const T a = closed_form_activation<T>(spec.name, spec.frequency, z, &known);
      const T b = apply_tables<T>(*f, z);
      for (int k = 0; k <= 3; ++k) {
        const double x = taylor_derivative(a, k), y = taylor_derivative(b, k);
        EXPECT_NEAR(x, y, 1e-12 * std::max(1.0, std::abs(x))) << spec.name << " k=" << k;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Registered, StreamRules,
                         ::testing::ValuesIn(registered_network_cases()), case_name);

}  // namespace
}  // namespace nfield::testutil
