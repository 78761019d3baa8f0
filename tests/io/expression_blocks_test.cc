// SPDX-License-Identifier: MIT
// io::Expression's compiled block path against its muparser path, on random points: every
// function and operator of the compiled language, the precedence cases where two parsers
// could disagree, the expressions that stay with muparser, and the block layout (several
// blocks and a remainder, missing trailing columns, a strided block of a larger matrix).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/expression.h"

namespace nfield::io {
namespace {

// n random points with columns x, y, z, t in [lo, hi].
Eigen::MatrixXd random_points(Eigen::Index n, Eigen::Index columns, double lo, double hi, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  Eigen::MatrixXd p(n, columns);
  for (Eigen::Index j = 0; j < columns; ++j)
    for (Eigen::Index i = 0; i < n; ++i) p(i, j) = u(rng);
  return p;
}

// Bit-equal values (NaNs alike), or within `ulps` units in the last place of the larger
// value or of 1, whichever is larger: where terms of about 1 nearly cancel (x^4 − y^5), a
// last-bit difference in a term is many units of the result's last place.
::testing::AssertionResult agree(const Eigen::VectorXd& compiled, const Eigen::VectorXd& muparser, double ulps,
                                 const std::string& text) {
  if (compiled.size() != muparser.size()) return ::testing::AssertionFailure() << text << ": sizes differ";
  for (Eigen::Index i = 0; i < compiled.size(); ++i) {
    const double a = compiled[i], b = muparser[i];
    if (std::isnan(a) && std::isnan(b)) continue;
    if (a == b) continue;
    const double scale = std::max({std::abs(a), std::abs(b), 1.0});
    if (std::isfinite(scale) && std::abs(a - b) <= ulps * std::numeric_limits<double>::epsilon() * scale) continue;
    return ::testing::AssertionFailure() << text << " at point " << i << ": compiled " << a << ", muparser " << b
                                         << " (difference " << a - b << ")";
  }
  return ::testing::AssertionSuccess();
}

// Every function and operator of the compiled language, as conditions use them; all compile,
// and the block values are muparser's bit for bit.
TEST(ExpressionBlocks, EveryFunctionAndOperatorMatchesMuparserExactly) {
  const char* texts[] = {
      "x + y",        "x - y",         "x * y",         "x / y",           "-x",            "+x",
      "x^2",          "y^3",           "x^0.5",         "x^y",             "pow(x, y)",     "pow(x, 0.7)",
      "sin(x)",       "cos(y)",        "tan(x)",        "exp(y)",          "log(x)",        "sqrt(y)",
      "abs(x - y)",   "tanh(2*x - 1)", "sinh(x)",       "cosh(y)",         "atan(x - y)",   "atan2(y - 0.5, x - 0.5)",
      "min(x, y)",    "max(x, t)",     "pi*x",          "e^x",             "2*pi^2*sin(pi*x)*sin(pi*y)",
      "sin(pi*x)*cos(2*pi*t) + 0.5*sin(4*pi*x)*cos(8*pi*t)",
      "exp(-2*t)*cos(x)*cos(y)",       "x*(1 - x)*y*(1 - y)",             "1/(1 + 25*x^2)",
      "(x - 0.5)*y + 3*y - t",         "exp(-(x*x + y*y)/0.02)",
  };
  const Eigen::MatrixXd points = random_points(1000, 4, 0.05, 1.5, 1);
  for (const char* text : texts) {
    const Expression e(text);
    ASSERT_TRUE(e.compiled()) << text;
    EXPECT_TRUE(agree(e.evaluate(points), e.evaluate_interpreted(points), 0, text));
  }
}

// Where the two parsers could read a text differently: the sign against ^, ^ to the right,
// an exponent with a sign, a power of a sum. Powers of anything but a bare variable are
// pow() in muparser and repeated squaring on the tape: a few units in the last place.
TEST(ExpressionBlocks, PrecedenceAndPowersAgreeWithMuparser) {
  const char* texts[] = {
      "-x^2",      "-2^2 + x",   "2^3^2 + x", "x^-1",        "2^-x",       "x^-y^2",      "-x^-2",
      "2*-x",      "x/-y*2",     "-(-x)",       "-(x - y)^3",  "(x + y)^4",  "x^4 - y^5",   "(1 - x)^10",
      "x^(1/3)",   "pi^3*x",     "3*x*5",     "(3*x + 1)*2", "4*x/3",      "x - x + 1",   "-x^2^-1",
      "(x - 0.5)/0.2 + 3*y - t",  // muparser: x*5 − 2.5
      "((x-0.5)^2 + (y-0.5)^2)/(2*0.1^2)",
  };
  const Eigen::MatrixXd points = random_points(1000, 4, 0.05, 1.5, 2);
  for (const char* text : texts) {
    const Expression e(text);
    ASSERT_TRUE(e.compiled()) << text;
    EXPECT_TRUE(agree(e.evaluate(points), e.evaluate_interpreted(points), 16, text));
  }
}

// Outside the tape's language muparser evaluates, and compiled() says so.
TEST(ExpressionBlocks, ComparisonsAndOtherFunctionsStayWithMuparser) {
  const char* texts[] = {
      "x < 0.5 ? 1 : 0",  "(x^2 + y^2)^(1/3)*sin(2/3*(atan2(y, x) + (y < 0 ? 2*pi : 0)))",
      "x >= y",           "x - 0.5*sign(x)", "asin(x/2)", "log10(x)", "heaviside(x - 0.3)", "besselj0(3*x)",
      "min(x, y, t)",     "sum(x, y)",       "ln(x)",
  };
  const Eigen::MatrixXd points = random_points(300, 4, -1, 1, 3);
  for (const char* text : texts) {
    const Expression e(text);
    EXPECT_FALSE(e.compiled()) << text;
    EXPECT_TRUE(agree(e.evaluate(points), e.evaluate_interpreted(points), 0, text));
  }
}

// The block loop: more points than one block with a remainder, a point set with fewer
// columns than variables (the missing ones read 0), a strided block of a larger matrix, no
// points, constants, and a domain's own variable names.
TEST(ExpressionBlocks, BlocksRemaindersMissingColumnsAndStrides) {
  const Expression e("sin(3*x)*exp(-t) + y*k", {"x", "y", "z", "t"}, {{"k", 0.25}});
  ASSERT_TRUE(e.compiled());
  const Eigen::MatrixXd wide = random_points(1031, 4, -2, 2, 4);
  EXPECT_TRUE(agree(e.evaluate(wide), e.evaluate_interpreted(wide), 0, "1031 points"));
  // x and y only: t = 0, so exp(-t) = 1.
  const Eigen::MatrixXd narrow = wide.leftCols(2);
  const Eigen::VectorXd values = e.evaluate(narrow);
  for (Eigen::Index i = 0; i < narrow.rows(); ++i)
    ASSERT_NEAR(values[i], std::sin(3 * narrow(i, 0)) + narrow(i, 1) * 0.25, 1e-15) << i;
  EXPECT_TRUE(agree(values, e.evaluate_interpreted(narrow), 0, "two columns"));
  // Rows 7..606 of the columns x, y, z: a Ref with an outer stride of 1031.
  const auto block = wide.block(7, 0, 600, 3);
  EXPECT_TRUE(agree(e.evaluate(block), e.evaluate_interpreted(block), 0, "strided block"));
  EXPECT_EQ(e.evaluate(Eigen::MatrixXd(0, 2)).size(), 0);
  EXPECT_THROW(e.evaluate(Eigen::MatrixXd::Zero(3, 5)), std::invalid_argument);

  const Expression named("r^2 + s", {"s", "r"});
  ASSERT_TRUE(named.compiled());
  const Eigen::MatrixXd rs = random_points(300, 2, -1, 1, 5);
  const Eigen::VectorXd r2s = named.evaluate(rs);
  for (Eigen::Index i = 0; i < rs.rows(); ++i)  // near: the compiler may fuse r·r + s here
    ASSERT_NEAR(r2s[i], rs(i, 1) * rs(i, 1) + rs(i, 0), 1e-15) << i;
  const Expression constant("2*pi");
  EXPECT_TRUE(constant.compiled());
  EXPECT_EQ(constant.evaluate(rs), Eigen::VectorXd::Constant(300, 2 * std::numbers::pi));
}

// ExpressionTiming: an interpreted scope routes evaluate through muparser (where the two
// differ in the last bit, the values change with it), the clock counts only inside a scope,
// and a second scope while one lives is refused.
TEST(ExpressionBlocks, TimingScope) {
  const Expression e("(x + y)^7 + 3*x*7");
  const Eigen::MatrixXd points = random_points(2000, 2, 0.1, 3, 6);
  const Eigen::VectorXd muparser = e.evaluate_interpreted(points);
  Eigen::VectorXd forced;
  {
    const ExpressionTiming interpreted(true);
    forced = e.evaluate(points);
  }
  EXPECT_TRUE(agree(forced, muparser, 0, "interpreter only"));
  const Eigen::VectorXd compiled = e.evaluate(points);
  EXPECT_NE(compiled, muparser) << "no last-bit difference left to tell the paths apart";
  EXPECT_TRUE(agree(compiled, muparser, 16, "compiled"));

  double counted = 0;
  {
    const ExpressionTiming timing(false);
    EXPECT_THROW(ExpressionTiming second(false), std::logic_error);
    for (int k = 0; k < 5; ++k) e.evaluate(points);
    counted = timing.seconds();
    EXPECT_GT(counted, 0.0);
    EXPECT_EQ(e.evaluate(points), compiled);
  }
  const ExpressionTiming fresh(false);  // the first scope ended: a new one starts at zero
  EXPECT_EQ(fresh.seconds(), 0.0);
}

}  // namespace
}  // namespace nfield::io
