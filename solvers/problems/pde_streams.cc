// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_streams.h"
#include "io/text.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <stdexcept>

namespace nfield::solvers {
namespace {

int index_of(const std::vector<std::string>& names, std::string_view name) {
  const auto at = std::find(names.begin(), names.end(), name);
  return at == names.end() ? -1 : static_cast<int>(at - names.begin());
}

// `lap(u)` / `bilap(u)`.
std::optional<DerivativeSymbol> operator_symbol(std::string_view name, const std::vector<std::string>& outputs,
                                                int space_dim) {
  for (const auto& [prefix, kind] : {std::pair{std::string_view("lap("), DerivativeSymbol::Kind::kLaplacian},
                                     std::pair{std::string_view("bilap("), DerivativeSymbol::Kind::kBilaplacian}}) {
    if (!name.starts_with(prefix) || !name.ends_with(")")) continue;
    const std::string_view argument = name.substr(prefix.size(), name.size() - prefix.size() - 1);
    const int output = index_of(outputs, argument);
    if (output < 0)
      throw std::invalid_argument(std::string(name) + ": '" + std::string(argument) +
                                  "' is no output (outputs: " + io::join(outputs) + ")");
    if (space_dim < 1) throw std::invalid_argument(std::string(name) + ": the domain has no space axes");
    DerivativeSymbol symbol;
    symbol.kind = kind;
    symbol.output = output;
    return symbol;
  }
  return std::nullopt;
}

// Canonical integer direction: w / (±gcd), first nonzero entry positive; returns the scale s
// with w = s · w'.
int canonical(std::vector<int>& w) {
  int g = 0;
  for (int v : w) g = std::gcd(g, v < 0 ? -v : v);
  const auto first = std::find_if(w.begin(), w.end(), [](int v) { return v != 0; });
  const int scale = *first < 0 ? -g : g;
  for (int& v : w) v /= scale;
  return scale;
}

int power(int base, int k) {
  int p = 1;
  for (int i = 0; i < k; ++i) p *= base;
  return p;
}

// ∂^α u as Σ coefficient · a_{w,k} over canonical integer directions w (polarization).
std::map<std::vector<int>, double> polarization(const std::vector<int>& axes, int input_dim) {
  const int k = static_cast<int>(axes.size());
  std::map<std::vector<int>, double> out;
  for (int subset = 1; subset < (1 << k); ++subset) {
    std::vector<int> w(static_cast<std::size_t>(input_dim), 0);
    int size = 0;
    for (int i = 0; i < k; ++i)
      if (subset & (1 << i)) {
        ++w[static_cast<std::size_t>(axes[static_cast<std::size_t>(i)])];
        ++size;
      }
    const int scale = canonical(w);
    out[w] += ((k - size) % 2 ? -1.0 : 1.0) * power(scale, k);
  }
  for (auto it = out.begin(); it != out.end();) it = it->second == 0 ? out.erase(it) : std::next(it);
  return out;
}

// Δ²u over the first space_dim axes as Σ coefficient · a_{w,4}.
std::map<std::vector<int>, double> bilaplacian(int space_dim, int input_dim) {
  std::map<std::vector<int>, double> out;
  for (int a = 0; a < space_dim; ++a)
    for (int b = a; b < space_dim; ++b)
      for (const auto& [w, c] : polarization({a, a, b, b}, input_dim)) out[w] += (a == b ? 1.0 : 2.0) * c;
  return out;
}

// Symbol s as stream entries: its tangent (`tangent`, first order), its operator stream
// (`op`), or its Taylor coefficients (`taylor` over `directions`; the 2D bilaplacian's three
// directions follow the integer ones).
std::vector<SymbolTerm> symbol_terms(const autodiff::StreamLayout& layout, const DerivativeSymbol& s, int space_dim,
                                     int tangent, int op, const std::map<std::vector<int>, double>& taylor,
                                     const std::vector<std::vector<int>>& directions) {
  std::vector<SymbolTerm> terms;
  if (s.order() == 0) {
    terms.push_back({autodiff::StreamLayout::value(), s.output, 1.0});
  } else if (s.kind == DerivativeSymbol::Kind::kPartial && s.order() == 1) {
    terms.push_back({layout.tangent(tangent), s.output, 1.0});
  } else if (op >= 0) {
    terms.push_back({layout.op(op), s.output, 1.0});
  } else if (s.kind == DerivativeSymbol::Kind::kBilaplacian && space_dim == 2) {
    for (int p = 0; p < 3; ++p)
      terms.push_back({layout.taylor(static_cast<int>(directions.size()) + p, 4), s.output, autodiff::kBiharmonic2dWeight});
  } else {
    for (const auto& [w, c] : taylor) {
      const auto p = static_cast<int>(std::find(directions.begin(), directions.end(), w) - directions.begin());
      terms.push_back({layout.taylor(p, s.order()), s.output, c});
    }
  }
  return terms;
}

}  // namespace

int DerivativeSymbol::order() const {
  switch (kind) {
    case Kind::kLaplacian:
    case Kind::kWeighted: return 2;
    case Kind::kBilaplacian: return 4;
    case Kind::kPartial: break;
  }
  return static_cast<int>(axes.size());
}

std::optional<DerivativeSymbol> parse_derivative_symbol(std::string_view name,
                                                        const std::vector<std::string>& outputs,
                                                        const std::vector<std::string>& inputs,
                                                        int space_dim) {
  if (std::optional<DerivativeSymbol> op = operator_symbol(name, outputs, space_dim)) return op;
  DerivativeSymbol symbol;
  const std::size_t underscore = name.find('_');
  symbol.output = index_of(outputs, name.substr(0, underscore));
  if (symbol.output < 0) return std::nullopt;
  if (underscore == std::string_view::npos) return symbol;  // the value
  const std::string_view suffix = name.substr(underscore + 1);
  for (char c : suffix) {
    const int axis = index_of(inputs, std::string(1, c));
    if (axis >= 0) {
      symbol.axes.push_back(axis);
      continue;
    }
    if (c == 'x' || c == 'y' || c == 'z' || c == 't')
      throw std::invalid_argument(std::string(name) + ": the domain has no variable '" + std::string(1, c) +
                                  "' (variables: " + io::join(inputs) + ")");
    return std::nullopt;  // not a derivative symbol: an unknown name
  }
  if (symbol.axes.empty()) return std::nullopt;
  if (symbol.order() > kMaxDerivativeOrder)
    throw std::invalid_argument(std::string(name) + ": derivatives go up to order " +
                                std::to_string(kMaxDerivativeOrder) + ", this one is of order " +
                                std::to_string(symbol.order()));
  std::sort(symbol.axes.begin(), symbol.axes.end());
  return symbol;
}

std::optional<DerivativeSymbol> weighted_second_derivative(const std::vector<std::pair<DerivativeSymbol, double>>& terms,
                                                           int input_dim, int space_dim) {
  using Kind = DerivativeSymbol::Kind;
  if (terms.empty()) return std::nullopt;
  DerivativeSymbol out;
  out.kind = Kind::kWeighted;
  out.output = terms[0].first.output;
  out.weights.assign(static_cast<std::size_t>(input_dim * input_dim), 0.0);
  auto add = [&](int a, int b, double c) {
    out.weights[static_cast<std::size_t>(a * input_dim + b)] += c;
  };
  for (const auto& [s, c] : terms) {
    if (s.output != out.output || s.order() != 2 || s.kind == Kind::kBilaplacian) return std::nullopt;
    if (s.kind == Kind::kLaplacian) {
      for (int a = 0; a < space_dim; ++a) add(a, a, c);
    } else if (s.kind == Kind::kPartial) {
      add(s.axes[0], s.axes[1], 0.5 * c);
      add(s.axes[1], s.axes[0], 0.5 * c);
    } else {
      for (std::size_t k = 0; k < out.weights.size(); ++k) out.weights[k] += c * s.weights[k];
    }
  }
  return out;
}

void set_second_derivative_folds(io::ExpressionScope& scope, const std::vector<std::string>& outputs,
                                 const std::vector<std::string>& inputs, int space_dim,
                                 std::function<int(const DerivativeSymbol&)> slot_of) {
  const auto second = [outputs, inputs, space_dim](std::string_view name) -> std::optional<DerivativeSymbol> {
    try {
      std::optional<DerivativeSymbol> s = parse_derivative_symbol(name, outputs, inputs, space_dim);
      if (s && s->order() == 2 && (s->kind == DerivativeSymbol::Kind::kPartial || s->kind == DerivativeSymbol::Kind::kLaplacian))
        return s;
    } catch (const std::invalid_argument&) {
    }
    return std::nullopt;
  };
  scope.fold_group = [second, outputs](std::string_view name) -> std::optional<std::string> {
    const std::optional<DerivativeSymbol> s = second(name);
    if (!s) return std::nullopt;
    return outputs[static_cast<std::size_t>(s->output)];
  };
  const int input_dim = static_cast<int>(inputs.size());
  scope.fold = [second, input_dim, space_dim, slot_of = std::move(slot_of)](
                   const std::vector<std::pair<std::string, double>>& terms) -> std::optional<int> {
    std::vector<std::pair<DerivativeSymbol, double>> symbols;
    for (const auto& [name, c] : terms) {
      std::optional<DerivativeSymbol> s = second(name);
      if (!s) return std::nullopt;
      symbols.emplace_back(std::move(*s), c);
    }
    const std::optional<DerivativeSymbol> folded = weighted_second_derivative(symbols, input_dim, space_dim);
    if (!folded) return std::nullopt;
    return slot_of(*folded);
  };
}

namespace {

// The tangent axes the symbols need, in order: those of first and second derivatives, the
// space axes for Δ, the axes a weighted sum of second derivatives reads.
std::vector<int> tangent_axes_of(const std::vector<DerivativeSymbol>& symbols, int input_dim, int space_dim) {
  using Kind = DerivativeSymbol::Kind;
  std::vector<int> tangent_axes;
  auto need_tangent = [&](int axis) {
    if (std::find(tangent_axes.begin(), tangent_axes.end(), axis) == tangent_axes.end()) tangent_axes.push_back(axis);
  };
  for (const DerivativeSymbol& s : symbols) {
    if (s.kind == Kind::kLaplacian)
      for (int a = 0; a < space_dim; ++a) need_tangent(a);
    else if (s.kind == Kind::kPartial && (s.order() == 1 || s.order() == 2))
      for (int a : s.axes) need_tangent(a);
    else if (s.kind == Kind::kWeighted)
      for (int a = 0; a < input_dim; ++a)
        for (int b = 0; b < input_dim; ++b)
          if (s.weights[static_cast<std::size_t>(a * input_dim + b)] != 0) need_tangent(a);
  }
  std::sort(tangent_axes.begin(), tangent_axes.end());
  return tangent_axes;
}

}  // namespace

StreamPlan plan_streams(const std::vector<DerivativeSymbol>& symbols, int input_dim, int space_dim) {
  using Kind = DerivativeSymbol::Kind;
  const std::vector<int> tangent_axes = tangent_axes_of(symbols, input_dim, space_dim);
  auto tangent_of = [&](int axis) {
    return static_cast<int>(std::find(tangent_axes.begin(), tangent_axes.end(), axis) - tangent_axes.begin());
  };

  StreamPlan plan;
  plan.spec = autodiff::StreamSpec::values(input_dim);
  const int t = static_cast<int>(tangent_axes.size());
  plan.spec.tangents = Eigen::MatrixXd::Zero(input_dim, t);
  for (int i = 0; i < t; ++i) plan.spec.tangents(tangent_axes[static_cast<std::size_t>(i)], i) = 1.0;

  // Operator streams, one per distinct C; Taylor directions with their coefficients.
  std::vector<int> operator_of(symbols.size(), -1);
  auto add_operator = [&](const Eigen::MatrixXd& c) {
    for (std::size_t q = 0; q < plan.spec.operators.size(); ++q)
      if (plan.spec.operators[q] == c) return static_cast<int>(q);
    return plan.spec.add_operator(c);
  };
  std::vector<std::vector<int>> directions;  // integer ones, canonical
  bool isotropic_2d = false;                 // bilap(u) in 2D: three directions 60° apart
  std::vector<std::map<std::vector<int>, double>> taylor_of(symbols.size());
  int taylor_order = 0;
  for (std::size_t k = 0; k < symbols.size(); ++k) {
    const DerivativeSymbol& s = symbols[k];
    if (s.kind == Kind::kLaplacian) {
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(t, t);
      for (int a = 0; a < space_dim; ++a) c(tangent_of(a), tangent_of(a)) = 1.0;
      operator_of[k] = add_operator(c);
    } else if (s.kind == Kind::kPartial && s.order() == 2) {
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(t, t);
      const int i = tangent_of(s.axes[0]), j = tangent_of(s.axes[1]);
      c(i, j) += 0.5;
      c(j, i) += 0.5;
      operator_of[k] = add_operator(c);
    } else if (s.kind == Kind::kWeighted) {
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(t, t);
      for (int a = 0; a < input_dim; ++a)
        for (int b = 0; b < input_dim; ++b)
          if (const double w = s.weights[static_cast<std::size_t>(a * input_dim + b)]; w != 0)
            c(tangent_of(a), tangent_of(b)) = w;
      operator_of[k] = add_operator(c);
    } else if (s.order() >= 3) {
      taylor_order = std::max(taylor_order, s.order());
      if (s.kind == Kind::kBilaplacian && space_dim == 2) {
        isotropic_2d = true;
        continue;
      }
      taylor_of[k] = s.kind == Kind::kBilaplacian ? bilaplacian(space_dim, input_dim) : polarization(s.axes, input_dim);
      for (const auto& [w, c] : taylor_of[k])
        if (std::find(directions.begin(), directions.end(), w) == directions.end()) directions.push_back(w);
    }
  }
  const int integer_dirs = static_cast<int>(directions.size());
  if (taylor_order > 0) {
    Eigen::MatrixXd w(input_dim, integer_dirs + (isotropic_2d ? 3 : 0));
    for (int p = 0; p < integer_dirs; ++p)
      for (int a = 0; a < input_dim; ++a) w(a, p) = directions[static_cast<std::size_t>(p)][static_cast<std::size_t>(a)];
    if (isotropic_2d) {
      w.rightCols(3).setZero();
      w.block(0, integer_dirs, 2, 3) = autodiff::biharmonic_directions_2d();
    }
    plan.spec.set_taylor(w, taylor_order);
  }

  const autodiff::StreamLayout layout(plan.spec);
  for (std::size_t k = 0; k < symbols.size(); ++k)
    plan.symbols.push_back(symbol_terms(layout, symbols[k], space_dim,
                                        symbols[k].axes.empty() ? -1 : tangent_of(symbols[k].axes[0]), operator_of[k],
                                        taylor_of[k], directions));
  return plan;
}

}  // namespace nfield::solvers
