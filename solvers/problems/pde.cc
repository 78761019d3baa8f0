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
//   conditions:                       # by output name (solvers/conditions/condition_list.h)
//     - {on: [x_min, x_max], type: dirichlet, value: {u: "0"}}
//     - {on: initial, type: value, value: {u: "-sin(pi*x)"}}
//     - {on: [x_max], type: residual, residual: "u_x + u - 1"}   # boundary_residual_2
//   reference:                        # solvers/problems/pde_reference.h
//     exact: {u: "sin(pi*x)*exp(-t)"} # optional, an expression per output: error metrics
//   # or `file: data.csv` (CSV, COMSOL table, F.h5:/dataset; `columns` maps names), whose
//   # points give rel_l2 and max_abs_err per output and over all outputs in metrics.json;
//   # or a solution the project computes: `solution: burgers_sine, nu: nu`, the Cole–Hopf
//   # solution of u_t + u u_x = ν u_xx from −sin πx (solvers/problems/burgers_reference.h)
//   derived: {u: "w + x*y"}           # expressions of the outputs' values and the coordinates
//   # that reference files may hold as they hold outputs (configs/lid_driven_cavity.yaml)
//
// A residual item is a string or {expr, weight (≥ 0, default 1), name (default pde, pde_1,
// …; residual_i for one with `on`), batch (the training.batch entry; default interior,
// boundary or initial after `on`), on (faces, boundary or initial; default the interior),
// where (without `on`: interior points only where this expression holds, for more points near
// a body; with `on` on a geometry: that part of the boundary)}.
// `functionals` (solvers/problems/pde_functionals.h): boundary integrals and point sums of the
// solution (a body's drag and lift), reported on the progress line, after training and by
// `nfield eval`.
// Its names: the domain's variables (x, y, z, t as it has them), the constants, pi and e,
// and the derivative symbols of solvers/problems/pde_streams.h (u, u_x, u_xt, u_xxxx,
// lap(u), bilap(u)); each residual asks the field for exactly the streams of the symbols it
// reads, and its adjoint comes from ceres::Jet (solvers/problems/pde_residual.h).
//
// Conditions of `type: residual` are compiled exactly as residuals with `on` are (one
// function, compile_residual); the others become loss terms in solvers/conditions/conditions.h
// or the ansatz of solvers/core/ansatz.h.
//
// The constants are numbers in every expression of the config: residuals, reference.exact,
// later constants and the conditions' values and coefficients. One no expression reads is an
// error (a typo, as an unknown key is).
//
// Inverse problems (solvers/core/unknowns.h, solvers/problems/pde_data.h): a constant given as
//   nu: {unknown: true, initial: 0.05, positive: true, true: 0.00318, lr: 1.0e-3}
// (or bounds: [a, b]) is trained with the field; only residuals (of the equation and of
// `type: residual` conditions) read it, as a slot whose current value is filled in at every
// evaluation. `data:` adds the measurements' loss term. An unknown constant no residual reads
// is a warning (the data alone cannot tell it); `true:` on a known constant is an error.
// Unknown fields (`unknown_fields: {a: {true: EXPR}}`, solvers/problems/pde_unknown_fields.h)
// are extra outputs of the field after `outputs` (or, with `hidden`, small networks of their
// own: fields/field_branches.h), read by residuals as the outputs are.
// Parametric fields (issue 28): `nu: {range: [a, b], sampling: uniform | log}` is an input
// column of the domain (solvers/core/domain.h, parameters), read by name as x or t are; not with
// `unknown`; `reference.held_out` lists the values outputs are evaluated at.
// Limits: a residual reads at most 32 symbols; hard conditions (enforce: hard) take no
// residual of order above 2.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "io/compiled_expression.h"
#include "io/text.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/conditions/condition_list.h"
#include "solvers/conditions/conditions.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/geometry/geometry_config.h"
#include "solvers/problems/pde_constants.h"
#include "solvers/problems/pde_data.h"
#include "solvers/problems/pde_functionals.h"
#include "solvers/problems/pde_reference.h"
#include "solvers/problems/pde_residual.h"
#include "solvers/problems/pde_streams.h"
#include "solvers/problems/pde_unknown_fields.h"
#include "solvers/problems/problems.h"

namespace nfield::solvers {
namespace {

const std::vector<std::string> kReservedNames = {
    "x", "y", "z", "t", "pi", "e", "lap", "bilap", "sin", "cos", "tan", "exp", "log", "sqrt",
    "abs", "tanh", "sinh", "cosh", "atan", "atan2", "min", "max", "pow"};

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
  std::optional<geometry::Selection> parts;  // instead of faces on a domain with a geometry
  std::shared_ptr<const io::Expression> region;  // interior points only where it is nonzero
  std::shared_ptr<const io::CompiledExpression> expression;
  std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols;
  std::vector<int> unknown_reads;  // the unknown constant at each slot after the symbols
  autodiff::StreamSpec spec;
  std::optional<io::ConfigNode> node;  // for errors found later (hard conditions, duplicate names)
};

class Pde final : public Problem, public HasFieldBranches, public ReportsProgress {
 public:
  explicit Pde(const ProblemContext& context)
      : domain_(Domain::from_config(context.root.child("domain"), context.config_dir)) {
    const io::ConfigNode& root = context.root;
    read_outputs(root);
    own_outputs_ = outputs_.size();
    if (root.has("unknown_fields")) {
      fields_ = PdeUnknownFields(root.child("unknown_fields"), outputs_, kReservedNames, domain_.input_names());
      outputs_.insert(outputs_.end(), fields_.names().begin(), fields_.names().end());
    }
    read_constants(root);
    const io::ConfigNode equation = root.child("equation");
    const io::ConfigNode list = equation.child("residuals");
    equation.require("residuals", list.is_sequence() && list.size() > 0,
                     "expected a non-empty list of residual expressions (each = 0)");
    for (std::size_t i = 0; i < list.size(); ++i) residuals_.push_back(read_residual(list.at(i), i));
    equation.reject_unknown_keys();
    if (root.has("conditions")) read_condition_list(root.child("conditions"));
    check_terms();
    if (root.has("derived")) read_derived(root.child("derived"));
    if (root.has("reference")) read_reference(root.child("reference"), context.config_dir);
    fields_.read_truths(reference_, value_expressions(), own_outputs());
    if (root.has("data")) read_data(root.child("data"), context.config_dir);
    if (root.has("functionals")) read_functionals(root.child("functionals"));
    for (const auto& [name, value] : constants_)
      if (!contains(constants_used_, name))
        throw root.child("constants").error(name, "constant '" + name + "' is never used (by a residual, "
                                                  "a condition, derived, reference.exact or another constant)");
    fields_.check(ansatz_ != nullptr);
    if (unknowns_) {
      if (ansatz_)
        throw root.child("constants").error("unknown constants take soft conditions only (enforce: soft)");
      for (const UnknownConstant& u : unknowns_->items())
        if (!contains(constants_used_, u.name))
          std::fprintf(stderr, "%s\n", root.child("constants").child(u.name).error(
              "warning: unknown constant '" + u.name + "' is read by no residual: nothing trains it").what());
    }
  }

  std::shared_ptr<UnknownConstants> unknowns() const override { return unknowns_; }
  std::vector<fields::FieldBranch> field_branches() const override { return fields_.branches(); }

  const Domain& domain() const override { return domain_; }
  int output_dim() const override { return static_cast<int>(outputs_.size()); }
  std::vector<std::string> output_names() const override { return outputs_; }

  fields::SineFrequencies default_sine_frequencies() const override {
    return fields::kPdeSineFrequencies;  // a differential equation: fields/field_config.h
  }
  std::vector<LossTerm> loss_terms() const override {
    std::vector<LossTerm> terms;
    for (const ResidualSpec& r : residuals_) {
      LossTerm term;
      term.name = r.name;
      term.batch_key = r.batch_key;
      term.weight = r.weight;
      term.spec = r.spec;
      const Domain* domain = &domain_;
      if (r.where == ResidualSpec::Where::kInterior && r.region)
        term.sample = [domain, region = r.region](Random& rng, Eigen::Index n) {
          return domain->sample_interior_where(rng, n, *region);
        };
      else if (r.where == ResidualSpec::Where::kInterior)
        term.sample = [domain](Random& rng, Eigen::Index n) { return domain->sample_interior(rng, n); };
      else if (r.where == ResidualSpec::Where::kInitial)
        term.sample = [domain](Random& rng, Eigen::Index n) { return domain->sample_initial(rng, n); };
      else if (r.parts)
        term.sample = [domain, parts = *r.parts](Random& rng, Eigen::Index n) {
          return domain->sample_boundary(parts, rng, n).points;
        };
      else
        term.sample = [domain, faces = r.faces](Random& rng, Eigen::Index n) {
          return domain->sample_faces(faces, rng, n);
        };
      term.residual = [expression = r.expression, symbols = r.symbols, unknowns = unknowns_,
                       reads = r.unknown_reads](const TermPoints& points) {
        return std::make_unique<ExpressionResidual>(expression, symbols, points.x, unknowns, reads);
      };
      terms.push_back(std::move(term));
    }
    terms.insert(terms.end(), conditions_.begin(), conditions_.end());
    if (!data_.empty()) terms.push_back(data_.loss_term(domain_.input_dim()));
    return terms;
  }

  std::shared_ptr<const Ansatz> ansatz() const override { return ansatz_; }
  std::vector<Eigen::VectorXd> held_out_parameters() const override {
    return reference_.held_out().empty() ? Problem::held_out_parameters() : reference_.held_out();
  }
  bool has_exact() const override { return reference_.has_exact(); }
  // The outputs' reference, then the unknown fields' truths.
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const override {
    return fields_.with_truths(x, reference_.exact(x));
  }

  // reference.file: the error at its points, after every stage and in metrics.json.
  std::optional<double> reported_error(const OutputContext& context) const override {
    if (!reference_.has_points()) return std::nullopt;
    return reference_.errors(compared(context)).all_rel_l2;
  }
  // `functionals`: on the progress line (at most every 10 s) and after training.
  std::vector<std::pair<std::string, double>> progress_metrics(const OutputContext& context,
                                                               const TrainingRate&) const override {
    return functionals_.values(context);
  }
  void write_outputs(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const override {
    functionals_.write(context, metrics);
    if (!reference_.has_points()) return;
    const OutputErrors e = reference_.errors(compared(context));
    const std::vector<std::string> names = compared_names();
    metrics.emplace_back("rel_l2", e.all_rel_l2);
    metrics.emplace_back("max_abs_err", e.all_max_abs);
    std::string per_output;
    for (std::size_t c = 0; names.size() > 1 && c < names.size(); ++c) {
      if (e.points[c] == 0) continue;  // no file has this output
      metrics.emplace_back("rel_l2_" + names[c], e.rel_l2[c]);
      metrics.emplace_back("max_abs_err_" + names[c], e.max_abs[c]);
      char line[96];
      std::snprintf(line, sizeof line, "; %s: rel_l2 %.3e, max_abs_err %.3e", names[c].c_str(), e.rel_l2[c],
                    e.max_abs[c]);
      per_output += line;
    }
    metrics.emplace_back("reference_points", static_cast<double>(reference_.point_count()));
    std::printf("reference.file, %ld points: rel_l2 %.3e, max_abs_err %.3e%s\n",
                static_cast<long>(reference_.point_count()), e.all_rel_l2, e.all_max_abs, per_output.c_str());
  }

 private:
  // `outputs`: names of letters and digits (no '_', which starts a derivative), distinct.
  void read_outputs(const io::ConfigNode& root) {
    outputs_ = root.get_or<std::vector<std::string>>("outputs", {"u"});
    root.require("outputs", !outputs_.empty(), "expected a non-empty list of output names");
    for (const std::string& name : outputs_) {
      root.require("outputs", io::is_name(name, false),
                   "output name '" + name + "' must be letters and digits, starting with a letter");
      root.require("outputs", !contains(kReservedNames, name),
                   "output name '" + name + "' is taken (reserved: " + io::join(kReservedNames) + ")");
      root.require("outputs", std::count(outputs_.begin(), outputs_.end(), name) == 1,
                   "output name '" + name + "' is listed twice");
    }
  }

  // The outputs, without the unknown fields.
  std::vector<std::string> own_outputs() const {
    return std::vector<std::string>(outputs_.begin(), outputs_.begin() + static_cast<long>(own_outputs_));
  }

  // `constants`: name → number or expression of earlier constants.
  void read_constants(const io::ConfigNode& root) {
    if (!root.has("constants")) return;
    const io::ConfigNode node = root.child("constants");
    node.require(node.is_map(), "expected a mapping of names to numbers or constant expressions");
    for (const std::string& name : node.keys()) {
      const std::string problem =
          !io::is_name(name, true)                         ? "must be letters, digits and '_', starting with a letter"
          : contains(kReservedNames, name)             ? "is taken (reserved: " + io::join(kReservedNames) + ")"
          : contains(outputs_, name.substr(0, name.find('_'))) ? "reads as an output or its derivative"
                                                                : "";
      if (!problem.empty()) throw node.error(name, "constant name '" + name + "' " + problem);
      if (node.has_map(name) && node.child(name).has("range")) {
        domain_.add_parameter(read_parameter(node.child(name), name));
        continue;
      }
      if (node.has_map(name)) {
        unknown_items_.push_back(read_unknown_constant(node.child(name), name));
        unknowns_ = std::make_shared<UnknownConstants>(unknown_items_);
        continue;
      }
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

  // `derived: {u: "w + lift"}`: named expressions of the variables, the constants and the
  // outputs' values (no derivatives), which reference files may hold as they hold outputs
  // (the lid-driven cavity trains w = u − lift and is compared with Ghia's u).
  void read_derived(const io::ConfigNode& node) {
    node.require(node.is_map(), "expected a mapping of names to expressions of the variables, constants and outputs");
    io::ExpressionScope s = scope(true);
    for (std::size_t c = 0; c < outputs_.size(); ++c)
      s.slots.emplace_back(outputs_[c], domain_.input_dim() + static_cast<int>(c));
    for (const std::string& name : node.keys()) {
      const bool constant =
          std::any_of(constants_.begin(), constants_.end(), [&](const auto& c) { return c.first == name; });
      node.require(name,
                   io::is_name(name, false) && !contains(kReservedNames, name) && !contains(outputs_, name) && !constant,
                   "expected a new name of letters and digits (not an output, constant, variable or function)");
      try {
        derived_.emplace_back(node.get<std::string>(name), s);
      } catch (const io::ExpressionError& error) {
        throw node.expression_error(name, error);
      }
      note_constants(derived_.back());
      derived_names_.push_back(name);
    }
  }

  // The outputs, then the derived quantities: what reference files are compared with.
  std::vector<std::string> compared_names() const {
    std::vector<std::string> names = outputs_;
    names.insert(names.end(), derived_names_.begin(), derived_names_.end());
    return names;
  }
  PdeReference::FieldValues compared(const OutputContext& context) const {
    return [this, values = context.values](const Eigen::MatrixXd& x) -> Eigen::MatrixXd {
      const Eigen::MatrixXd out = values(x);
      if (derived_.empty()) return out;
      Eigen::MatrixXd inputs(x.rows(), x.cols() + out.cols());
      inputs << x, out;
      Eigen::MatrixXd all(x.rows(), out.cols() + static_cast<Eigen::Index>(derived_.size()));
      all.leftCols(out.cols()) = out;
      std::vector<double> scratch;
      for (std::size_t k = 0; k < derived_.size(); ++k)
        derived_[k].evaluate<double>(x.rows(), inputs.data(), x.rows(),
                                     all.col(out.cols() + static_cast<Eigen::Index>(k)).data(), scratch);
      return all;
    };
  }

  // `conditions`: read once (solvers/conditions/condition_list.h); the residual items
  // compiled as the equation's residuals on faces are.
  void read_condition_list(const io::ConfigNode& node) {
    ConditionReading reading;
    reading.outputs = outputs_;
    reading.constants = constants_;
    reading.allow_hard = reading.allow_residual = true;
    const std::vector<ConditionItem> items = read_conditions(node, domain_, reading);
    for (const ConditionItem& item : items) {
      for (const auto* e : {&item.robin_a, &item.robin_b}) note_constants(*e);
      for (const auto& e : item.values) note_constants(e);
      if (item.type != ConditionType::kResidual) continue;
      ResidualSpec r;
      r.node = item.node;
      r.weight = item.weight;
      const std::string suffix = item.index > 0 ? "_" + std::to_string(item.index) : "";
      r.where = item.initial ? ResidualSpec::Where::kInitial : ResidualSpec::Where::kFaces;
      r.batch_key = item.initial ? "initial" : "boundary";
      r.name = (item.initial ? "initial_residual" : "boundary_residual") + suffix;
      r.faces = item.faces;
      r.parts = item.parts;
      compile_residual(item.residual, item.node, "residual", r);
      residuals_.push_back(std::move(r));
    }
    ansatz_ = read_ansatz(items, domain_, output_dim());
    conditions_ = condition_terms(items, domain_);
  }

  void note_constants(const std::optional<io::Expression>& e) {
    if (!e) return;
    for (const std::string& name : e->constants_used())
      if (!contains(constants_used_, name)) constants_used_.push_back(name);
  }

  // How the reference and the measurements compile their expressions: over the coordinates
  // and constants (no outputs), noting the constants they read.
  PdeExpressions value_expressions() {
    PdeExpressions e;
    e.compile = [this](const io::ConfigNode& parent, const std::string& key) {
      try {
        io::CompiledExpression compiled(parent.get<std::string>(key), scope(false));
        note_constants(compiled);
        return compiled;
      } catch (const io::ExpressionError& error) {
        throw parent.expression_error(key, error);
      }
    };
    e.constant = [this](const io::ConfigNode& parent, const std::string& key) {
      return constant_expression(parent, key,
                                 "constants: " + (constants_.empty() ? std::string("none") : constant_names()));
    };
    return e;
  }

  void read_reference(const io::ConfigNode& node, const std::filesystem::path& config_dir) {
    reference_ = PdeReference(node, domain_, compared_names(), value_expressions(), config_dir, own_outputs_);
  }

  // `functionals` (solvers/problems/pde_functionals.h): compiled as residuals are, with the
  // normal's components as variables after the inputs.
  void read_functionals(const io::ConfigNode& node) {
    std::vector<std::string> taken = outputs_;
    for (const auto& [name, value] : constants_) taken.push_back(name);
    if (unknowns_)
      for (const UnknownConstant& u : unknowns_->items()) taken.push_back(u.name);
    const CompileReads compile = [this](const io::ConfigNode& item, const std::string& key,
                                        const std::vector<std::string>& extra) {
      ResidualSpec r;
      compile_residual(item.get<std::string>(key), item, key, r, extra, "functional");
      return CompiledReads{r.expression, r.symbols, r.unknown_reads, r.spec};
    };
    functionals_ = PdeFunctionals(node, domain_, compile, taken, unknowns_);
  }

  // `data`: measurements (solvers/problems/pde_data.h).
  void read_data(const io::ConfigNode& node, const std::filesystem::path& config_dir) {
    data_ = PdeData(node, domain_, own_outputs(), value_expressions(), &reference_, config_dir);
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
      item.require("name", io::is_name(r.name, true), "expected a name of letters, digits and '_'");
      r.batch_key = item.get_or("batch", r.batch_key);
      item.require("batch", io::is_name(r.batch_key, true), "expected a training.batch key (letters, digits, '_')");
    } else {
      text = item.as<std::string>();
      r.name = "pde" + suffix;
      r.batch_key = "interior";
    }
    compile_residual(text, item, item.is_map() ? std::optional<std::string>("expr") : std::nullopt, r);
    if (item.is_map()) item.reject_unknown_keys();
    return r;
  }

  // Compiles `text` (at node[key], or node itself) into r's expression, symbols and streams.
  // `extra` names variables in the slots after the domain's inputs (a functional's normal
  // components); `what` names the expression in errors.
  void compile_residual(const std::string& text, const io::ConfigNode& node, const std::optional<std::string>& key,
                        ResidualSpec& r, const std::vector<std::string>& extra = {},
                        const std::string& what = "residual") {
    // Candidate symbols get slots d, d + 1, … as they are resolved; those the compiled
    // expression reads (an alias may have replaced some) are then renumbered from d.
    std::vector<DerivativeSymbol> candidates;
    io::ExpressionScope s = scope(true);
    for (std::size_t k = 0; k < extra.size(); ++k)
      s.slots.emplace_back(extra[k], domain_.input_dim() + static_cast<int>(k));
    if (!extra.empty()) s.valid_names += "; " + io::join(extra);
    const int d = domain_.input_dim() + static_cast<int>(extra.size());
    // Unknown constants resolve to slots d + kUnknownSlots + i until renumbered.
    constexpr int kUnknownSlots = 1 << 16;
    const auto slot_of = [&candidates, d](const DerivativeSymbol& symbol) {
      auto at = std::find(candidates.begin(), candidates.end(), symbol);
      if (at == candidates.end()) at = candidates.insert(candidates.end(), symbol);
      return d + static_cast<int>(at - candidates.begin());
    };
    s.resolve = [&](std::string_view name) -> std::optional<int> {
      if (unknowns_ && unknowns_->index(std::string(name)) >= 0)
        return d + kUnknownSlots + unknowns_->index(std::string(name));
      const auto symbol = parse_derivative_symbol(name, outputs_, domain_.input_names(), domain_.space_dim());
      if (!symbol) return std::nullopt;
      return slot_of(*symbol);
    };
    s.sum_aliases = laplacian_aliases();
    set_second_derivative_folds(s, outputs_, domain_.input_names(), domain_.space_dim(), slot_of);
    io::CompiledExpression expression;
    try {
      expression = io::CompiledExpression(text, s);
      note_constants(expression);
    } catch (const io::ExpressionError& e) {
      throw key ? node.expression_error(*key, e) : node.expression_error(e);
    }
    std::vector<DerivativeSymbol> symbols;
    std::vector<int> slot(static_cast<std::size_t>(d + kUnknownSlots + (unknowns_ ? unknowns_->count() : 0)));
    for (int a = 0; a < d; ++a) slot[static_cast<std::size_t>(a)] = a;
    for (const io::SymbolUse& use : expression.symbols())
      if (use.slot >= d && use.slot < d + kUnknownSlots) {
        slot[static_cast<std::size_t>(use.slot)] = d + static_cast<int>(symbols.size());
        symbols.push_back(candidates[static_cast<std::size_t>(use.slot - d)]);
        const auto output = static_cast<std::size_t>(symbols.back().output);
        if (output >= own_outputs_) fields_.note_read(output - own_outputs_);
      }
    for (const io::SymbolUse& use : expression.symbols())
      if (use.slot >= d + kUnknownSlots) {
        slot[static_cast<std::size_t>(use.slot)] = d + static_cast<int>(symbols.size() + r.unknown_reads.size());
        r.unknown_reads.push_back(use.slot - d - kUnknownSlots);
        if (!contains(constants_used_, use.name)) constants_used_.push_back(use.name);
      }
    expression.remap_slots(slot);
    r.expression = std::make_shared<const io::CompiledExpression>(std::move(expression));
    const auto error = [&](const std::string& message) {
      return key ? node.error(*key, message) : node.error(message);
    };
    if (symbols.empty())
      throw error("the " + what + " '" + text + "' reads no output (outputs: " + io::join(outputs_) +
                  "); write it with u, u_x, lap(u), …");
    if (static_cast<int>(symbols.size()) > kMaxExpressionReads)
      throw error("the " + what + " reads " + std::to_string(symbols.size()) + " derivative symbols; at most " +
                  std::to_string(kMaxExpressionReads));
    StreamPlan plan = plan_streams(symbols, domain_.input_dim(), domain_.space_dim());
    r.spec = std::move(plan.spec);
    r.symbols = std::make_shared<const std::vector<std::vector<SymbolTerm>>>(std::move(plan.symbols));
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

  // `on`: faces, boundary or initial; absent: the interior, or with `where` the region of it
  // where that expression is nonzero (more points near a body: its own batch and weight).
  void read_where(const io::ConfigNode& item, ResidualSpec& r) {
    r.batch_key = "interior";
    if (!item.has("on")) {
      if (item.has("where")) {
        r.region = read_interior_region(item, "where", domain_, constants_);
        note_constants(std::optional<io::Expression>(*r.region));
      }
      return;
    }
    if (!item.has_list("on") && io::to_lower(item.get<std::string>("on")) == "initial") {
      if (!domain_.has_time()) throw item.error("on", "'initial' needs a domain with a time interval");
      r.where = ResidualSpec::Where::kInitial;
      r.batch_key = "initial";
      return;
    }
    if (domain_.geometry()) r.parts = geometry::read_selection(item, *domain_.geometry());
    else r.faces = condition_faces(item, domain_);
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

  Domain domain_;
  std::vector<std::string> outputs_;  // the outputs, then the unknown fields
  std::size_t own_outputs_ = 0;       // of which the outputs
  PdeUnknownFields fields_;
  std::vector<std::pair<std::string, double>> constants_;
  std::vector<std::string> constants_used_;
  std::vector<ResidualSpec> residuals_;
  std::vector<LossTerm> conditions_;
  std::vector<io::CompiledExpression> derived_;
  std::vector<std::string> derived_names_;
  std::shared_ptr<const Ansatz> ansatz_;
  PdeReference reference_;
  std::vector<UnknownConstant> unknown_items_;
  std::shared_ptr<UnknownConstants> unknowns_;  // null: none
  PdeData data_;
  PdeFunctionals functionals_;
};

}  // namespace

std::unique_ptr<Problem> make_pde(const ProblemContext& context) {
  return std::make_unique<Pde>(context);
}

}  // namespace nfield::solvers
