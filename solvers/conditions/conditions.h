// SPDX-License-Identifier: MIT
//
// Boundary and initial conditions from the `conditions:` list of a config:
//
//   - {on: boundary, type: dirichlet, value: "0"}            u = g on every space face
//   - {on: [x_min, y_max], type: neumann, value: "x*y"}      ∂u/∂n = g (outward normal)
//   - {on: initial, type: value, value: "sin(pi*x)"}         u(x, t0) = g
//   - {on: initial, type: velocity, value: "0"}              u_t(x, t0) = g
//
// `value` is one expression, or a list with one per output channel (complex fields: real,
// imaginary). `weight` (default 1) scales the term. Each condition is one loss term drawing
// its points from the `boundary` (faces) or `initial` batch.
//
// `enforce: hard` (default soft) makes a Dirichlet or initial value/velocity condition exact
// instead: no loss term, the field's output becomes u = A + D·N (solvers/conditions/hard_constraints.h
// has the ansatz and its limits). Neumann conditions stay soft. Only problems that pass the
// `ansatz` out-parameter (poisson, wave, pde) accept hard items; others reject them.
#pragma once

#include <memory>
#include <vector>

#include "io/config.h"
#include "solvers/conditions/condition_values.h"
#include "solvers/residual.h"

namespace nfield::solvers {

class Ansatz;
// `constants`: named numbers the value expressions may read (problem: pde's `constants`).
std::vector<LossTerm> condition_terms(const io::ConfigNode& conditions, const Domain& domain,
                                      int output_dim,
                                      std::shared_ptr<const Ansatz>* ansatz = nullptr,
                                      const io::ExpressionConstants& constants = {});

}  // namespace nfield::solvers
