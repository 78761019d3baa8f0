// SPDX-License-Identifier: MIT
//
// The Solution (solvers/solution.h) of a field and a problem's ansatz: u = A + D·N with the
// network N in the field's precision, converted to double. The one place where a field and
// its hard conditions are composed for everything that evaluates a trained field (the run's
// outputs and error metrics, `nfield eval`, `nfield render`, the Python module); the trainer
// composes its loss terms instead (with_ansatz on LossTerms, hard_constraints.h).
// The solution refers to `field`, which must outlive it.
#pragma once

#include <memory>

#include "fields/field.h"
#include "solvers/conditions/hard_constraints.h"
#include "solvers/solution.h"

namespace nfield::solvers {

// Null ansatz: the network itself.
template <typename Scalar>
Solution make_solution(const fields::Field<Scalar>& field, std::shared_ptr<const Ansatz> ansatz);

// The values of one scale of a multiscale field (fields/field.h, Field::scales) with the ansatz.
template <typename Scalar>
std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values(const fields::Field<Scalar>& field,
                                                                          std::shared_ptr<const Ansatz> ansatz);

}  // namespace nfield::solvers
