// SPDX-License-Identifier: MIT
//
// The hard items of a `conditions:` list (solvers/conditions/condition_list.h) as the ansatz
// u = A + D·N (solvers/core/ansatz.h: the forms of A and D, the streams, the adjoint).
#pragma once

#include <memory>
#include <vector>

#include "solvers/core/ansatz.h"

namespace nfield::solvers {

struct ConditionItem;

// The ansatz of the hard items of a `conditions:` list (read_conditions,
// solvers/conditions/condition_list.h); null when there are none. Config errors: a second
// hard initial value or velocity, hard velocity without a hard value, different values on
// hard Dirichlet faces, a t-dependent hard Dirichlet value together with hard initial data,
// incompatible initial data on hard faces.
std::shared_ptr<const Ansatz> read_ansatz(const std::vector<ConditionItem>& items, const Domain& domain,
                                          int output_dim);

}  // namespace nfield::solvers
