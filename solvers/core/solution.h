// SPDX-License-Identifier: MIT
//
// The trained solution as everything outside the trainer sees it: the field's network N
// composed with the problem's ansatz, u = A + D·N where conditions are hard (the network
// itself where they are soft), evaluated in double at any points (n × field inputs): its
// values (n × outputs) and, for outputs that read derivatives, its streams.
//
// make_solution builds one from a field and a problem's ansatz (null: the network itself),
// with N in the field's precision, converted to double. The run's outputs and error metrics,
// `nfield eval`, `nfield render`, the Python module and the problems that sample where the
// field is (capability SamplesWithSolution) all read one built this way; the trainer
// composes its loss terms instead (with_ansatz on LossTerms, ansatz.h). It reads the field's
// current parameters at each call (during training it follows the field), and refers to
// `field`, which must outlive it.
#pragma once

#include <functional>
#include <memory>

#include <Eigen/Core>

#include "autodiff/streams.h"
#include "fields/field.h"
#include "solvers/core/ansatz.h"

namespace nfield::solvers {

struct Solution {
  using Values = std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>;
  using Streams =
      std::function<autodiff::Streams<double>(const autodiff::StreamLayout&, const Eigen::MatrixXd&)>;
  Values values;
  Streams streams;
};

// Null ansatz: the network itself.
template <typename Scalar>
Solution make_solution(const fields::Field<Scalar>& field, std::shared_ptr<const Ansatz> ansatz);

// The values of one scale of a multiscale field (fields/field.h, Field::scales) with the ansatz.
template <typename Scalar>
std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values(const fields::Field<Scalar>& field,
                                                                          std::shared_ptr<const Ansatz> ansatz);

}  // namespace nfield::solvers
