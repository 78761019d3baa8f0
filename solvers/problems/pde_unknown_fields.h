// SPDX-License-Identifier: MIT
//
// The `unknown_fields:` section of `problem: pde` (issue 26 item 2): coefficients that vary
// over the domain and are learnt with the solution,
//
//   unknown_fields:
//     a: {true: "1/(1 + x^2 + y^2)"}   # or {} (no truth)
//
// Each is an extra output channel of the field, after `outputs`. Residuals read it with its
// derivatives exactly as they read u (a, a_x, a_xy, lap(a): the same streams, the same Jet
// adjoint, solvers/problems/pde_residual.h), so Adam, L-BFGS and both LM backends train it
// through the field's own parameters and Jacobian, and checkpoints carry it with no special
// case; conditions give its known values by name (`{on: boundary, type: dirichlet, value:
// {a: "…"}}`); the grid outputs write it beside u and, with `true:`, its exact_/error_ arrays
// and rel_l2_a, max_abs_err_a in metrics.json.
//
// A network of its own (issue 26 item 2): an item with `hidden` is a branch of the field
// (fields/field_branches.h), a small network of the inputs it names,
//
//   unknown_fields:
//     s: {hidden: [32, 32], inputs: [x, y], positive: true, true: "EXPR"}
//
// keys: hidden (widths), type (mlp | siren; mlp), activation (mlp; tanh), first_omega and
// hidden_omega (siren; 30 and 30, and the field's for an mlp with sine), inputs (names of
// the domain's inputs; all of them), positive (softplus of the network's output). It is
// the field's last output(s): the fields without `hidden` (extra outputs of the field's own
// network, sharing its hidden layers) come first, whatever the order in the config. Inputs
// without t in a space-time problem give a field of space only (a source s(x, y)): its
// t-derivatives are 0. Its parameters are part of θ, so every optimizer, both precisions,
// checkpoints and `nfield eval` take it as they take the field's own.
// Why an extra output stays the default: the output shares the field's hidden layers,
// cheaper per pass; a network of its own decouples a and u (their smoothness, their inputs).
//
// Rules: names as outputs' (letters and digits, not reserved, not an output). `true:` needs
// reference.exact (or solution) for the outputs, and with one truth given every unknown
// field needs its own (the grid compares every output). Measurements (`data:`) are of the
// outputs, not the fields. A field no residual reads is a warning, as an unknown constant
// is. `positive: true` without `hidden` is refused (the extra output's chain rule through
// every derivative symbol would be a second implementation of the branch's softplus layer).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/compiled_expression.h"
#include "fields/field_options.h"
#include "io/config.h"
#include "solvers/problems/pde_reference.h"

namespace nfield::solvers {

class PdeUnknownFields {
 public:
  PdeUnknownFields() = default;
  // Reads node (`unknown_fields`); `outputs` are the problem's outputs, `reserved` the names
  // no output may take, `inputs` the domain's input columns. The truths are read later.
  PdeUnknownFields(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                   const std::vector<std::string>& reserved, const std::vector<std::string>& inputs);

  bool empty() const { return names_.empty(); }
  // In output order: extra outputs of the field's network first, then the branches.
  const std::vector<std::string>& names() const { return names_; }
  // The fields with a network of their own, as branches of the field (seed: the field's).
  const std::vector<fields::FieldBranch>& branches() const { return branches_; }
  // Field f is read by a residual.
  void note_read(std::size_t f) { read_[f] = 1; }

  // The `true:` expressions, once the reference is known (`outputs`: for its messages).
  void read_truths(const PdeReference& reference, const PdeExpressions& expressions,
                   const std::vector<std::string>& outputs);
  // The outputs' exact values `own` (n × outputs), then a column per field's truth.
  Eigen::MatrixXd with_truths(const Eigen::MatrixXd& x, const Eigen::MatrixXd& own) const;
  // Refusals that need the whole problem read, and the warning for fields no residual reads.
  void check(bool hard_conditions) const;

 private:
  std::optional<io::ConfigNode> node_;  // absent: no unknown fields
  std::vector<std::string> names_;
  std::vector<io::ConfigNode> items_;
  std::vector<char> read_;
  std::vector<io::CompiledExpression> truths_;
  std::vector<fields::FieldBranch> branches_;
};

}  // namespace nfield::solvers
