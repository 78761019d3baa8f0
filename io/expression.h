// SPDX-License-Identifier: MIT
#pragma once
// Math expressions from config files, such as `2*pi^2*sin(pi*x)*sin(pi*y)`, evaluated
// over batches of points: condition values, sources, exact solutions.
//
// Available: + - * / ^ (power), comparisons, `c ? a : b`; constants pi and e;
// functions sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp log (natural)
// log2 log10 sqrt abs sign atan2(y, x) pow(a, b) min max sum avg, and
// heaviside(x) = step(x) = (x >= 0 ? 1 : 0), besselj0(x) and besselj1(x) (J0 and J1, the
// Bessel functions of the first kind, through std::cyl_bessel_j).
//
//   Expression source("2*pi^2*sin(pi*x)*sin(pi*y)");      // variables x, y, z, t
//   Eigen::VectorXd f = source.evaluate(points);           // points: n x 2 -> z = t = 0
//
// Two evaluators, one class. muparser parses every text (its messages and positions are the
// ones a config error reports, and it tells which variables a text uses). Where the text is
// also in the language of io::CompiledExpression (+ − * / ^, unary ±, sin cos tan exp log
// sqrt abs tanh sinh cosh atan min max pow atan2, pi, e, the constants), evaluate runs that
// tape instead, over blocks of 256 points: one pass per instruction over the block rather
// than one bytecode interpretation per point (issue 29 item 4; figures in docs/experiments.md,
// 2026-11-26, `nfield bench --expressions`). The rest (comparisons, `c ? a : b`, sign, asin,
// log10, sum, besselj0, min of three, …) stays with muparser; compiled() tells which.
//
// The two agree to rounding, not always to the last bit. The tape folds constant subtrees
// and computes a constant integer power k (|k| ≤ 64) by repeated squaring, where muparser
// calls pow for a power of anything but a bare variable and folds its own patterns
// ((3*x + 1)*2 as 6*x + 2). So (x + 1)^3 or x^4 may differ in the last bit or two; sums,
// products, quotients, x^2, x^3 and the functions (the same libm calls) do not.
//
// Thread safety: evaluate may be called on the same Expression (or copies of it) from
// many threads at once. The compiled form is read-only and each call has its own scratch;
// a muparser evaluation borrows a private muparser instance from a pool owned by the
// expression, so no locking happens while evaluating. evaluate itself is serial;
// parallelise over batches in the caller.

#include <cstddef>
#include <memory>
#include <span>
#include <stdexcept>
#include <utility>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "io/expression_error.h"

namespace nfield::io {

class Expression {
 public:
  // Parses `text` (checked here: errors throw ExpressionError) over the named variables.
  // A variable may not be named like a constant or function (`e`, `pi`, `exp`, ...).
  // `constants` are named numbers, named like no variable.
  explicit Expression(std::string text,
                      std::vector<std::string> variables = {"x", "y", "z", "t"},
                      ExpressionConstants constants = {});

  // One value per row of `points`; column j holds variable j. Missing trailing columns
  // are 0 (a 2-D point sets x and y, with z = t = 0); more columns than variables is
  // std::invalid_argument. Division by zero and the like give inf/nan, not errors.
  // Pitfall: an Eigen::Vector2d is two points of one column; pass a single point as a
  // row (p.transpose()) or through the span overload.
  Eigen::VectorXd evaluate(const Eigen::Ref<const Eigen::MatrixXd>& points) const;
  // One point (variables in order, missing ones 0).
  double evaluate(std::span<const double> point) const;
  // evaluate through muparser, point by point, even where the compiled form exists (tests
  // and benchmarks compare the two).
  Eigen::VectorXd evaluate_interpreted(const Eigen::Ref<const Eigen::MatrixXd>& points) const;
  // Whether evaluate runs the compiled tape (false: the text needs muparser).
  bool compiled() const;

  // Whether the expression mentions `variable` (e.g. `t` to tell time dependence).
  bool uses(std::string_view variable) const;
  // True if the expression mentions none of its variables (constants do not count).
  bool is_constant() const;
  // The names of `constants` it reads.
  std::vector<std::string> constants_used() const;
  const std::string& text() const;
  const std::vector<std::string>& variables() const;

 private:
  void check_columns(Eigen::Index columns) const;
  struct Shared;
  std::shared_ptr<Shared> shared_;
};

// Benchmarks and tests only: while one lives, every Expression::evaluate in the process runs
// through muparser (interpreted) or, where the text allows, the compiled form (not
// interpreted), and the wall time of each evaluate is summed. Process-wide because the
// expressions being timed sit deep inside a problem's conditions and sources, where no
// option reaches; hence a scope rather than switches: one at a time (a second while one lives
// is std::logic_error), and its end restores the default (compiled, no clock reads).
class ExpressionTiming {
 public:
  explicit ExpressionTiming(bool interpreted);
  ~ExpressionTiming();
  ExpressionTiming(const ExpressionTiming&) = delete;
  ExpressionTiming& operator=(const ExpressionTiming&) = delete;
  // Wall seconds of evaluate calls since this scope began.
  double seconds() const;
};

}  // namespace nfield::io
