// SPDX-License-Identifier: MIT
#include "io/expression.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <numbers>
#include <set>
#include <stdexcept>
#include <utility>

#include <muParser.h>

#include "io/compiled_expression.h"

namespace nfield::io {
namespace {

double step(double x) { return x >= 0.0 ? 1.0 : 0.0; }
double power(double base, double exponent) { return std::pow(base, exponent); }
// Bessel functions of the first kind, J0 and J1 (the radial modes of a disk); J0' = −J1.
double bessel_j0(double x) { return std::cyl_bessel_j(0.0, std::abs(x)); }
double bessel_j1(double x) { return x < 0 ? -std::cyl_bessel_j(1.0, -x) : std::cyl_bessel_j(1.0, x); }

bool is_identifier(std::string_view name) {
  auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  return !name.empty() && alpha(name.front()) &&
         std::all_of(name.begin(), name.end(), [&](char c) { return alpha(c) || digit(c); });
}

std::size_t error_position(const mu::ParserError& e) {
  return e.GetPos() < 0 ? std::string::npos : static_cast<std::size_t>(e.GetPos());
}

// A muparser instance bound to its own variable storage. Parsers are not thread-safe
// (Eval mutates internal stacks), so each concurrent evaluate borrows one.
struct Evaluator {
  mu::Parser parser;
  std::vector<double> values;
  std::vector<double> constants;  // bound as variables, so that muparser reports their use
};

// ExpressionTiming's state: set while one lives.
std::atomic<bool> interpreter_only{false};
std::atomic<bool> counting{false};
std::atomic<long long> counted_nanoseconds{0};

// Points per pass of the tape: its registers (block × tape doubles) stay in L1/L2.
constexpr Eigen::Index kBlock = 256;

// The compiled form of `text` over the variables (slot i: variable i) and constants, or
// nullopt when the tape's language lacks something the text uses (comparisons, `c ? a : b`,
// sign, log10, besselj0, …): muparser evaluates those.
std::optional<CompiledExpression> compile(const std::string& text, const std::vector<std::string>& variables,
                                          const ExpressionConstants& constants) {
  ExpressionScope scope;
  for (std::size_t i = 0; i < variables.size(); ++i) scope.slots.emplace_back(variables[i], static_cast<int>(i));
  scope.constants = constants;
  try {
    return CompiledExpression(text, scope);
  } catch (const ExpressionError&) {
    return std::nullopt;
  }
}

// The tape over the rows of `points` in blocks of kBlock. Columns the points lack read 0:
// a block of them is copied into `row_block` with zeros beyond.
void evaluate_blocks(const CompiledExpression& compiled, const Eigen::Ref<const Eigen::MatrixXd>& points,
                     Eigen::VectorXd& result) {
  const Eigen::Index n = points.rows();
  const Eigen::Index width = compiled.row_size();
  std::vector<double> scratch;
  if (points.cols() >= width) {
    for (Eigen::Index start = 0; start < n; start += kBlock)
      compiled.evaluate<double>(std::min(kBlock, n - start), points.data() + start, points.outerStride(),
                                result.data() + start, scratch);
    return;
  }
  Eigen::MatrixXd row_block = Eigen::MatrixXd::Zero(std::min(kBlock, n), width);
  for (Eigen::Index start = 0; start < n; start += kBlock) {
    const Eigen::Index m = std::min(kBlock, n - start);
    row_block.topLeftCorner(m, points.cols()) = points.middleRows(start, m);
    compiled.evaluate<double>(m, row_block.data(), row_block.rows(), result.data() + start, scratch);
  }
}

// Adds the time from its construction to its end to counted_nanoseconds, when counting.
class EvaluationTimer {
 public:
  EvaluationTimer() : on_(counting.load(std::memory_order_relaxed)) {
    if (on_) start_ = std::chrono::steady_clock::now();
  }
  ~EvaluationTimer() {
    if (on_)
      counted_nanoseconds.fetch_add(
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start_).count(),
          std::memory_order_relaxed);
  }
  EvaluationTimer(const EvaluationTimer&) = delete;
  EvaluationTimer& operator=(const EvaluationTimer&) = delete;

 private:
  bool on_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

ExpressionError::ExpressionError(std::string expression, std::size_t position,
                                 std::string reason)
    : std::runtime_error("in expression '" + expression + "': " + reason),
      expression_(std::move(expression)),
      position_(position),
      reason_(std::move(reason)) {}

struct Expression::Shared {
  std::string text;
  std::vector<std::string> variables;
  ExpressionConstants constants;
  std::vector<bool> used;
  std::vector<std::string> constants_used;
  std::optional<CompiledExpression> compiled;  // nullopt: muparser only
  std::mutex mutex;
  std::vector<std::unique_ptr<Evaluator>> idle;

  std::unique_ptr<Evaluator> make_evaluator() const {
    auto evaluator = std::make_unique<Evaluator>();
    evaluator->values.assign(variables.size(), 0.0);
    mu::Parser& parser = evaluator->parser;
    try {
      parser.DefineConst("pi", std::numbers::pi);
      parser.DefineConst("e", std::numbers::e);
      parser.DefineFun("pow", power);
      parser.DefineFun("heaviside", step);
      parser.DefineFun("step", step);
      parser.DefineFun("besselj0", bessel_j0);
      parser.DefineFun("besselj1", bessel_j1);
      for (std::size_t i = 0; i < variables.size(); ++i)
        parser.DefineVar(variables[i], &evaluator->values[i]);
      evaluator->constants.resize(constants.size());
      for (std::size_t i = 0; i < constants.size(); ++i) {
        evaluator->constants[i] = constants[i].second;
        parser.DefineVar(constants[i].first, &evaluator->constants[i]);
      }
      parser.SetExpr(text);
      parser.Eval();  // compiles to bytecode; reports syntax errors and unknown names
    } catch (const mu::ParserError& e) {
      throw ExpressionError(text, error_position(e), e.GetMsg());
    }
    if (parser.GetNumResults() != 1)
      throw ExpressionError(text, std::string::npos,
                            "expected a single expression, got " +
                                std::to_string(parser.GetNumResults()) +
                                " separated by commas");
    return evaluator;
  }

  std::unique_ptr<Evaluator> borrow() {
    {
      std::lock_guard lock(mutex);
      if (!idle.empty()) {
        auto evaluator = std::move(idle.back());
        idle.pop_back();
        return evaluator;
      }
    }
    return make_evaluator();
  }

  void give_back(std::unique_ptr<Evaluator> evaluator) noexcept {
    try {
      std::lock_guard lock(mutex);
      idle.push_back(std::move(evaluator));
    } catch (...) {  // out of memory: let this evaluator go
    }
  }

  // Returns a borrowed evaluator to the pool even when evaluation throws.
  class Lease {
   public:
    explicit Lease(Shared& shared) : shared_(shared), evaluator_(shared.borrow()) {}
    ~Lease() { shared_.give_back(std::move(evaluator_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Evaluator& operator*() { return *evaluator_; }

   private:
    Shared& shared_;
    std::unique_ptr<Evaluator> evaluator_;
  };
};

Expression::Expression(std::string text, std::vector<std::string> variables, ExpressionConstants constants)
    : shared_(std::make_shared<Shared>()) {
  std::set<std::string_view> seen;
  auto check = [&](const std::string& name) {
    if (!is_identifier(name))
      throw ExpressionError(text, std::string::npos, "invalid variable name '" + name + "'");
    if (!seen.insert(name).second)
      throw ExpressionError(text, std::string::npos, "variable '" + name + "' listed twice");
  };
  for (const std::string& name : variables) check(name);
  for (const auto& constant : constants) check(constant.first);
  shared_->text = std::move(text);
  shared_->variables = std::move(variables);
  shared_->constants = std::move(constants);
  auto evaluator = shared_->make_evaluator();
  const mu::varmap_type& used = evaluator->parser.GetUsedVar();
  for (const std::string& name : shared_->variables)
    shared_->used.push_back(used.count(name) > 0);
  for (const auto& constant : shared_->constants)
    if (used.count(constant.first) > 0) shared_->constants_used.push_back(constant.first);
  shared_->give_back(std::move(evaluator));
  shared_->compiled = compile(shared_->text, shared_->variables, shared_->constants);
}

void Expression::check_columns(Eigen::Index columns) const {
  if (static_cast<std::size_t>(columns) > shared_->variables.size())
    throw std::invalid_argument("expression '" + shared_->text + "' has " +
                                std::to_string(shared_->variables.size()) +
                                " variables, got points with " + std::to_string(columns) +
                                " columns");
}

Eigen::VectorXd Expression::evaluate(const Eigen::Ref<const Eigen::MatrixXd>& points) const {
  if (!shared_->compiled || interpreter_only.load(std::memory_order_relaxed)) return evaluate_interpreted(points);
  check_columns(points.cols());
  Eigen::VectorXd result(points.rows());
  if (points.rows() == 0) return result;
  const EvaluationTimer timer;
  evaluate_blocks(*shared_->compiled, points, result);
  return result;
}

Eigen::VectorXd Expression::evaluate_interpreted(const Eigen::Ref<const Eigen::MatrixXd>& points) const {
  check_columns(points.cols());
  const auto columns = static_cast<std::size_t>(points.cols());
  Eigen::VectorXd result(points.rows());
  if (points.rows() == 0) return result;
  const EvaluationTimer timer;
  Shared::Lease lease(*shared_);
  Evaluator& evaluator = *lease;
  std::fill(evaluator.values.begin(), evaluator.values.end(), 0.0);
  try {
    for (Eigen::Index row = 0; row < points.rows(); ++row) {
      for (std::size_t col = 0; col < columns; ++col)
        evaluator.values[col] = points(row, static_cast<Eigen::Index>(col));
      result[row] = evaluator.parser.Eval();
    }
  } catch (const mu::ParserError& e) {
    throw ExpressionError(shared_->text, error_position(e), e.GetMsg());
  }
  return result;
}

double Expression::evaluate(std::span<const double> point) const {
  return evaluate(Eigen::Map<const Eigen::RowVectorXd>(point.data(),
                                                       static_cast<Eigen::Index>(point.size())))[0];
}

bool Expression::uses(std::string_view variable) const {
  for (std::size_t i = 0; i < shared_->variables.size(); ++i)
    if (shared_->variables[i] == variable) return shared_->used[i];
  return false;
}

bool Expression::is_constant() const {
  return std::none_of(shared_->used.begin(), shared_->used.end(), [](bool b) { return b; });
}

std::vector<std::string> Expression::constants_used() const { return shared_->constants_used; }

bool Expression::compiled() const { return shared_->compiled.has_value(); }

ExpressionTiming::ExpressionTiming(bool interpreted) {
  if (counting.exchange(true, std::memory_order_relaxed))
    throw std::logic_error("ExpressionTiming: another one is alive");
  counted_nanoseconds.store(0, std::memory_order_relaxed);
  interpreter_only.store(interpreted, std::memory_order_relaxed);
}

ExpressionTiming::~ExpressionTiming() {
  interpreter_only.store(false, std::memory_order_relaxed);
  counting.store(false, std::memory_order_relaxed);
}

double ExpressionTiming::seconds() const {
  return 1e-9 * static_cast<double>(counted_nanoseconds.load(std::memory_order_relaxed));
}

const std::string& Expression::text() const { return shared_->text; }
const std::vector<std::string>& Expression::variables() const { return shared_->variables; }

}  // namespace nfield::io
