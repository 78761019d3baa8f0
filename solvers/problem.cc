// SPDX-License-Identifier: MIT
#include "solvers/problem.h"
#include "solvers/problem_capabilities.h"

#include <stdexcept>

namespace nfield::solvers {

Eigen::MatrixXd Problem::exact(const Eigen::MatrixXd&) const {
  throw std::logic_error("this problem has no exact solution");
}

Eigen::Array<bool, Eigen::Dynamic, 1> error_mask(const Problem& problem, const Eigen::MatrixXd& x) {
  if (const auto* masks = capability<MasksError>(problem)) return masks->error_mask(x);
  return Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(x.rows(), true);
}

void Problem::write_outputs(const OutputContext&, std::vector<std::pair<std::string, double>>&) const {}

}  // namespace nfield::solvers
