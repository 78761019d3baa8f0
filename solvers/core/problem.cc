// SPDX-License-Identifier: MIT
#include "solvers/core/problem.h"

#include <stdexcept>

namespace nfield::solvers {

Eigen::MatrixXd Problem::exact(const Eigen::MatrixXd&) const {
  throw std::logic_error("this problem has no exact solution");
}

std::vector<Eigen::VectorXd> Problem::held_out_parameters() const {
  if (domain().parameter_count() == 0) return {};
  return {domain().parameter_middles()};
}

void Problem::write_outputs(const OutputContext&, std::vector<std::pair<std::string, double>>&) const {}

}  // namespace nfield::solvers
