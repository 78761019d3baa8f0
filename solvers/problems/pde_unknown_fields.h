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
// Why an extra output and not a second small network of its own (`hidden:`, refused): the
// output shares the field's hidden layers, so every pass, optimizer, the LM Jacobian, MPI
// and checkpoints already handle it; a second network would need a second parameter block
// through all of them. The cost: a and u share features, and the widths are u's.
//
// Rules: names as outputs' (letters and digits, not reserved, not an output). `true:` needs
// reference.exact (or solution) for the outputs, and with one truth given every unknown
// field needs its own (the grid compares every output). Measurements (`data:`) are of the
// outputs, not the fields. A field no residual reads is a warning, as an unknown constant
// is. `positive: true` is refused (for constants it is a log parametrisation; a field would
// need the chain rule through every derivative symbol the residuals read): not done.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/compiled_expression.h"
#include "io/config.h"
#include "solvers/problems/pde_reference.h"

namespace nfield::solvers {

class PdeUnknownFields {
 public:
  PdeUnknownFields() = default;
  // Reads node (`unknown_fields`); `outputs` are the problem's outputs, `reserved` the names
  // no output may take. The truths are read later (read_truths).
  PdeUnknownFields(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                   const std::vector<std::string>& reserved);

  bool empty() const { return names_.empty(); }
  const std::vector<std::string>& names() const { return names_; }
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
};

}  // namespace nfield::solvers
