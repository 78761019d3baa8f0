// SPDX-License-Identifier: MIT
#include "solvers/problem.h"

#include <stdexcept>

namespace nfield::solvers {

Eigen::MatrixXd Problem::exact(const Eigen::MatrixXd&) const {
  throw std::logic_error("this problem has no exact solution");
}

Eigen::Array<bool, Eigen::Dynamic, 1> Problem::error_mask(const Eigen::MatrixXd& x) const {
  return Eigen::Array<bool, Eigen::Dynamic, 1>::Constant(x.rows(), true);
}

void Problem::render_views(const OutputContext&, const RenderRequest&) const {
  throw std::invalid_argument("this problem's field renders no images (nfield render takes a radiance-field checkpoint, problem: nerf)");
}

std::vector<Eigen::VectorXd> Problem::held_out_parameters() const {
  if (domain().parameter_count() == 0) return {};
  return {domain().parameter_middles()};
}

void Problem::give_input_variances() {
  throw std::logic_error("this problem gives no variances of its points (Problem::gives_input_variances)");
}

void Problem::write_outputs(const OutputContext&, std::vector<std::pair<std::string, double>>&) const {}

}  // namespace nfield::solvers
