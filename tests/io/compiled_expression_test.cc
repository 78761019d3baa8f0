// SPDX-License-Identifier: MIT
//
// The expression compiler (io/compiled_expression.h): every operator and function against
// plain C++ in double and float over blocks of random points, precedence, constant folding,
// the Jet derivative of random expressions against central differences, and errors at their
// positions.
#include "io/compiled_expression.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>

namespace nfield::io {
namespace {

// Slots: x → 0, y → 1, z → 2.
ExpressionScope xyz_scope() {
  ExpressionScope scope;
  scope.slots = {{"x", 0}, {"y", 1}, {"z", 2}};
  return scope;
}

template <typename T>
using Reference = std::function<T(T, T)>;

struct Case {
  const char* text;
  Reference<double> in_double;
  Reference<float> in_float;
};

// x > 0 (log, sqrt, pow of a real exponent), y of either sign.
#define CASE(text, expr) \
  Case { text, [](double x, double y) { (void)x; (void)y; return expr; }, [](float x, float y) { (void)x; (void)y; return expr; } }

const std::vector<Case>& cases() {
  using std::abs, std::atan, std::atan2, std::cos, std::cosh, std::exp, std::log, std::pow, std::sin, std::sinh,
      std::sqrt, std::tan, std::tanh;
  static const std::vector<Case> all = {
      CASE("x + y", x + y),         CASE("x - y", x - y),           CASE("x * y", x * y),
      CASE("x / y", x / y),         CASE("-y", -y),                 CASE("+y", y),
      CASE("x ^ 2", x * x),         CASE("y^3", y * y * y),         CASE("y^-2", 1 / (y * y)),
      CASE("x^0.5", pow(x, decltype(x)(0.5))),                      CASE("x^y", pow(x, y)),
      CASE("sin(y)", sin(y)),       CASE("cos(y)", cos(y)),         CASE("tan(y)", tan(y)),
      CASE("exp(y)", exp(y)),       CASE("log(x)", log(x)),         CASE("sqrt(x)", sqrt(x)),
      CASE("abs(y)", abs(y)),       CASE("tanh(y)", tanh(y)),       CASE("sinh(y)", sinh(y)),
      CASE("cosh(y)", cosh(y)),     CASE("atan(y)", atan(y)),       CASE("min(x, y)", x < y ? x : y),
      CASE("max(x, y)", x < y ? y : x),                             CASE("pow(x, y)", pow(x, y)),
      CASE("pow(y, 2)", y * y),     CASE("x - y - 1", x - y - 1),   CASE("x / y / 2", x / y / 2),
      CASE("-x^2", -(x * x)),       CASE("2*-x", 2 * -x),           CASE("(x + y) * 2", (x + y) * 2),
      CASE("x*y + y*x", x * y + y * x),  CASE("atan2(y, x)", atan2(y, x)), CASE("atan2(-y, -x)", atan2(-y, -x)),
  };
  return all;
}
#undef CASE

template <typename T>
void check_cases(double tolerance) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0.1, 2.0), uy(-1.5, 1.5);
  const Eigen::Index n = 37, stride = 40;
  std::vector<T> inputs(static_cast<std::size_t>(3 * stride));
  for (Eigen::Index p = 0; p < n; ++p) {
    inputs[p] = static_cast<T>(ux(rng));
    inputs[p + stride] = static_cast<T>(uy(rng));
  }
  std::vector<T> scratch, out(n);
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.text);
    const CompiledExpression e(c.text, xyz_scope());
    e.evaluate<T>(n, inputs.data(), stride, out.data(), scratch);
    for (Eigen::Index p = 0; p < n; ++p) {
      const T x = inputs[p], y = inputs[p + stride];
      T want;
      if constexpr (std::is_same_v<T, double>) want = c.in_double(x, y);
      else want = c.in_float(x, y);
      EXPECT_NEAR(out[p], want, tolerance * std::max<T>(1, std::abs(want))) << "x " << x << " y " << y;
      const T row[3] = {x, y, 0};
      EXPECT_EQ(e.evaluate<T>(row, scratch), out[p]);  // one point = the same block entry
    }
  }
}

TEST(CompiledExpression, EveryOperatorAndFunctionInDouble) {
  check_cases<double>(4 * std::numeric_limits<double>::epsilon());
}

TEST(CompiledExpression, EveryOperatorAndFunctionInFloat) {
  check_cases<float>(4 * std::numeric_limits<float>::epsilon());
}

TEST(CompiledExpression, NumbersConstantsAndPrecedence) {
  struct Literal {
    const char* text;
    double value;
  };
  const double pi = std::numbers::pi;
  const Literal literals[] = {
      {"2^3^2", 512},         {"-2^2", -4},          {"2^-1", 0.5},        {"1e-3 + 2e1", 20.001},
      {"2*e", 2 * std::numbers::e},                  {".5", 0.5},          {"3.", 3},
      {"2.5E+2", 250},        {"1 - 2 + 3", 2},      {"12 / 4 / 3", 1},    {"2 * (3 + 4)", 14},
      {"0.01/pi", 0.01 / pi}, {"pi", pi},            {"--3", 3},           {" 7 ", 7},
      {"nu * 2", 0.02},       {"pow(2, 10)", 1024},  {"min(3, -1)", -1},   {"max(3, -1)", 3},
  };
  ExpressionScope scope;
  scope.constants = {{"nu", 0.01}, {"mu", 2}};
  EXPECT_EQ(CompiledExpression("nu * 2 + nu - pi", scope).constants_read(), std::vector<std::string>{"nu"});
  std::vector<double> scratch;
  for (const Literal& l : literals) {
    SCOPED_TRACE(l.text);
    const CompiledExpression e(l.text, scope);
    EXPECT_TRUE(e.is_constant());
    ASSERT_EQ(e.tape().size(), 1u);  // folded
    EXPECT_DOUBLE_EQ(e.evaluate<double>(nullptr, scratch), l.value);
  }
}

TEST(CompiledExpression, FoldsConstantSubtreesAndReportsReads) {
  const CompiledExpression e("2*pi^2*sin(pi*x)*sin(pi*y) + z - z", xyz_scope());
  // 2π² and π fold; the rest: x, π·x, sin, ·, y, π·y, sin, ·, z, +, z, −, with the constants.
  for (const auto& in : e.tape())
    if (in.op == CompiledExpression::Op::kPow || in.op == CompiledExpression::Op::kPowConst)
      ADD_FAILURE() << "a power of constants was not folded";
  EXPECT_EQ(e.reads(), (std::vector<int>{0, 1, 2}));
  ASSERT_EQ(e.symbols().size(), 3u);
  EXPECT_EQ(e.symbols()[0].name, "x");
  EXPECT_EQ(e.symbols()[0].position, 14u);
  EXPECT_EQ(e.symbols()[2].name, "z");
  EXPECT_EQ(e.row_size(), 3);
  const double row[3] = {0.25, 0.5, 9};
  std::vector<double> scratch;
  const double pi = std::numbers::pi;
  EXPECT_NEAR(e.evaluate<double>(row, scratch), 2 * pi * pi * std::sin(pi * 0.25), 1e-13);
  // An integer power is repeated multiplication: exact where pow need not be.
  const CompiledExpression cube("x^3", xyz_scope());
  const double third[3] = {1.0 / 3.0, 0, 0};
  EXPECT_EQ(cube.evaluate<double>(third, scratch), third[0] * third[0] * third[0]);
  EXPECT_EQ(cube.tape().back().op, CompiledExpression::Op::kPowInt);
}

// A random smooth expression over x, y, z (no abs, min, max: their kinks), well defined
// everywhere (logs and roots of positive arguments, divisions by 2 + sin).
std::string random_expression(std::mt19937& rng, int depth) {
  std::uniform_int_distribution<int> pick(0, depth <= 0 ? 3 : 17);
  std::uniform_real_distribution<double> number(-2, 2);
  const char* vars[] = {"x", "y", "z"};
  auto sub = [&] { return random_expression(rng, depth - 1); };
  switch (pick(rng)) {
    case 0: case 1: case 2: return vars[std::uniform_int_distribution<int>(0, 2)(rng)];
    case 3: return std::to_string(number(rng));
    case 4: return "(" + sub() + " + " + sub() + ")";
    case 5: return "(" + sub() + " - " + sub() + ")";
    case 6: return sub() + " * " + sub();
    case 7: return "(" + sub() + ") / (2 + sin(" + sub() + "))";
    case 8: return "(" + sub() + ")^2";
    case 9: return "(" + sub() + ")^3";
    case 10: return "sin(" + sub() + ")";
    case 11: return "cos(" + sub() + ")";
    case 12: return "exp(0.3 * tanh(" + sub() + "))";
    case 13: return "log(1 + (" + sub() + ")^2)";
    case 14: return "sqrt(1.5 + cos(" + sub() + "))";
    case 15: return "atan(" + sub() + ") + sinh(0.5*cos(" + sub() + "))";
    case 16: return "pow(1.2 + sin(" + sub() + "), 0.7) * cosh(0.3*" + sub() + ")";
    default: return "-" + sub() + " + tan(0.4*sin(" + sub() + "))";
  }
}

TEST(CompiledExpression, JetDerivativesMatchCentralDifferences) {
  using Jet = ceres::Jet<double, 3>;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  std::vector<double> scratch;
  std::vector<Jet> jet_scratch;
  for (int trial = 0; trial < 200; ++trial) {
    const std::string text = random_expression(rng, 4);
    SCOPED_TRACE(text);
    const CompiledExpression e(text, xyz_scope());
    double row[3] = {coordinate(rng), coordinate(rng), coordinate(rng)};
    Jet jets[3];
    for (int i = 0; i < 3; ++i) jets[i] = Jet(row[i], i);
    const Jet value = e.evaluate<Jet>(jets, jet_scratch);
    EXPECT_NEAR(value.a, e.evaluate<double>(row, scratch), 1e-13 * std::max(1.0, std::abs(value.a)));
    // With x fixed (from a double pass), the derivatives in y and z are the same, in x 0.
    e.evaluate<double>(row, scratch);
    const Jet partial = e.evaluate_varying<Jet>(jets, e.varying_from(1), scratch.data(), 1, jet_scratch);
    EXPECT_EQ(partial.a, value.a);
    EXPECT_EQ(partial.v[0], 0.0);
    EXPECT_EQ(partial.v[1], value.v[1]);
    EXPECT_EQ(partial.v[2], value.v[2]);
    for (int i = 0; i < 3; ++i) {
      const double h = 1e-5, saved = row[i];
      row[i] = saved + h;
      const double up = e.evaluate<double>(row, scratch);
      row[i] = saved - h;
      const double down = e.evaluate<double>(row, scratch);
      row[i] = saved;
      const double difference = (up - down) / (2 * h);
      EXPECT_NEAR(value.v[i], difference, 1e-6 * std::max(1.0, std::abs(difference))) << "d/d slot " << i;
    }
  }
}

// atan2(y, x) in every quadrant, across the branch cut at x < 0 from either side, and its
// Jet derivatives (−y, x)/(x² + y²) against central differences.
TEST(CompiledExpression, Atan2ValueAndDerivatives) {
  using Jet = ceres::Jet<double, 2>;
  const CompiledExpression e("atan2(y, x)", xyz_scope());
  std::vector<double> scratch;
  std::vector<Jet> jet_scratch;
  const double points[][2] = {{1, 0.5}, {-1, 0.5}, {-1, -0.5}, {0.3, -2}, {-1, 1e-12}, {-1, -1e-12}, {0, 1}};
  for (const auto& p : points) {
    SCOPED_TRACE(std::to_string(p[0]) + ", " + std::to_string(p[1]));
    double row[3] = {p[0], p[1], 0};
    EXPECT_EQ(e.evaluate<double>(row, scratch), std::atan2(p[1], p[0]));
    Jet jets[3] = {Jet(p[0], 0), Jet(p[1], 1), Jet(0.0)};
    const Jet value = e.evaluate<Jet>(jets, jet_scratch);
    EXPECT_EQ(value.a, std::atan2(p[1], p[0]));
    const double r2 = p[0] * p[0] + p[1] * p[1];
    EXPECT_NEAR(value.v[0], -p[1] / r2, 1e-15);
    EXPECT_NEAR(value.v[1], p[0] / r2, 1e-15);
    if (p[0] < 0 && std::abs(p[1]) < 1e-6) continue;  // central differences straddle the cut
    for (int i = 0; i < 2; ++i) {
      const double h = 1e-6, saved = row[i];
      row[i] = saved + h;
      const double up = e.evaluate<double>(row, scratch);
      row[i] = saved - h;
      const double down = e.evaluate<double>(row, scratch);
      row[i] = saved;
      EXPECT_NEAR(value.v[i], (up - down) / (2 * h), 1e-8) << "d/d slot " << i;
    }
  }
  // The cut: just above it the angle is near π, just below near −π.
  EXPECT_NEAR(e.evaluate<double>(std::array<double, 3>{-1, 1e-12, 0}.data(), scratch), std::numbers::pi, 1e-11);
  EXPECT_NEAR(e.evaluate<double>(std::array<double, 3>{-1, -1e-12, 0}.data(), scratch), -std::numbers::pi, 1e-11);
}

// The error's position and a part of its message.
void expect_error(const std::string& text, std::size_t position, const std::string& part,
                  const ExpressionScope& scope = xyz_scope()) {
  SCOPED_TRACE(text);
  try {
    CompiledExpression e(text, scope);
    ADD_FAILURE() << "no error";
  } catch (const ExpressionError& e) {
    EXPECT_EQ(e.position(), position) << e.what();
    EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
    EXPECT_EQ(e.expression(), text);
  }
}

TEST(CompiledExpression, ErrorsNameTheirPosition) {
  expect_error("sin(x", 5, "expected ')'");
  expect_error("x + q", 4, "unknown symbol 'q' (valid: x, y, z, pi, e)");
  expect_error("2 +", 3, "unexpected end");
  expect_error("", 0, "empty expression");
  expect_error("foo(x)", 0, "unknown function 'foo' (functions: sin, cos");
  expect_error("1 + sin(x, y)", 4, "sin takes 1 argument, got 2");
  expect_error("max(x)", 0, "max takes 2 arguments, got 1");
  expect_error("x $ y", 2, "unexpected '$'");
  expect_error("2x", 1, "unexpected 'x'");
  expect_error("exp + 1", 0, "needs its argument in parentheses");
  expect_error("(x + y", 6, "expected ')'");
  expect_error("x)", 1, "unexpected ')'");
  ExpressionScope listed = xyz_scope();
  listed.valid_names = "variables: x, y, z";
  expect_error("w", 0, "unknown symbol 'w' (variables: x, y, z)", listed);
}

// Names beyond the listed slots through `resolve`, and `name(arg)` as one name.
TEST(CompiledExpression, ResolvedNamesAndAppliedNames) {
  ExpressionScope scope = xyz_scope();
  std::vector<std::string> resolved;
  scope.resolve = [&](std::string_view name) -> std::optional<int> {
    if (name == "lap(u)" || name == "u_xx") {
      const auto at = std::find(resolved.begin(), resolved.end(), name);
      if (at != resolved.end()) return 3 + static_cast<int>(at - resolved.begin());
      resolved.emplace_back(name);
      return 2 + static_cast<int>(resolved.size());
    }
    if (name == "u_q") throw std::invalid_argument("the domain has no variable 'q'");
    if (name.starts_with("lap(")) throw std::invalid_argument("lap of an unknown output");
    return std::nullopt;
  };
  const CompiledExpression e("lap( u ) - u_xx * x + lap(u)", scope);
  ASSERT_EQ(e.symbols().size(), 3u);
  EXPECT_EQ(e.symbols()[0].name, "lap(u)");
  EXPECT_EQ(e.symbols()[0].slot, 3);
  EXPECT_EQ(e.symbols()[1].name, "u_xx");
  EXPECT_EQ(e.symbols()[1].slot, 4);
  EXPECT_EQ(e.reads(), (std::vector<int>{0, 3, 4}));
  const double row[5] = {2, 0, 0, 10, 3};
  std::vector<double> scratch;
  EXPECT_EQ(e.evaluate<double>(row, scratch), 10 - 3 * 2 + 10);
  expect_error("1 + u_q", 4, "the domain has no variable 'q'", scope);
  expect_error("lap(v)", 0, "lap of an unknown output", scope);
  expect_error("grad(u)", 0, "unknown function 'grad'", scope);
}

// Constant-coefficient sums of names one group holds become one read of the slot `fold`
// gives; the test's fold returns slot 6 and records the (name, coefficient) list, and the
// row gives slot 6 a value of its own (9) that tells which was read. Slots: x 0, c 1
// (a slot, so no constant), u_tt 3, u_xx 4, v_xx 5.
TEST(CompiledExpression, FoldsConstantCoefficientSums) {
  ExpressionScope scope;
  scope.slots = {{"x", 0}, {"c", 1}, {"u_tt", 3}, {"u_xx", 4}, {"v_xx", 5}};
  scope.constants = {{"k", 2.0}};
  scope.fold_group = [](std::string_view name) -> std::optional<std::string> {
    if (name == "u_tt" || name == "u_xx") return "u";
    if (name == "v_xx") return "v";
    return std::nullopt;
  };
  std::vector<std::pair<std::string, double>> folded;
  scope.fold = [&folded](const std::vector<std::pair<std::string, double>>& terms) -> std::optional<int> {
    folded = terms;
    return 6;
  };
  const double row[7] = {0.5, 3, 0, 2, 3, 5, 9};
  std::vector<double> scratch;
  struct Folded {
    const char* text;
    double value;
    std::vector<int> reads;
    std::vector<std::pair<std::string, double>> terms;  // what fold was given; empty: not called
  };
  using T = std::vector<std::pair<std::string, double>>;
  const Folded cases[] = {
      {"u_tt - k^2*u_xx", 9, {6}, T{{"u_tt", 1}, {"u_xx", -4}}},
      {"x - (2*u_tt + u_xx/4)", 0.5 - 9, {0, 6}, T{{"u_tt", 2}, {"u_xx", 0.25}}},
      {"-u_tt + k*u_xx + x", -9 + 0.5, {0, 6}, T{{"u_tt", 1}, {"u_xx", -2}}},  // the first place keeps its −
      {"u_tt - c*u_xx", 2 - 9, {1, 3, 4}, T{}},                               // c varies: no fold
      {"u_tt - u_xx + u_xx*x", 2 - 3 + 1.5, {0, 3, 4}, T{}},                  // u_xx read twice
      {"u_tt + v_xx", 7, {3, 5}, T{}},                                        // two groups of one
      {"u_tt + 0*u_xx", 2, {3, 4}, T{}},                                       // a zero coefficient
  };
  for (const Folded& c : cases) {
    SCOPED_TRACE(c.text);
    folded.clear();
    const CompiledExpression e(c.text, scope);
    EXPECT_DOUBLE_EQ(e.evaluate<double>(row, scratch), c.value);
    EXPECT_EQ(e.reads(), c.reads);
    EXPECT_EQ(folded, c.terms);
  }
  EXPECT_EQ(CompiledExpression("u_tt - k^2*u_xx", scope).symbols()[0].name, "u_tt - 4*u_xx");
}

// u_xx + u_yy read as lap(u) where the sum is whole, of one sign, and its terms read nowhere
// else; slots: x 0, u_xx 3, u_yy 4, lap(u) 5.
TEST(CompiledExpression, SumAliases) {
  ExpressionScope scope;
  scope.slots = {{"x", 0}, {"u_xx", 3}, {"u_yy", 4}};
  scope.resolve = [](std::string_view name) -> std::optional<int> {
    if (name == "lap(u)") return 5;
    return std::nullopt;
  };
  scope.sum_aliases = {{{"u_xx", "u_yy"}, "lap(u)"}};
  const double row[6] = {0.5, 0, 0, 2, 3, 7};  // lap(u) = 7 ≠ 2 + 3: tells which was read
  std::vector<double> scratch;
  struct Aliased {
    const char* text;
    double value;
    std::vector<int> reads;
  };
  const Aliased cases[] = {
      {"u_xx + u_yy", 7, {5}},
      {"2 - (u_xx + u_yy)", -5, {5}},
      {"-u_xx - u_yy + x", -6.5, {0, 5}},
      {"u_yy + x + u_xx", 7.5, {0, 5}},
      {"sin(u_xx + u_yy)", std::sin(7.0), {5}},
      {"u_xx + u_yy + u_xx*x", 6, {0, 3, 4}},  // u_xx read twice
      {"u_xx - u_yy", -1, {3, 4}},          // two signs
      {"u_xx*2 + u_yy", 7, {3, 4}},         // not a bare term
      {"u_xx", 2, {3}},
  };
  for (const Aliased& c : cases) {
    SCOPED_TRACE(c.text);
    const CompiledExpression e(c.text, scope);
    EXPECT_DOUBLE_EQ(e.evaluate<double>(row, scratch), c.value);
    EXPECT_EQ(e.reads(), c.reads);
  }
  CompiledExpression moved("x + u_xx + u_yy", scope);
  EXPECT_EQ(moved.symbols()[1].name, "lap(u)");
  EXPECT_EQ(moved.symbols()[1].position, 4u);
  moved.remap_slots({1, -1, -1, -1, -1, 0});
  const double swapped[2] = {7, 0.5};
  EXPECT_DOUBLE_EQ(moved.evaluate<double>(swapped, scratch), 7.5);
  EXPECT_EQ(moved.reads(), (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace nfield::io
