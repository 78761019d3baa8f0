// SPDX-License-Identifier: MIT
//
// Expressions compiled once to a flat tape and evaluated in any scalar type: double and
// float over blocks of points, ceres::Jet<double, N> for derivatives with respect to the
// inputs (a residual's adjoint), with no parsing or name look-up after construction.
//
// The language:
//
//   numbers      2, 0.5, .5, 1e-3, 2.5E+2;   constants pi, e
//   names        what the caller's scope maps to a slot of the input row, or to a constant
//                (folded into the tape); `name(arg)` with a bare name as argument, when
//                `name` is no function, is looked up as the one name "name(arg)" (lap(u))
//   operators    + − * / ^ and unary ±, with the usual precedence; ^ binds tighter than
//                unary minus and to the right: −x^2 = −(x²), 2^3^2 = 2⁹ = 512
//   functions    sin cos tan exp log sqrt abs tanh sinh cosh atan (one argument),
//                min max pow atan2 (two; atan2(y, x) is the angle of (x, y) in (−π, π],
//                with derivatives (x, −y)/(x² + y²) in Jet: infinite at the origin)
//
// The tape. Parsing builds a tree, which is compiled bottom-up into SSA instructions
// (instruction k writes register k and reads earlier registers): a subtree that reads no
// slot is folded into one constant in double (0.01/pi, 2*pi^2), and a power whose exponent
// is a constant integer k, |k| ≤ 64, becomes repeated multiplication (x^2 = x·x exactly,
// and a Jet needs no log of a negative base); another constant exponent calls pow(x, c).
// evaluate runs the tape instruction by instruction over a block of points, each
// instruction one loop over the block (registers: block × tape doubles of scratch), so the
// dispatch costs once per block, not per point. A Jet is evaluated with a block of one.
//
// Scalars. The instructions are templates calling functions unqualified after
// `using std::sin;` etc., so that ceres::Jet's overloads are found by ADL; constants enter
// as T(c) (derivative 0) and are rounded to T once per evaluation. Pitfalls in Jet, where
// the derivative is not the one a reader expects: abs has derivative ±1 at 0 (Ceres'
// copysign), sqrt at 0 an infinite one, min and max the branch taken (they compare values).
//
// Errors are io::ExpressionError with the 0-based position of the offending character (a
// config reader turns it into a file column, io::ConfigNode::expression_error) and a
// message listing what is valid: `unknown symbol 'u_xq' (outputs: u; variables: x, t)`.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "io/expression_error.h"

namespace nfield::io {

// A sum the caller reads as one name: u_xx + u_yy as lap(u), one stream instead of two.
struct SumAlias {
  std::vector<std::string> terms;
  std::string name;
};

// What the names of an expression mean. Names are matched in this order: the slots, the
// constants, then `resolve` (for names too many to list, such as derivative symbols). A
// name none of them knows is an error listing `valid_names`.
struct ExpressionScope {
  std::vector<std::pair<std::string, int>> slots;         // name → column of the input row
  std::vector<std::pair<std::string, double>> constants;  // folded into the tape
  // A slot for a name not listed above, or nullopt when the name is unknown. It may throw
  // std::invalid_argument saying why a name that looks valid is not (`u_z`: no variable z);
  // the message is reported at the name's position. It may be called more than once per
  // name, and for names the expression ends up not reading (a `name(arg)` probe, a term an
  // alias replaced): give the same slot each time, and take the slots read from symbols().
  std::function<std::optional<int>(std::string_view name)> resolve;
  // What an unknown-name error lists; empty: the slot and constant names.
  std::string valid_names;
  // Where a chain of + and − (through unary −) has every term of an alias as a bare name,
  // all with one sign, and those names are read nowhere else in the expression, they become
  // the alias's name (resolved as any name) with that sign: `2 - (u_xx + u_yy)` reads
  // lap(u), `u_xx + u_yy + u_xx*u` or `u_xx - u_yy` stays as written.
  std::vector<SumAlias> sum_aliases;
  // Constant-coefficient sums read as one name: where a chain of + and − (after the aliases)
  // has two or more terms `c·name` (c a constant subtree: `c^2*u_xx`, `u_xx/4`, `-u_tt`) whose
  // names `fold_group` puts in one group, each read nowhere else and each c finite and
  // nonzero, they become one read of the slot `fold` gives for their (name, signed
  // coefficient) list: u_tt − c²u_xx as one weighted second-derivative stream. The first
  // term's place reads the new name; the others read 0. Either callback unset: no folding.
  std::function<std::optional<std::string>(std::string_view name)> fold_group;
  std::function<std::optional<int>(const std::vector<std::pair<std::string, double>>& terms)> fold;
};

// One name an expression reads through a slot, in order of first appearance.
struct SymbolUse {
  std::string name;
  int slot = 0;
  std::size_t position = 0;  // 0-based, of its first appearance
};

class CompiledExpression {
 public:
  enum class Op : std::uint8_t {
    kConst, kSlot, kNeg, kAdd, kSub, kMul, kDiv, kPowInt, kPowConst, kPow, kMin, kMax,
    kSin, kCos, kTan, kExp, kLog, kSqrt, kAbs, kTanh, kSinh, kCosh, kAtan, kAtan2,
  };
  struct Instruction {
    Op op = Op::kConst;
    int a = -1, b = -1;  // registers read
    int slot = 0;        // kSlot: the input column; kPowInt: the exponent
    double value = 0;    // kConst: the value; kPowConst: the exponent
  };

  CompiledExpression() : CompiledExpression("0", {}) {}
  // Parses and compiles `text`; throws ExpressionError.
  CompiledExpression(std::string text, const ExpressionScope& scope);

  // Values at n points. Input slot s of point p is inputs[p + s · stride] (a column-major
  // n × slots block with leading dimension `stride` ≥ n); out[p] receives the value.
  // `scratch` is resized to n × tape().size() (reuse it across calls).
  template <typename T>
  void evaluate(Eigen::Index n, const T* inputs, Eigen::Index stride, T* out, std::vector<T>& scratch) const;
  // One point: row[s] is slot s.
  template <typename T>
  T evaluate(const T* row, std::vector<T>& scratch) const {
    T value;
    evaluate<T>(1, row, 1, &value, scratch);
    return value;
  }

  // Per instruction, whether it depends on a slot ≥ first_slot. The others are fixed while
  // only those slots vary: a pass in Jet over the symbols of a residual can take them from a
  // pass in double (evaluate_varying) instead of recomputing a source term's sines in Jet.
  std::vector<char> varying_from(int first_slot) const;
  // One point in T, with the instructions that are not `varying` read as T(fixed[k · stride])
  // for instruction k (the registers of an evaluate<double> over a block: its scratch, offset
  // to the point, stride the block's size).
  template <typename T>
  T evaluate_varying(const T* row, const std::vector<char>& varying, const double* fixed, Eigen::Index stride,
                     std::vector<T>& scratch) const;

  const std::string& text() const { return text_; }
  // The names read through slots (after aliases), in order of first appearance; a name the
  // scope resolved that an alias replaced is not among them.
  const std::vector<SymbolUse>& symbols() const { return symbols_; }
  // Moves every slot s the tape reads to new_slot[s] (a caller compacting its slots).
  void remap_slots(const std::vector<int>& new_slot);
  // The scope's constants it reads (folded into the tape), in order of first appearance.
  const std::vector<std::string>& constants_read() const { return constants_read_; }
  // Sorted distinct slots the expression reads (after folding: x − x still reads x).
  std::vector<int> reads() const;
  bool is_constant() const { return symbols_.empty(); }
  // One past the largest slot read (0 when none): the row length evaluate needs.
  int row_size() const;
  const std::vector<Instruction>& tape() const { return tape_; }

  // The scalar rule of one instruction on register values (used by evaluate and by the
  // constant folding in double).
  template <typename T>
  static T apply(const Instruction& in, const T& a, const T& b);

 private:
  std::string text_;
  std::vector<Instruction> tape_;
  std::vector<SymbolUse> symbols_;
  std::vector<std::string> constants_read_;
};

// x^k by repeated squaring: exact for small k in double, and no log(x) in a Jet.
template <typename T>
T power_integer(const T& x, int k) {
  if (k < 0) return T(1.0) / power_integer(x, -k);
  T result(1.0), base = x;
  bool first = true;
  while (k > 0) {
    if (k & 1) {
      result = first ? base : T(result * base);
      first = false;
    }
    k >>= 1;
    if (k > 0) base = base * base;
  }
  return result;
}

template <typename T>
T CompiledExpression::apply(const Instruction& in, const T& a, const T& b) {
  using std::abs, std::atan, std::atan2, std::cos, std::cosh, std::exp, std::log, std::pow, std::sin,
      std::sinh, std::sqrt, std::tan, std::tanh;
  switch (in.op) {
    case Op::kConst: return T(in.value);
    case Op::kSlot: return a;  // not reached: evaluate copies slots itself
    case Op::kNeg: return -a;
    case Op::kAdd: return a + b;
    case Op::kSub: return a - b;
    case Op::kMul: return a * b;
    case Op::kDiv: return a / b;
    case Op::kPowInt: return power_integer(a, in.slot);
    case Op::kPowConst:
      if constexpr (std::is_floating_point_v<T>) return pow(a, static_cast<T>(in.value));
      else return pow(a, in.value);
    case Op::kPow: return pow(a, b);
    case Op::kMin: return b < a ? b : a;
    case Op::kMax: return a < b ? b : a;
    case Op::kSin: return sin(a);
    case Op::kCos: return cos(a);
    case Op::kTan: return tan(a);
    case Op::kExp: return exp(a);
    case Op::kLog: return log(a);
    case Op::kSqrt: return sqrt(a);
    case Op::kAbs: return abs(a);
    case Op::kTanh: return tanh(a);
    case Op::kSinh: return sinh(a);
    case Op::kCosh: return cosh(a);
    case Op::kAtan: return atan(a);
    case Op::kAtan2: return atan2(a, b);
  }
  return a;
}

template <typename T>
void CompiledExpression::evaluate(Eigen::Index n, const T* inputs, Eigen::Index stride, T* out,
                                  std::vector<T>& scratch) const {
  const auto registers = static_cast<Eigen::Index>(tape_.size());
  if (static_cast<Eigen::Index>(scratch.size()) < n * registers)
    scratch.resize(static_cast<std::size_t>(n * registers));
  T* r = scratch.data();
  for (Eigen::Index k = 0; k < registers; ++k) {
    const Instruction& in = tape_[static_cast<std::size_t>(k)];
    T* y = r + k * n;
    if (in.op == Op::kSlot) {
      for (Eigen::Index p = 0; p < n; ++p) y[p] = inputs[p + in.slot * stride];
    } else if (in.op == Op::kConst) {
      const T c(in.value);
      for (Eigen::Index p = 0; p < n; ++p) y[p] = c;
    } else if (in.b < 0) {
      const T* a = r + in.a * n;
      for (Eigen::Index p = 0; p < n; ++p) y[p] = apply<T>(in, a[p], a[p]);
    } else {
      const T* a = r + in.a * n;
      const T* b = r + in.b * n;
      for (Eigen::Index p = 0; p < n; ++p) y[p] = apply<T>(in, a[p], b[p]);
    }
  }
  const T* last = r + (registers - 1) * n;
  for (Eigen::Index p = 0; p < n; ++p) out[p] = last[p];
}

template <typename T>
T CompiledExpression::evaluate_varying(const T* row, const std::vector<char>& varying, const double* fixed,
                                       Eigen::Index stride, std::vector<T>& scratch) const {
  const std::size_t registers = tape_.size();
  if (scratch.size() < registers) scratch.resize(registers);
  for (std::size_t k = 0; k < registers; ++k) {
    const Instruction& in = tape_[k];
    if (!varying[k]) scratch[k] = T(fixed[static_cast<Eigen::Index>(k) * stride]);
    else if (in.op == Op::kSlot) scratch[k] = row[in.slot];
    else scratch[k] = apply<T>(in, scratch[static_cast<std::size_t>(in.a)], scratch[static_cast<std::size_t>(in.b < 0 ? in.a : in.b)]);
  }
  return scratch[registers - 1];
}

}  // namespace nfield::io
