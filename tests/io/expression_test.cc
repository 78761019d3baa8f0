// SPDX-License-Identifier: MIT
#include "io/expression.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <thread>

#include <gtest/gtest.h>

namespace nfield::io {
namespace {

constexpr double pi = std::numbers::pi;

TEST(Expression, PoissonSourceMatchesHandComputedValues) {
  Expression source("2*pi^2*sin(pi*x)*sin(pi*y)");
  Eigen::MatrixXd points(4, 2);
  points << 0.5, 0.5,   //
      0.25, 0.75,       //
      0.0, 0.3,         //
      0.1, 0.9;
  const Eigen::VectorXd values = source.evaluate(points);
  ASSERT_EQ(values.size(), 4);
  EXPECT_NEAR(values[0], 2 * pi * pi, 1e-12);               // sin(pi/2)^2 = 1
  EXPECT_NEAR(values[1], 2 * pi * pi * 0.5, 1e-12);         // (sqrt(2)/2)^2
  EXPECT_NEAR(values[2], 0.0, 1e-12);
  EXPECT_NEAR(values[3], 2 * pi * pi * std::sin(0.1 * pi) * std::sin(0.9 * pi), 1e-12);
}

struct Case {
  const char* text;
  double expected;  // at x = 0.3, y = -0.7, z = 2, t = 0.5
};

TEST(Expression, FunctionsAndConstants) {
  const double x = 0.3, y = -0.7, z = 2, t = 0.5;
  const Case cases[] = {
      {"sin(x)", std::sin(x)},          {"cos(y)", std::cos(y)},
      {"tan(x)", std::tan(x)},          {"exp(z)", std::exp(z)},
      {"log(z)", std::log(z)},          {"sqrt(z)", std::sqrt(z)},
      {"abs(y)", 0.7},                  {"tanh(y)", std::tanh(y)},
      {"sinh(x)", std::sinh(x)},        {"cosh(x)", std::cosh(x)},
      {"atan2(y, x)", std::atan2(y, x)}, {"pow(z, 3)", 8},
      {"z^3", 8},                       {"-z^2", -4},
      {"2^3^2", 512},                   {"min(x, y)", y},
      {"max(x, y, t)", t},              {"heaviside(y)", 0},
      {"heaviside(x)", 1},              {"step(0)", 1},
      {"pi", pi},                       {"e", std::numbers::e},
      {"2*e", 2 * std::numbers::e},     {"1e-3 + 2e1", 20.001},
      {"x < t ? 1 : 2", 1},             {"x*y*z*t", x * y * z * t},
      {"log10(100)", 2},                {"7", 7},
  };
  Eigen::MatrixXd point(1, 4);
  point << x, y, z, t;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    Expression expression(c.text);
    EXPECT_NEAR(expression.evaluate(point)[0], c.expected, 1e-14);
    EXPECT_NEAR(expression.evaluate(std::vector<double>{x, y, z, t}), c.expected, 1e-14);
  }
}

TEST(Expression, MissingColumnsAreZero) {
  Expression sum("x + 10*y + 100*z + 1000*t + 1");
  Eigen::MatrixXd one_column(2, 1);
  one_column << 1, 2;
  EXPECT_EQ(sum.evaluate(one_column), Eigen::Vector2d(2, 3));
  Eigen::MatrixXd three_columns(1, 3);
  three_columns << 1, 2, 3;
  EXPECT_EQ(sum.evaluate(three_columns)[0], 322);
  EXPECT_EQ(sum.evaluate(Eigen::MatrixXd(0, 2)).size(), 0);
  EXPECT_THROW(sum.evaluate(Eigen::MatrixXd::Zero(1, 5)), std::invalid_argument);
}

TEST(Expression, CustomVariablesAndQueries) {
  Expression radius("sqrt(r^2 + s^2)", {"r", "s"});
  EXPECT_EQ(radius.evaluate(std::vector<double>{3, 4}), 5);
  EXPECT_EQ(radius.text(), "sqrt(r^2 + s^2)");
  EXPECT_EQ(radius.variables(), (std::vector<std::string>{"r", "s"}));
  EXPECT_TRUE(radius.uses("r"));
  EXPECT_FALSE(radius.uses("x"));
  EXPECT_FALSE(radius.is_constant());

  Expression wave("sin(x - t)");
  EXPECT_TRUE(wave.uses("t"));
  EXPECT_FALSE(wave.uses("y"));
  EXPECT_TRUE(Expression("2*pi").is_constant());
  // Blocks and maps are accepted without copies on the caller's side.
  Eigen::MatrixXd grid = Eigen::MatrixXd::Random(5, 4);
  const Eigen::VectorXd values = wave.evaluate(grid.leftCols(2));  // t = 0
  for (Eigen::Index i = 0; i < grid.rows(); ++i) EXPECT_EQ(values[i], std::sin(grid(i, 0)));
}

struct BadCase {
  const char* text;
  std::vector<std::string> variables;
  std::size_t position;
  const char* what;
};

TEST(Expression, ErrorsCarryPositionAndMessage) {
  const std::size_t none = std::string::npos;
  const BadCase cases[] = {
      {"sin(pi*q)", {"x"}, 7, "in expression 'sin(pi*q)': Unexpected token \"q\" found at position 7."},
      {"2*x +", {"x"}, 6, "in expression '2*x +': Unexpected end of expression at position 6"},
      {"", {"x"}, none, "in expression '': Expression is empty."},
      {"x, 2", {"x"}, none, "in expression 'x, 2': expected a single expression, got 2 separated by commas"},
      {"x", {"1x"}, none, "in expression 'x': invalid variable name '1x'"},
      {"x", {"x", "x"}, none, "in expression 'x': variable 'x' listed twice"},
      {"e", {"e"}, none, "in expression 'e': Name conflict"},
      {"foo(x)", {"x"}, 0, "in expression 'foo(x)': Unexpected token \"foo\" found at position 0."},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      Expression expression(c.text, c.variables);
      ADD_FAILURE() << "no ExpressionError";
    } catch (const ExpressionError& e) {
      EXPECT_EQ(e.position(), c.position);
      EXPECT_EQ(std::string(e.what()), c.what);
      EXPECT_EQ(e.expression(), c.text);
    }
  }
}

TEST(Expression, ConcurrentEvaluationMatchesSerial) {
  const Expression expression("exp(-x^2 - y^2) * cos(3*z) + t");
  Eigen::MatrixXd points = Eigen::MatrixXd::Random(2000, 4);
  const Eigen::VectorXd expected = expression.evaluate(points);
  std::vector<int> mismatches(8, 0);
  std::vector<std::thread> threads;
  for (int k = 0; k < 8; ++k)
    threads.emplace_back([&, k] {
      const Expression copy = expression;  // copies share the evaluator pool
      for (int repeat = 0; repeat < 20; ++repeat) {
        const Eigen::VectorXd values = (k % 2 ? copy : expression).evaluate(points);
        if (values != expected) ++mismatches[k];
      }
    });
  for (std::thread& thread : threads) thread.join();
  for (int k = 0; k < 8; ++k) EXPECT_EQ(mismatches[k], 0) << "thread " << k;
}

TEST(Expression, NamedConstants) {
  const Expression e("nu*x + 2", {"x", "t"}, {{"nu", 0.5}, {"mu", 3}});
  Eigen::MatrixXd points(2, 2);
  points << 4, 0, -2, 1;
  EXPECT_EQ(e.evaluate(points), Eigen::Vector2d(4, 1));
  EXPECT_EQ(e.constants_used(), std::vector<std::string>{"nu"});
  EXPECT_TRUE(e.uses("x"));
  EXPECT_FALSE(Expression("nu*mu", {"x"}, {{"nu", 0.5}, {"mu", 3}}).uses("x"));
  EXPECT_TRUE(Expression("nu*mu", {"x"}, {{"nu", 0.5}, {"mu", 3}}).is_constant());
  EXPECT_THROW(Expression("x", {"x"}, {{"x", 1}}), ExpressionError);
  EXPECT_THROW(Expression("q", {"x"}, {{"nu", 1}}), ExpressionError);
}

}  // namespace
}  // namespace nfield::io
