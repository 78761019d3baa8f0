// SPDX-License-Identifier: MIT
#include "solvers/core/problem_capabilities.h"

namespace nfield::solvers {

Eigen::Array<bool, Eigen::Dynamic, 1> error_mask(const Problem& problem, const Eigen::MatrixXd& x) {
  if (const auto* masks = capability<MasksError>(problem)) return masks->error_mask(x);
  return Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(x.rows(), true);
}

std::vector<ProblemInstance> instances(const Problem& problem, bool held_out) {
  if (const auto* family = capability<HasInstances>(problem)) return family->instances(held_out);
  return {};
}

}  // namespace nfield::solvers
