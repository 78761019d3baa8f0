// SPDX-License-Identifier: MIT
//
// Any PDE from the config: residual expressions over the field's outputs, their
// derivatives and the coordinates, each trained to 0.
//
//   problem: pde
//   domain: {lower: [-1], upper: [1], time: [0, 1]}
//   outputs: [u]                      # the field's output channels (default [u])
//   constants: {nu: "0.01/pi"}        # numbers or constant expressions, in order
//   equation:
//     residuals:                      # each "= 0", its own loss term
//       - "u_t + u*u_x - nu*u_xx"     # name pde, batch interior, weight 1
//       - {expr: "u_x + u - 1", on: [x_max], weight: 10, name: robin}   # on faces
//   conditions:                       # as for poisson and wave (solvers/conditions/conditions.h)
//     - {on: boundary, type: dirichlet, value: "0"}
//     - {on: initial, type: value, value: "-sin(pi*x)"}
//   reference:
//     exact: {u: "sin(pi*x)*exp(-t)"} # optional, an expression per output: error metrics
//   # or a solution the project computes: `solution: burgers_sine, nu: nu`, the Cole–Hopf
//   # solution of u_t + u u_x = ν u_xx from −sin πx (solvers/problems/burgers_reference.h)
//
// A residual item is a string or {expr, weight (≥ 0, default 1), name (default pde, pde_1,
// …; residual_i for one with `on`), batch (the training.batch entry; default interior,
// boundary or initial after `on`), on (faces, boundary or initial; default the interior)}.
// Its names: the domain's variables (x, y, z, t as it has them), the constants, pi and e,
// and the derivative symbols of solvers/problems/pde_streams.h (u, u_x, u_xt, u_xxxx,
// lap(u), bilap(u)); each residual asks the field for exactly the streams of the symbols it
// reads, and its adjoint comes from ceres::Jet (solvers/problems/pde_residual.h).
//
// The constants are numbers in every expression of the config: residuals, reference.exact,
// later constants and the conditions' values. One no expression reads is an error (a typo,
// as an unknown key is).
// Limits: a residual reads at most 32 symbols; hard conditions (enforce: hard) take no
// residual of order above 2.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>

#include "io/compiled_expression.h"
#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/conditions/conditions.h"
#include "solvers/problems/burgers_reference.h"
#include "solvers/problems/pde_residual.h"
#include "solvers/problems/pde_streams.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

const std::vector<std::string> kReservedNames = {
    "x", "y", "z", "t", "pi", "e", "lap", "bilap", "sin", "cos", "tan", "exp", "log", "sqrt",
    "abs", "tanh", "sinh", "cosh", "atan", "min", "max", "pow"};

bool is_name(const std::string& name, bool underscore) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  return std::all_of(name.begin(), name.end(), [&](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || (underscore && c == '_');
  });
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// One residual of equation.residuals, compiled.
struct ResidualSpec {
  enum class Where { kInterior, kFaces, kInitial };
  std::string name, batch_key;
  double weight = 1;
  Where where = Where::kInterior;
  std::vector<Face> faces;
  std::shared_ptr<const io::CompiledExpression> expression;
  std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols;
  autodiff::StreamSpec spec;
  std::optional<io::ConfigNode> node;  // for errors found later (hard conditions, duplicate names)
};

class Pde final : public Problem {
 public:
  explicit Pde(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"))) {
    const io::ConfigNode& root = context.root;
    read_outputs(root);
    read_constants(root);
    const io::ConfigNode equation = root.child("equation");
    const io::ConfigNode list = equation.child("residuals");
    equation.require("residuals", list.is_sequence() && list.size() > 0,
                     "expected a non-empty list of residual expressions (each = 0)");
    for (std::size_t i = 0; i < list.size(); ++i) residuals_.push_back(read_residual(list.at(i), i));
    equation.reject_unknown_keys();
    if (root.has("conditions"))
      conditions_ = condition_terms(root.child("conditions"), domain_, output_dim(), &ansatz_, constants_);
    if (root.has("conditions")) note_condition_constants(root.child("conditions"));
    check_terms();
    if (root.has("reference")) read_reference(root.child("reference"));
    for (const auto& [name, value] : constants_)
      if (!contains(constants_used_, name))
        throw root.child("constants").error(name, "constant '" + name + "' is never used (by a residual, "
                                                  "a condition, reference.exact or another constant)");
  }

  const Domain& domain() const override { return domain_; }
  int output_dim() const override { return static_cast<int>(outputs_.size()); }
  std::vector<std::string> output_names() const override { return outputs_; }

  std::vector<LossTerm> loss_terms() const override {
    std::vector<LossTerm> terms;
    for (const ResidualSpec& r : residuals_) {
      LossTerm term;
      term.name = r.name;
      term.batch_key = r.batch_key;
      term.weight = r.weight;
      term.spec = r.spec;
      const Domain* domain = &domain_;
      if (r.where == ResidualSpec::Where::kInterior)
        term.sample = [domain](Random& rng, Eigen::Index n) { return domain->sample_interior(rng, n); };
      else if (r.where == ResidualSpec::Where::kInitial)
        term.sample = [domain](Random& rng, Eigen::Index n) { return domain->sample_initial(rng, n); };
      else
        term.sample = [domain, faces = r.faces](Random& rng, Eigen::Index n) {
          return domain->sample_faces(faces, rng, n);
        };
      term.residual = [expression = r.expression, symbols = r.symbols](const TermPoints& points) {
        return std::make_unique<ExpressionResidual>(expression, symbols, points.x);
      };
      terms.push_back(std::move(term));
    }
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  bool has_exact() const override { return !exact_.empty() || burgers_; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override {
    if (burgers_) {
      Eigen::MatrixXd xt(x.rows(), 2);
      xt << x.col(0), x.col(domain_.time_column());
      return burgers_sine_solution(xt, *burgers_);
    }
    Eigen::MatrixXd out(x.rows(), output_dim());
    std::vector<double> scratch;
    for (int c = 0; c < output_dim(); ++c)
      exact_[static_cast<std::size_t>(c)].evaluate<double>(x.rows(), x.data(), x.rows(), out.col(c).data(), scratch);
    return out;
  }

 private:
  // `outputs`: names of letters and digits (no '_', which starts a derivative), distinct.
  void read_outputs(const io::ConfigNode& root) {
    outputs_ = root.get_or<std::vector<std::string>>("outputs", {"u"});
    root.require("outputs", !outputs_.empty(), "expected a non-empty list of output names");
    for (const std::string& name : outputs_) {
      root.require("outputs", is_name(name, false),
                   "output name '" + name + "' must be letters and digits, starting with a letter");
      root.require("outputs", !contains(kReservedNames, name),
                   "output name '" + name + "' is taken (reserved: " + io::join(kReservedNames) + ")");
      root.require("outputs", std::count(outputs_.begin(), outputs_.end(), name) == 1,
                   "output name '" + name + "' is listed twice");
    }
  }

  // `constants`: name → number or expression of earlier constants.
  void read_constants(const io::ConfigNode& root) {
    if (!root.has("constants")) return;
    const io::ConfigNode node = root.child("constants");
    node.require(node.is_map(), "expected a mapping of names to numbers or constant expressions");
    for (const std::string& name : node.keys()) {
      const std::string problem =
          !is_name(name, true)                         ? "must be letters, digits and '_', starting with a letter"
          : contains(kReservedNames, name)             ? "is taken (reserved: " + io::join(kReservedNames) + ")"
          : contains(outputs_, name.substr(0, name.find('_'))) ? "reads as an output or its derivative"
                                                                : "";
      if (!problem.empty()) throw node.error(name, "constant name '" + name + "' " + problem);
      const double value = constant_expression(
          node, name,
          "constants before this one: " + (constants_.empty() ? std::string("none") : constant_names()) +
              "; pi, e; a constant reads no variable or output");
      node.require(name, std::isfinite(value), "constant '" + name + "' is not finite");
      constants_.emplace_back(name, value);
    }
  }

  // The value of node[key], an expression of the constants read so far (`valid` names them in
  // its errors).
  double constant_expression(const io::ConfigNode& node, const std::string& key, const std::string& valid) {
    io::ExpressionScope scope;
    scope.constants = constants_;
    scope.valid_names = valid;
    try {
      const io::CompiledExpression e(node.get<std::string>(key), scope);
      std::vector<double> scratch;
      note_constants(e);
      return e.evaluate<double>(nullptr, scratch);
    } catch (const io::ExpressionError& e) {
      throw node.expression_error(key, e);
    }
  }

  void note_constants(const io::CompiledExpression& e) {
    for (const std::string& name : e.constants_read())
      if (!contains(constants_used_, name)) constants_used_.push_back(name);
  }

  // The constants the conditions' values read (muparser expressions, read by condition_terms).
  void note_condition_constants(const io::ConfigNode& conditions) {
    for (std::size_t i = 0; i < conditions.size(); ++i) {
      const io::ConfigNode item = conditions.at(i);
      std::vector<std::string> texts;
      if (item.has_list("value"))
        for (std::size_t c = 0; c < item.child("value").size(); ++c) texts.push_back(item.child("value").at(c).as<std::string>());
      else if (item.has("value"))
        texts.push_back(item.get<std::string>("value"));
      for (const std::string& text : texts)
        for (const std::string& name :
             io::Expression(text.empty() ? "0" : text, domain_.expression_variables(), constants_).constants_used())
          if (!contains(constants_used_, name)) constants_used_.push_back(name);
    }
  }

  std::string constant_names() const {
    std::vector<std::string> names;
    for (const auto& [n, v] : constants_) names.push_back(n);
    return io::join(names);
  }

  // The names an expression may read: the domain's variables (slots 0 … d−1) and constants.
  io::ExpressionScope scope(bool with_outputs) const {
    io::ExpressionScope s;
    const std::vector<std::string> inputs = domain_.input_names();
    for (std::size_t a = 0; a < inputs.size(); ++a) s.slots.emplace_back(inputs[a], static_cast<int>(a));
    s.constants = constants_;
    s.valid_names = (with_outputs ? "outputs: " + io::join(outputs_) + "; " : std::string()) +
                    "variables: " + io::join(inputs) +
                    (constants_.empty() ? std::string() : "; constants: " + constant_names());
    return s;
  }

  ResidualSpec read_residual(const io::ConfigNode& item, std::size_t index) {
    ResidualSpec r;
    r.node = item;
    const std::string suffix = index > 0 ? "_" + std::to_string(index) : "";
    std::string text;
    if (item.is_map()) {
      text = item.get<std::string>("expr");
      r.weight = item.get_or("weight", 1.0);
      item.require("weight", std::isfinite(r.weight) && r.weight >= 0, "expected a weight >= 0");
      read_where(item, r);
      r.name = item.get_or("name", (r.where == ResidualSpec::Where::kInterior ? "pde" : "residual") + suffix);
      item.require("name", is_name(r.name, true), "expected a name of letters, digits and '_'");
      r.batch_key = item.get_or("batch", r.batch_key);
      item.require("batch", is_name(r.batch_key, true), "expected a training.batch key (letters, digits, '_')");
    } else {
      text = item.as<std::string>();
      r.name = "pde" + suffix;
      r.batch_key = "interior";
    }
    // Candidate symbols get slots d, d + 1, … as they are resolved; those the compiled
    // expression reads (an alias may have replaced some) are then renumbered from d.
    std::vector<DerivativeSymbol> candidates;
    io::ExpressionScope s = scope(true);
    const int d = domain_.input_dim();
    s.resolve = [&](std::string_view name) -> std::optional<int> {
      const auto symbol = parse_derivative_symbol(name, outputs_, domain_.input_names(), domain_.space_dim());
      if (!symbol) return std::nullopt;
      auto at = std::find(candidates.begin(), candidates.end(), *symbol);
      if (at == candidates.end()) at = candidates.insert(candidates.end(), *symbol);
      return d + static_cast<int>(at - candidates.begin());
    };
    s.sum_aliases = laplacian_aliases();
    io::CompiledExpression expression;
    try {
      expression = io::CompiledExpression(text, s);
      note_constants(expression);
    } catch (const io::ExpressionError& e) {
      throw item.is_map() ? item.expression_error("expr", e) : item.expression_error(e);
    }
    std::vector<DerivativeSymbol> symbols;
    std::vector<int> slot(static_cast<std::size_t>(d) + candidates.size());
    for (int a = 0; a < d; ++a) slot[static_cast<std::size_t>(a)] = a;
    for (const io::SymbolUse& use : expression.symbols())
      if (use.slot >= d) {
        slot[static_cast<std::size_t>(use.slot)] = d + static_cast<int>(symbols.size());
        symbols.push_back(candidates[static_cast<std::size_t>(use.slot - d)]);
      }
    expression.remap_slots(slot);
    r.expression = std::make_shared<const io::CompiledExpression>(std::move(expression));
    const auto error = [&](const std::string& message) {
      return item.is_map() ? item.error("expr", message) : item.error(message);
    };
    if (symbols.empty())
      throw error("the residual '" + text + "' reads no output (outputs: " + io::join(outputs_) +
                  "); write it with u, u_x, lap(u), …");
    if (static_cast<int>(symbols.size()) > kMaxExpressionReads)
      throw error("the residual reads " + std::to_string(symbols.size()) + " derivative symbols; at most " +
                  std::to_string(kMaxExpressionReads));
    StreamPlan plan = plan_streams(symbols, d, domain_.space_dim());
    r.spec = std::move(plan.spec);
    r.symbols = std::make_shared<const std::vector<std::vector<SymbolTerm>>>(std::move(plan.symbols));
    if (item.is_map()) item.reject_unknown_keys();
    return r;
  }

  // u_xx + u_yy (+ u_zz) read as lap(u): one operator stream instead of two or three.
  std::vector<io::SumAlias> laplacian_aliases() const {
    std::vector<io::SumAlias> aliases;
    if (domain_.space_dim() < 2) return aliases;
    for (const std::string& u : outputs_) {
      io::SumAlias alias{{}, "lap(" + u + ")"};
      for (int a = 0; a < domain_.space_dim(); ++a) {
        const std::string axis = domain_.input_names()[static_cast<std::size_t>(a)];
        alias.terms.push_back(u + "_" + axis + axis);
      }
      aliases.push_back(std::move(alias));
    }
    return aliases;
  }

  // `on`: faces, boundary or initial; absent: the interior.
  void read_where(const io::ConfigNode& item, ResidualSpec& r) const {
    r.batch_key = "interior";
    if (!item.has("on")) return;
    if (!item.has_list("on") && io::to_lower(item.get<std::string>("on")) == "initial") {
      if (!domain_.has_time()) throw item.error("on", "'initial' needs a domain with a time interval");
      r.where = ResidualSpec::Where::kInitial;
      r.batch_key = "initial";
      return;
    }
    r.faces = condition_faces(item, domain_);
    r.where = ResidualSpec::Where::kFaces;
    r.batch_key = "boundary";
  }

  // Distinct term names; no Taylor streams under hard conditions.
  void check_terms() const {
    std::vector<std::string> names;
    for (const LossTerm& c : conditions_) names.push_back(c.name);
    for (const ResidualSpec& r : residuals_) {
      const io::ConfigNode& node = *r.node;
      if (contains(names, r.name))
        throw node.is_map() && node.has("name")
            ? node.error("name", "loss term name '" + r.name + "' is taken")
            : node.error("loss term name '" + r.name + "' is taken; give this residual a name");
      names.push_back(r.name);
      if (ansatz_ && r.spec.taylor_order > 0)
        throw node.error("the residual reads derivatives of order above 2 (Taylor streams), which hard "
                           "conditions (enforce: hard) do not support; use enforce: soft");
    }
  }

  // `reference.exact`: an expression per output ({u: "…"}), or one string for one output.
  void read_reference(const io::ConfigNode& node) {
    if (node.has("solution")) return read_named_solution(node);
    const io::ExpressionScope s = scope(false);
    auto compile = [&](const io::ConfigNode& parent, const std::string& key) {
      try {
        io::CompiledExpression e(parent.get<std::string>(key), s);
        note_constants(e);
        return e;
      } catch (const io::ExpressionError& e) {
        throw parent.expression_error(key, e);
      }
    };
    if (!node.has_map("exact")) {
      node.require("exact", output_dim() == 1,
                   "expected a mapping of output names to expressions (outputs: " + io::join(outputs_) + ")");
      exact_.push_back(compile(node, "exact"));
    } else {
      const io::ConfigNode exact = node.child("exact");
      for (const std::string& key : exact.keys())
        if (!contains(outputs_, key))
          throw exact.error(key, "'" + key + "' is no output (outputs: " + io::join(outputs_) + ")");
      for (const std::string& output : outputs_) {
        if (!exact.has(output)) throw exact.error("missing the exact solution of output '" + output + "'");
        exact_.push_back(compile(exact, output));
      }
    }
    node.reject_unknown_keys();
  }

  // `reference: {solution: burgers_sine, nu: EXPRESSION}`: on x ∈ [−1, 1] (any part of it)
  // and t ∈ [0, 10], one output.
  void read_named_solution(const io::ConfigNode& node) {
    node.get_choice("solution", {"burgers_sine"});
    node.require("solution", domain_.space_dim() == 1 && domain_.has_time() && output_dim() == 1,
                 "burgers_sine needs one output over one space variable and time (domain: lower, upper "
                 "of size 1 and time)");
    node.require("solution", domain_.time().first >= 0 && domain_.time().second <= 10,
                 "burgers_sine is computed for t in [0, 10]");
    const double nu = constant_expression(
        node, "nu", "constants: " + (constants_.empty() ? std::string("none") : constant_names()));
    BurgersSineOptions options;
    options.nu = nu;
    node.require("nu", nu >= 1e-4 && nu <= 1e3, "expected a viscosity in [1e-4, 1e3]");
    burgers_ = options;
    node.reject_unknown_keys();
  }

  Domain domain_;
  std::vector<std::string> outputs_;
  std::vector<std::pair<std::string, double>> constants_;
  std::vector<std::string> constants_used_;
  std::vector<ResidualSpec> residuals_;
  std::vector<LossTerm> conditions_;
  std::shared_ptr<const Ansatz> ansatz_;
  std::vector<io::CompiledExpression> exact_;
  std::optional<BurgersSineOptions> burgers_;  // reference.solution: burgers_sine
};

}  // namespace

std::unique_ptr<Problem> make_pde(const ProblemContext& context) {
  return std::make_unique<Pde>(context);
}

}  // namespace nfield::solvers
