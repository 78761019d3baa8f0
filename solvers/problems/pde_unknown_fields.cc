// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_unknown_fields.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "io/text.h"

namespace nfield::solvers {

namespace {

bool is_plain_name(const std::string& name) {
  return !name.empty() && std::isalpha(static_cast<unsigned char>(name[0])) &&
         std::all_of(name.begin(), name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)); });
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

PdeUnknownFields::PdeUnknownFields(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                                   const std::vector<std::string>& reserved)
    : node_(node) {
  node.require(node.is_map() && node.size() > 0,
               "expected a mapping of field names to {true: EXPR} (or {} for no truth)");
  for (const std::string& name : node.keys()) {
    node.require(name, is_plain_name(name),
                 "unknown field name '" + name + "' must be letters and digits, starting with a letter");
    node.require(name, !contains(reserved, name),
                 "unknown field name '" + name + "' is taken (reserved: " + io::join(reserved) + ")");
    node.require(name, !contains(outputs, name), "'" + name + "' is an output already (outputs: " + io::join(outputs) + ")");
    const io::ConfigNode item = node.child(name);
    item.require(item.is_map() || item.is_null(), "expected a mapping {true: EXPR} (or {})");
    if (item.is_map()) {
      if (item.has("hidden"))
        throw item.error("hidden", "an unknown field is an extra output of the field (its hidden layers); a "
                                   "second network of its own is not implemented: remove 'hidden'");
      if (item.has("positive"))
        throw item.error("positive", "positive is not implemented for unknown fields (it is for unknown "
                                     "constants); write the residual in terms of a field that may take any sign");
      (void)item.has("true");  // read once the constants and the reference are known
      item.reject_unknown_keys();
    }
    names_.push_back(name);
    items_.push_back(item);
    read_.push_back(0);
  }
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
