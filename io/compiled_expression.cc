// SPDX-License-Identifier: MIT
#include "io/compiled_expression.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

namespace nfield::io {
namespace {

using Op = CompiledExpression::Op;
using Instruction = CompiledExpression::Instruction;

struct Function {
  const char* name;
  Op op;
  int arity;
};
constexpr Function kFunctions[] = {
    {"sin", Op::kSin, 1},   {"cos", Op::kCos, 1},   {"tan", Op::kTan, 1},   {"exp", Op::kExp, 1},
    {"log", Op::kLog, 1},   {"sqrt", Op::kSqrt, 1}, {"abs", Op::kAbs, 1},   {"tanh", Op::kTanh, 1},
    {"sinh", Op::kSinh, 1}, {"cosh", Op::kCosh, 1}, {"atan", Op::kAtan, 1}, {"min", Op::kMin, 2},
    {"max", Op::kMax, 2},   {"pow", Op::kPow, 2},   {"atan2", Op::kAtan2, 2},
};

const Function* find_function(std::string_view name) {
  for (const Function& f : kFunctions)
    if (name == f.name) return &f;
  return nullptr;
}

bool identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// A tree node: an operation on its children, a constant or a slot.
struct Node {
  Op op = Op::kConst;
  std::vector<int> children;
  double value = 0;
  int slot = 0;
  int symbol = -1;  // kSlot: index into Parser::symbols()
};

// Recursive descent over the grammar
//   sum     := product (('+' | '-') product)*
//   product := unary (('*' | '/') unary)*
//   unary   := ('-' | '+') unary | power
//   power   := primary ('^' unary)?             (right-associative through unary)
//   primary := number | name | name '(' sum (',' sum)* ')' | '(' sum ')'
class Parser {
 public:
  Parser(const std::string& text, const ExpressionScope& scope) : text_(text), scope_(scope) {}

  int parse() {
    const int root = sum();
    skip_space();
    if (at_ < text_.size()) fail(at_, "unexpected '" + std::string(1, text_[at_]) + "'");
    return root;
  }
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<SymbolUse>& symbols() const { return symbols_; }
  const std::vector<std::string>& constants_read() const { return constants_read_; }

 private:
  [[noreturn]] void fail(std::size_t position, const std::string& reason) const {
    throw ExpressionError(text_, position, reason);
  }
  void skip_space() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  }
  bool accept(char c) {
    skip_space();
    if (at_ < text_.size() && text_[at_] == c) {
      ++at_;
      return true;
    }
    return false;
  }
  int add(Node node) {
    nodes_.push_back(std::move(node));
    return static_cast<int>(nodes_.size()) - 1;
  }
  int binary(Op op, int a, int b) { return add(Node{op, {a, b}}); }

  int sum() {
    int left = product();
    for (;;) {
      if (accept('+')) left = binary(Op::kAdd, left, product());
      else if (accept('-')) left = binary(Op::kSub, left, product());
      else return left;
    }
  }
  int product() {
    int left = unary();
    for (;;) {
      if (accept('*')) left = binary(Op::kMul, left, unary());
      else if (accept('/')) left = binary(Op::kDiv, left, unary());
      else return left;
    }
  }
  int unary() {
    if (accept('-')) return add(Node{Op::kNeg, {unary()}});
    if (accept('+')) return unary();
    return power();
  }
  int power() {
    const int base = primary();
    if (accept('^')) return binary(Op::kPow, base, unary());
    return base;
  }

  int primary() {
    skip_space();
    if (at_ >= text_.size()) fail(at_, text_.empty() ? "empty expression" : "unexpected end of expression");
    const char c = text_[at_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (identifier_start(c)) return name();
    if (accept('(')) {
      const int inner = sum();
      if (!accept(')')) fail(at_, "expected ')'");
      return inner;
    }
    fail(at_, "unexpected '" + std::string(1, c) + "'");
  }

  int number() {
    const std::size_t start = at_;
    while (at_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[at_]))) ++at_;
    if (at_ < text_.size() && text_[at_] == '.') ++at_;
    while (at_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[at_]))) ++at_;
    if (at_ == start + 1 && text_[start] == '.') fail(start, "expected a number");
    // An exponent only when digits follow: `2e` is 2 followed by the name e.
    if (at_ < text_.size() && (text_[at_] == 'e' || text_[at_] == 'E')) {
      std::size_t k = at_ + 1;
      if (k < text_.size() && (text_[k] == '+' || text_[k] == '-')) ++k;
      if (k < text_.size() && std::isdigit(static_cast<unsigned char>(text_[k]))) {
        at_ = k;
        while (at_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[at_]))) ++at_;
      }
    }
    const std::string digits = text_.substr(start, at_ - start);
    return add(Node{Op::kConst, {}, std::strtod(digits.c_str(), nullptr)});
  }

  int name() {
    const std::size_t start = at_;
    while (at_ < text_.size() && identifier_char(text_[at_])) ++at_;
    const std::string id = text_.substr(start, at_ - start);
    const std::size_t after = at_;
    skip_space();
    if (at_ < text_.size() && text_[at_] == '(') {
      if (const Function* f = find_function(id)) return call(*f, start);
      if (std::optional<std::string> symbol = applied_name(id)) return lookup(*symbol, start, true);
      fail(start, "unknown function '" + id + "' (functions: " + function_names() + ")");
    }
    at_ = after;
    if (find_function(id)) fail(start, "function '" + id + "' needs its argument in parentheses");
    return lookup(id, start, false);
  }

  // `name(arg)` with a bare name as the argument, as the one name "name(arg)" when the scope
  // knows it; the parser stays at the '(' otherwise.
  std::optional<std::string> applied_name(const std::string& id) {
    const std::size_t open = at_;
    ++at_;
    skip_space();
    const std::size_t arg_start = at_;
    while (at_ < text_.size() && identifier_char(text_[at_])) ++at_;
    const std::string arg = text_.substr(arg_start, at_ - arg_start);
    if (!arg.empty() && identifier_start(arg[0]) && accept(')')) {
      const std::string symbol = id + "(" + arg + ")";
      if (known(symbol)) return symbol;
    }
    at_ = open;
    return std::nullopt;
  }

  bool known(const std::string& symbol) const {
    for (const auto& [n, slot] : scope_.slots)
      if (n == symbol) return true;
    if (!scope_.resolve) return false;
    try {
      return scope_.resolve(symbol).has_value();
    } catch (const std::invalid_argument&) {
      return true;  // known, with an error that lookup reports
    }
  }

  int call(const Function& f, std::size_t start) {
    accept('(');
    std::vector<int> args{sum()};
    while (accept(',')) args.push_back(sum());
    if (!accept(')')) fail(at_, "expected ')' or ','");
    if (static_cast<int>(args.size()) != f.arity)
      fail(start, std::string(f.name) + " takes " + std::to_string(f.arity) + " argument" +
                      (f.arity == 1 ? "" : "s") + ", got " + std::to_string(args.size()));
    return add(Node{f.op, args});
  }

  int lookup(const std::string& id, std::size_t start, bool applied) {
    if (!applied && id == "pi") return add(Node{Op::kConst, {}, std::numbers::pi});
    if (!applied && id == "e") return add(Node{Op::kConst, {}, std::numbers::e});
    std::optional<int> slot;
    for (const auto& [n, s] : scope_.slots)
      if (n == id) slot = s;
    if (!slot)
      for (const auto& [n, v] : scope_.constants)
        if (n == id) {
          if (std::find(constants_read_.begin(), constants_read_.end(), id) == constants_read_.end())
            constants_read_.push_back(id);
          return add(Node{Op::kConst, {}, v});
        }
    if (!slot && scope_.resolve) {
      try {
        slot = scope_.resolve(id);
      } catch (const std::invalid_argument& e) {
        fail(start, e.what());
      }
    }
    if (!slot) fail(start, "unknown symbol '" + id + "' (" + valid_names() + ")");
    return slot_node(id, *slot, start);
  }

 public:
  // A node reading `slot` as the symbol `id`.
  int slot_node(const std::string& id, int slot, std::size_t start) {
    auto seen = std::find_if(symbols_.begin(), symbols_.end(), [&](const SymbolUse& s) { return s.name == id; });
    if (seen == symbols_.end()) seen = symbols_.insert(symbols_.end(), {id, slot, start});
    return add(Node{Op::kSlot, {}, 0, slot, static_cast<int>(seen - symbols_.begin())});
  }
  // The slot of a name the scope lists or resolves; nullopt when it does not.
  std::optional<int> slot_for(const std::string& id) const {
    for (const auto& [n, s] : scope_.slots)
      if (n == id) return s;
    if (!scope_.resolve) return std::nullopt;
    try {
      return scope_.resolve(id);
    } catch (const std::invalid_argument&) {
      return std::nullopt;
    }
  }
  std::vector<Node>& nodes() { return nodes_; }
  std::vector<SymbolUse>& symbols() { return symbols_; }

 private:
  std::string valid_names() const {
    if (!scope_.valid_names.empty()) return scope_.valid_names;
    std::string out;
    for (const auto& [n, s] : scope_.slots) out += (out.empty() ? "" : ", ") + n;
    for (const auto& [n, v] : scope_.constants) out += (out.empty() ? "" : ", ") + n;
    return "valid: " + (out.empty() ? std::string("none") : out) + ", pi, e";
  }
  static std::string function_names() {
    std::string out;
    for (const Function& f : kFunctions) out += (out.empty() ? "" : ", ") + std::string(f.name);
    return out;
  }

  const std::string& text_;
  const ExpressionScope& scope_;
  std::size_t at_ = 0;
  std::vector<Node> nodes_;
  std::vector<SymbolUse> symbols_;
  std::vector<std::string> constants_read_;
};

// The terms of a chain of + and − (through unary −) with their signs.
void flatten(const std::vector<Node>& nodes, int index, int sign, std::vector<std::pair<int, int>>& terms) {
  const Node& node = nodes[static_cast<std::size_t>(index)];
  if (node.op == Op::kAdd || node.op == Op::kSub) {
    flatten(nodes, node.children[0], sign, terms);
    flatten(nodes, node.children[1], node.op == Op::kSub ? -sign : sign, terms);
  } else if (node.op == Op::kNeg) {
    flatten(nodes, node.children[0], -sign, terms);
  } else {
    terms.emplace_back(index, sign);
  }
}

// Replaces the terms of one alias in a chain when all are there, with one sign, and read
// nowhere else: the first becomes the alias, the others 0 (dropped when compiled).
void replace_alias(Parser& parser, const std::vector<std::pair<int, int>>& terms, const SumAlias& alias,
                   const std::vector<int>& uses) {
  std::vector<Node>& nodes = parser.nodes();
  std::vector<int> found;
  int sign = 0;
  for (const std::string& name : alias.terms) {
    const auto term = std::find_if(terms.begin(), terms.end(), [&](const std::pair<int, int>& t) {
      const Node& n = nodes[static_cast<std::size_t>(t.first)];
      return n.op == Op::kSlot && n.symbol >= 0 && parser.symbols()[static_cast<std::size_t>(n.symbol)].name == name;
    });
    if (term == terms.end()) return;
    const int symbol = nodes[static_cast<std::size_t>(term->first)].symbol;
    if (uses[static_cast<std::size_t>(symbol)] != 1 || (sign != 0 && term->second != sign)) return;
    sign = term->second;
    found.push_back(term->first);
  }
  const std::optional<int> slot = parser.slot_for(alias.name);
  if (found.empty() || !slot) return;
  const std::size_t position = parser.symbols()[static_cast<std::size_t>(nodes[static_cast<std::size_t>(found[0])].symbol)].position;
  const int replacement = parser.slot_node(alias.name, *slot, position);
  nodes[static_cast<std::size_t>(found[0])] = nodes[static_cast<std::size_t>(replacement)];
  for (std::size_t k = 1; k < found.size(); ++k) nodes[static_cast<std::size_t>(found[k])] = Node{Op::kConst, {}, 0.0};
}

// Counts the reads of each symbol below `index` into `uses`.
void count_uses(const std::vector<Node>& nodes, int index, std::vector<int>& uses) {
  const Node& node = nodes[static_cast<std::size_t>(index)];
  if (node.op == Op::kSlot && node.symbol >= 0) ++uses[static_cast<std::size_t>(node.symbol)];
  for (int child : node.children) count_uses(nodes, child, uses);
}

// Applies the scope's sum aliases to every chain of + and − below `index` (`root`: the whole
// expression, where a term must be read only once).
void apply_aliases(Parser& parser, int index, int root, const ExpressionScope& scope) {
  const Node node = parser.nodes()[static_cast<std::size_t>(index)];
  if (node.op != Op::kAdd && node.op != Op::kSub) {
    for (int child : node.children) apply_aliases(parser, child, root, scope);
    return;
  }
  std::vector<std::pair<int, int>> terms;
  flatten(parser.nodes(), index, 1, terms);
  for (const SumAlias& alias : scope.sum_aliases) {
    std::vector<int> uses(parser.symbols().size(), 0);
    count_uses(parser.nodes(), root, uses);
    replace_alias(parser, terms, alias, uses);
  }
  for (const auto& [term, sign] : terms) apply_aliases(parser, term, root, scope);
}

// The value of a subtree that reads no slot; nullopt when it reads one.
std::optional<double> constant_value(const std::vector<Node>& nodes, int index) {
  const Node& node = nodes[static_cast<std::size_t>(index)];
  if (node.op == Op::kConst) return node.value;
  if (node.op == Op::kSlot) return std::nullopt;
  const std::optional<double> a = constant_value(nodes, node.children[0]);
  if (!a) return std::nullopt;
  const std::optional<double> b = node.children.size() > 1 ? constant_value(nodes, node.children[1]) : a;
  if (!b) return std::nullopt;
  return CompiledExpression::apply<double>({node.op, 0, node.children.size() > 1 ? 1 : -1, 0, 0}, *a, *b);
}

// A term c·name (through *, / by a constant and unary −) as (symbol, c); nullopt otherwise.
std::optional<std::pair<int, double>> linear_term(const std::vector<Node>& nodes, int index) {
  const Node& node = nodes[static_cast<std::size_t>(index)];
  std::optional<std::pair<int, double>> inner;
  double factor = 1;
  if (node.op == Op::kSlot) return node.symbol >= 0 ? std::optional(std::pair{node.symbol, 1.0}) : std::nullopt;
  if (node.op == Op::kNeg) {
    inner = linear_term(nodes, node.children[0]);
    factor = -1;
  } else if (node.op == Op::kAdd || node.op == Op::kSub) {  // x ± 0, what an alias leaves
    const std::optional<double> left = constant_value(nodes, node.children[0]);
    const std::optional<double> right = constant_value(nodes, node.children[1]);
    if (right == 0.0) inner = linear_term(nodes, node.children[0]);
    else if (left == 0.0) inner = linear_term(nodes, node.children[1]);
    factor = left == 0.0 && node.op == Op::kSub ? -1 : 1;
  } else if (node.op == Op::kMul || node.op == Op::kDiv) {
    const std::optional<double> right = constant_value(nodes, node.children[1]);
    if (right) {
      inner = linear_term(nodes, node.children[0]);
      factor = node.op == Op::kMul ? *right : 1.0 / *right;
    } else if (node.op == Op::kMul) {
      const std::optional<double> left = constant_value(nodes, node.children[0]);
      if (left) inner = linear_term(nodes, node.children[1]);
      factor = left.value_or(0);
    }
  }
  if (!inner) return std::nullopt;
  return std::pair{inner->first, inner->second * factor};
}

// "u_tt - 4*u_xx": the name of a folded sum, for symbols() and messages.
std::string folded_name(const std::vector<std::pair<std::string, double>>& terms) {
  std::string out;
  for (const auto& [name, c] : terms) {
    const double magnitude = std::abs(c);
    out += out.empty() ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ");
    if (magnitude != 1) {
      char buffer[32];
      std::snprintf(buffer, sizeof buffer, "%.17g*", magnitude);
      out += buffer;
    }
    out += name;
  }
  return out;
}

// Folds the groups of one chain's terms (see ExpressionScope::fold); `uses`: each symbol's
// reads in the whole expression.
void fold_chain(Parser& parser, const std::vector<std::pair<int, int>>& terms, const std::vector<int>& uses,
                const ExpressionScope& scope) {
  std::vector<Node>& nodes = parser.nodes();
  std::vector<std::string> groups;
  std::vector<std::vector<std::pair<int, double>>> members;  // per group: (term node, signed coefficient)
  for (const auto& [index, sign] : terms) {
    const std::optional<std::pair<int, double>> term = linear_term(nodes, index);
    if (!term || uses[static_cast<std::size_t>(term->first)] != 1 || !std::isfinite(term->second) || term->second == 0)
      continue;
    const std::optional<std::string> group = scope.fold_group(parser.symbols()[static_cast<std::size_t>(term->first)].name);
    if (!group) continue;
    const auto at = std::find(groups.begin(), groups.end(), *group);
    if (at == groups.end()) {
      groups.push_back(*group);
      members.emplace_back();
    }
    members[static_cast<std::size_t>(std::find(groups.begin(), groups.end(), *group) - groups.begin())].emplace_back(
        index, sign * term->second);
  }
  for (const auto& group : members) {
    if (group.size() < 2) continue;
    // The first term's place keeps its chain sign s: the folded name reads s · Σ sign_i c_i name_i.
    const int first_chain_sign = std::find_if(terms.begin(), terms.end(), [&](const std::pair<int, int>& t) {
                                   return t.first == group[0].first;
                                 })->second;
    std::vector<std::pair<std::string, double>> weighted;
    for (const auto& [index, c] : group)
      weighted.emplace_back(parser.symbols()[static_cast<std::size_t>(linear_term(nodes, index)->first)].name,
                            c * first_chain_sign);
    const std::optional<int> slot = scope.fold(weighted);
    if (!slot) continue;
    const int first_symbol = linear_term(nodes, group[0].first)->first;
    const std::size_t position = parser.symbols()[static_cast<std::size_t>(first_symbol)].position;
    const int replacement = parser.slot_node(folded_name(weighted), *slot, position);
    nodes[static_cast<std::size_t>(group[0].first)] = nodes[static_cast<std::size_t>(replacement)];
    for (std::size_t k = 1; k < group.size(); ++k)
      nodes[static_cast<std::size_t>(group[k].first)] = Node{Op::kConst, {}, 0.0};
  }
}

// Folds every chain of + and − below `index` (`root`: the whole expression).
void apply_folds(Parser& parser, int index, int root, const ExpressionScope& scope) {
  const Node node = parser.nodes()[static_cast<std::size_t>(index)];
  if (node.op != Op::kAdd && node.op != Op::kSub) {
    for (int child : node.children) apply_folds(parser, child, root, scope);
    return;
  }
  std::vector<std::pair<int, int>> terms;
  flatten(parser.nodes(), index, 1, terms);
  std::vector<int> uses(parser.symbols().size(), 0);
  count_uses(parser.nodes(), root, uses);
  fold_chain(parser, terms, uses, scope);
  for (const auto& [term, sign] : terms) apply_folds(parser, term, root, scope);
}

// Emits the tree below `node` onto the tape, folding constant subtrees; returns the register
// holding its value.
class Compiler {
 public:
  explicit Compiler(const std::vector<Node>& nodes) : nodes_(nodes) {}
  std::vector<Instruction> take() { return std::move(tape_); }

  int emit(int index) {
    const Node& node = nodes_[static_cast<std::size_t>(index)];
    if (node.op == Op::kConst) return constant(node.value);
    if (node.op == Op::kSlot) return push({Op::kSlot, -1, -1, node.slot, 0});
    const int a = emit(node.children[0]);
    const int b = node.children.size() > 1 ? emit(node.children[1]) : -1;
    if (node.op == Op::kPow && tape_[static_cast<std::size_t>(b)].op == Op::kConst) {
      const double exponent = tape_[static_cast<std::size_t>(b)].value;
      tape_.pop_back();  // the exponent's constant, emitted last
      if (exponent == std::round(exponent) && std::abs(exponent) <= 64)
        return fold_or_push({Op::kPowInt, a, -1, static_cast<int>(exponent), 0});
      return fold_or_push({Op::kPowConst, a, -1, 0, exponent});
    }
    if ((node.op == Op::kAdd || node.op == Op::kSub) && tape_.back().op == Op::kConst && tape_.back().value == 0 &&
        tape_[static_cast<std::size_t>(a)].op != Op::kConst) {
      tape_.pop_back();  // x ± 0, what an alias leaves
      return a;
    }
    return fold_or_push({node.op, a, b, 0, 0});
  }

 private:
  int push(Instruction in) {
    tape_.push_back(in);
    return static_cast<int>(tape_.size()) - 1;
  }
  int constant(double value) { return push({Op::kConst, -1, -1, 0, value}); }

  // An instruction whose operands are all constants becomes one constant (the operands,
  // the last registers emitted, are dropped).
  int fold_or_push(Instruction in) {
    const bool a_const = tape_[static_cast<std::size_t>(in.a)].op == Op::kConst;
    const bool b_const = in.b < 0 || tape_[static_cast<std::size_t>(in.b)].op == Op::kConst;
    if (!a_const || !b_const) return push(in);
    const double a = tape_[static_cast<std::size_t>(in.a)].value;
    const double b = in.b < 0 ? a : tape_[static_cast<std::size_t>(in.b)].value;
    const double value = CompiledExpression::apply<double>(in, a, b);
    tape_.resize(static_cast<std::size_t>(std::min(in.a, in.b < 0 ? in.a : in.b)));
    return constant(value);
  }

  const std::vector<Node>& nodes_;
  std::vector<Instruction> tape_;
};

}  // namespace

CompiledExpression::CompiledExpression(std::string text, const ExpressionScope& scope)
    : text_(std::move(text)) {
  Parser parser(text_, scope);
  const int root = parser.parse();
  if (!scope.sum_aliases.empty()) apply_aliases(parser, root, root, scope);
  if (scope.fold_group && scope.fold) apply_folds(parser, root, root, scope);
  Compiler compiler(parser.nodes());
  compiler.emit(root);
  tape_ = compiler.take();
  // The symbols the tape still reads, in order of first appearance.
  for (const Instruction& in : tape_)
    if (in.op == Op::kSlot)
      for (const SymbolUse& s : parser.symbols())
        if (s.slot == in.slot && std::none_of(symbols_.begin(), symbols_.end(), [&](const SymbolUse& u) { return u.name == s.name; }))
          symbols_.push_back(s);
  std::stable_sort(symbols_.begin(), symbols_.end(),
                   [](const SymbolUse& a, const SymbolUse& b) { return a.position < b.position; });
  constants_read_ = parser.constants_read();
}

std::vector<char> CompiledExpression::varying_from(int first_slot) const {
  std::vector<char> varying(tape_.size(), 0);
  for (std::size_t k = 0; k < tape_.size(); ++k) {
    const Instruction& in = tape_[k];
    if (in.op == Op::kSlot) varying[k] = in.slot >= first_slot;
    else if (in.op != Op::kConst)
      varying[k] = varying[static_cast<std::size_t>(in.a)] || (in.b >= 0 && varying[static_cast<std::size_t>(in.b)]);
  }
  return varying;
}

void CompiledExpression::remap_slots(const std::vector<int>& new_slot) {
  for (Instruction& in : tape_)
    if (in.op == Op::kSlot) in.slot = new_slot.at(static_cast<std::size_t>(in.slot));
  for (SymbolUse& s : symbols_) s.slot = new_slot.at(static_cast<std::size_t>(s.slot));
}

std::vector<int> CompiledExpression::reads() const {
  std::vector<int> slots;
  for (const SymbolUse& s : symbols_) slots.push_back(s.slot);
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  return slots;
}

int CompiledExpression::row_size() const {
  int size = 0;
  for (const SymbolUse& s : symbols_) size = std::max(size, s.slot + 1);
  return size;
}

}  // namespace nfield::io
