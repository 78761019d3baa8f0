// SPDX-License-Identifier: MIT
//
// The loss terms of the soft items of a `conditions:` list (read by read_conditions,
// solvers/conditions/condition_list.h, which documents the keys):
//
//   dirichlet   r = u − g                         on the faces, per constrained output
//   neumann     r = ∂u/∂n − g                     n the outward normal of the point's face
//   robin       r = a u + b ∂u/∂n − g
//   periodic    r = (u(p) − u(p'), ∂ₐu(p) − ∂ₐu(p'))   p on the lower face of axis a, p' its
//               partner on the upper face (groups of two points)
//   initial     r = u(x, t0) − g,  velocity: r = u_t(x, t0) − g
//
// Each is one loss term drawing its points from the `boundary` (faces) or `initial` batch,
// named after its type (dirichlet, neumann, robin, periodic, initial, initial_velocity) with
// _i appended for item i > 0. An output an item leaves free (the mapping form of `value`)
// has no component in its residual. Hard items give no term (the ansatz enforces them;
// solvers/conditions/hard_constraints.h), residual items neither (problem: pde compiles them
// with its equation residuals).
#pragma once

#include <vector>

#include "solvers/conditions/condition_list.h"
#include "solvers/core/residual.h"

namespace nfield::solvers {

// `domain` must outlive the terms (their samplers read it).
std::vector<LossTerm> condition_terms(const std::vector<ConditionItem>& items, const Domain& domain);

}  // namespace nfield::solvers
