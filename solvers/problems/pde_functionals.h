// SPDX-License-Identifier: MIT
//
// Functionals of a `problem: pde` solution: the scalars an engineer reads off a flow or a
// field (the drag and lift on a body, a flux through a face, a pressure difference), computed
// from the trained field after training, in `nfield eval`, and on the progress line.
//
//   functionals:
//     drag:                                        # J = Σᵢ wᵢ e(xᵢ, nᵢ)
//       integral: "p*nx - nu*(2*u_x*nx + (u_y + v_x)*ny)"
//       on: cylinder                               # parts of the geometry, or box faces
//       reference: 0.011159                        # optional: rel_error in metrics.json
//     dp:
//       value: "p"                                 # a weighted sum of point values
//       at: [[0.15, 0.2], [0.25, 0.2]]
//       coefficients: [1, -1]                      # default: all 1
//
// `integral`: ∫ e dS over the named parts, by the deterministic boundary quadrature of
// solvers/geometry/geometry.h (boundary_quadrature: the periodic midpoint rule on a whole
// circle, spectral for smooth integrands; O(h²) on faces), or the midpoint rule on box faces;
// `points` nodes (default 16384). The integrand reads what a residual reads (the outputs,
// their derivatives, the coordinates, the constants) and nx, ny(, nz): the components of the
// domain's outward unit normal, which on a hole points into the hole (out of the fluid). With
// `domain.time` the integral is at `time: T`.
// `value`: Σₖ cₖ e(xₖ) at the listed points (inputs in the field's order: space, then t).
//
// e compiles as a residual does (solvers/problems/pde.cc, compile_residual), so it costs the
// streams of the symbols it reads, and it is evaluated by an ExpressionResidual built once at
// load over the nodes (with the normals as coordinate slots after the inputs).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "autodiff/streams.h"
#include "io/compiled_expression.h"
#include "io/config.h"
#include "solvers/core/domain.h"
#include "solvers/core/problem.h"
#include "solvers/core/residual.h"
#include "solvers/core/unknowns.h"
#include "solvers/problems/pde_streams.h"

namespace nfield::solvers {

// An expression compiled over the coordinates, extra variables and derivative symbols.
struct CompiledReads {
  std::shared_ptr<const io::CompiledExpression> expression;
  std::shared_ptr<const std::vector<std::vector<SymbolTerm>>> symbols;
  std::vector<int> unknown_reads;
  autodiff::StreamSpec spec;
};

// Compiles node[key] with `extra` variable names in the slots after the domain's inputs.
using CompileReads =
    std::function<CompiledReads(const io::ConfigNode& node, const std::string& key, const std::vector<std::string>& extra)>;

class PdeFunctionals {
 public:
  PdeFunctionals() = default;
  // `taken`: names nx, ny, nz may not be (outputs, constants). `unknowns` (may be null): the
  // unknown constants an expression reads, at their values when evaluated. Errors are located
  // ConfigErrors.
  PdeFunctionals(const io::ConfigNode& node, const Domain& domain, const CompileReads& compile,
                 const std::vector<std::string>& taken, std::shared_ptr<const UnknownConstants> unknowns);

  bool empty() const { return items_.empty(); }
  // (name, value) in the config's order.
  std::vector<std::pair<std::string, double>> values(const OutputContext& context) const;
  // Prints one line per functional and adds functional_NAME (and with a reference
  // functional_NAME_reference and functional_NAME_rel_error) to `metrics`.
  void write(const OutputContext& context, std::vector<std::pair<std::string, double>>& metrics) const;

 private:
  // Where a functional evaluates the field, and what it sums there.
  struct Nodes {
    Eigen::MatrixXd inputs;       // n × input_dim: where the field is evaluated
    Eigen::MatrixXd coordinates;  // n × (input_dim + normals): the expression's coordinate slots
    Eigen::VectorXd weights;
  };
  struct Item {
    std::string name;
    autodiff::StreamSpec spec;
    std::shared_ptr<const Residual> expression;  // over Nodes::coordinates
    Eigen::MatrixXd inputs;
    Eigen::VectorXd weights;
    std::optional<double> reference;
  };
  static Nodes integral_nodes(const io::ConfigNode& item, const Domain& domain);
  static Nodes value_nodes(const io::ConfigNode& item, const Domain& domain);

  std::vector<Item> items_;
};

}  // namespace nfield::solvers
