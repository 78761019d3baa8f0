// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_unknown_fields.h"

#include <algorithm>
#include <cstdio>

#include "io/text.h"

namespace nfield::solvers {

namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The keys of an unknown field with a network of its own (the header).
fields::FieldBranch read_branch(const io::ConfigNode& item, const std::vector<std::string>& inputs) {
  fields::FieldBranch branch;
  fields::FieldOptions& o = branch.options;
  o.type = item.get_choice("type", {"mlp", "siren"}, "mlp");
  o.hidden = item.get<std::vector<int>>("hidden");
  item.require("hidden", !o.hidden.empty(), "expected a non-empty list of widths");
  for (int h : o.hidden) item.require("hidden", h >= 1 && h <= 4096, "expected widths in [1, 4096]");
  if (o.type == "mlp") o.activation = item.get_choice("activation", {"tanh", "softplus", "sine", "identity"}, "tanh");
  o.first_omega = item.get_or("first_omega", 30.0);
  item.require("first_omega", o.first_omega > 0, "expected a number > 0");
  o.hidden_omega = item.get_or("hidden_omega", o.type == "mlp" ? 1.0 : 30.0);
  item.require("hidden_omega", o.hidden_omega > 0, "expected a number > 0");
  branch.positive = item.get_or("positive", false);
  std::vector<std::string> names = inputs;
  if (item.has("inputs")) {
    names = item.get<std::vector<std::string>>("inputs");
    item.require("inputs", !names.empty(), "expected a non-empty list of the domain's inputs (" + io::join(inputs) + ")");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto at = std::find(inputs.begin(), inputs.end(), names[i]);
    item.require("inputs", at != inputs.end(),
                 "'" + names[i] + "' is not an input of the domain (inputs: " + io::join(inputs) + ")");
    const int column = static_cast<int>(at - inputs.begin());
    item.require("inputs", i == 0 || column > branch.inputs.back(),
                 "list the inputs once each, in the domain's order (" + io::join(inputs) + ")");
    branch.inputs.push_back(column);
  }
  o.input_dim = static_cast<int>(branch.inputs.size());
  o.output_dim = 1;
  return branch;
}

}  // namespace

PdeUnknownFields::PdeUnknownFields(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                                   const std::vector<std::string>& reserved, const std::vector<std::string>& inputs)
    : node_(node) {
  node.require(node.is_map() && node.size() > 0,
               "expected a mapping of field names to {true: EXPR} (or {} for no truth)");
  std::vector<std::string> own_names;
  std::vector<io::ConfigNode> own_items;
  for (const std::string& name : node.keys()) {
    node.require(name, io::is_name(name, false),
                 "unknown field name '" + name + "' must be letters and digits, starting with a letter");
    node.require(name, !contains(reserved, name),
                 "unknown field name '" + name + "' is taken (reserved: " + io::join(reserved) + ")");
    node.require(name, !contains(outputs, name), "'" + name + "' is an output already (outputs: " + io::join(outputs) + ")");
    const io::ConfigNode item = node.child(name);
    item.require(item.is_map() || item.is_null(), "expected a mapping {true: EXPR, hidden: [...], …} (or {})");
    const bool own = item.is_map() && item.has("hidden");
    if (item.is_map()) {
      if (own) {
        branches_.push_back(read_branch(item, inputs));
      } else {
        for (const char* key : {"positive", "inputs", "type", "activation", "first_omega", "hidden_omega"})
          if (item.has(key))
            throw item.error(key, std::string(key) + " needs a network of its own for '" + name +
                                      "' (hidden: [widths]); without it the field is an extra output of u's network");
      }
      (void)item.has("true");  // read once the constants and the reference are known
      item.reject_unknown_keys();
    }
    (own ? own_names : names_).push_back(name);
    (own ? own_items : items_).push_back(item);
  }
  names_.insert(names_.end(), own_names.begin(), own_names.end());
  items_.insert(items_.end(), own_items.begin(), own_items.end());
  read_.assign(names_.size(), 0);
}

void PdeUnknownFields::read_truths(const PdeReference& reference, const PdeExpressions& expressions,
                                   const std::vector<std::string>& outputs) {
  const bool any = std::any_of(items_.begin(), items_.end(),
                               [](const io::ConfigNode& item) { return item.is_map() && item.has("true"); });
  if (!any) return;
  for (std::size_t f = 0; f < items_.size(); ++f) {
    const io::ConfigNode& item = items_[f];
    if (!item.is_map() || !item.has("true"))
      throw node_->error(names_[f], "give every unknown field its truth (true: EXPR) or none: the grid's errors "
                                   "compare every output");
    if (!reference.has_exact())
      throw item.error("true", "a truth needs reference.exact (or reference.solution) for the outputs (" +
                                   io::join(outputs) + ")");
    truths_.push_back(expressions.compile(item, "true"));
  }
}

Eigen::MatrixXd PdeUnknownFields::with_truths(const Eigen::MatrixXd& x, const Eigen::MatrixXd& own) const {
  if (truths_.empty()) return own;
  Eigen::MatrixXd all(x.rows(), own.cols() + static_cast<Eigen::Index>(truths_.size()));
  all.leftCols(own.cols()) = own;
  std::vector<double> scratch;
  for (std::size_t f = 0; f < truths_.size(); ++f)
    truths_[f].evaluate<double>(x.rows(), x.data(), x.rows(), all.col(own.cols() + static_cast<Eigen::Index>(f)).data(),
                                scratch);
  return all;
}

void PdeUnknownFields::check(bool hard_conditions) const {
  if (empty()) return;
  if (hard_conditions) throw node_->error("unknown fields take soft conditions only (enforce: soft)");
  for (std::size_t f = 0; f < names_.size(); ++f)
    if (!read_[f])
      std::fprintf(stderr, "%s\n", node_->child(names_[f]).error("warning: unknown field '" + names_[f] +
                                                                "' is read by no residual: nothing ties it to "
                                                                "the equation").what());
}

}  // namespace nfield::solvers
