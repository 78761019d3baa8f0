// SPDX-License-Identifier: MIT
//
// The trained solution as everything outside the trainer sees it: the field's network N
// composed with the problem's ansatz, u = A + D·N where conditions are hard (the network
// itself where they are soft), evaluated in double at any points (n × field inputs): its
// values (n × outputs) and, for outputs that read derivatives, its streams.
//
// One is built per run from the field in training (solvers/output/grid_output.h,
// make_solution); the outputs, `nfield eval`, the Python module and the problems that sample
// where the field is (Problem capability SamplesWithSolution) all read the same one. It reads
// the field's current parameters at each call: during training it follows the field.
#pragma once

#include <functional>

#include <Eigen/Core>

#include "autodiff/streams.h"

namespace nfield::solvers {

struct Solution {
  using Values = std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)>;
  using Streams =
      std::function<autodiff::Streams<double>(const autodiff::StreamLayout&, const Eigen::MatrixXd&)>;
  Values values;
  Streams streams;
};

}  // namespace nfield::solvers
