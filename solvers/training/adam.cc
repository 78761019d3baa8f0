// SPDX-License-Identifier: MIT
#include "solvers/training/adam.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nfield::solvers {

void AdamOptions::validate() const {
  auto reject = [](const char* field, double value, const char* rule) {
    throw std::invalid_argument(std::string("adam.") + field + " = " + std::to_string(value) +
                                ": " + rule);
  };
  if (!(learning_rate > 0)) reject("lr", learning_rate, "must be > 0");
  if (!(beta1 >= 0 && beta1 < 1)) reject("beta1", beta1, "must be in [0, 1)");
  if (!(beta2 >= 0 && beta2 < 1)) reject("beta2", beta2, "must be in [0, 1)");
  if (!(epsilon > 0)) reject("epsilon", epsilon, "must be > 0");
}

template <typename Scalar>
Adam<Scalar>::Adam(Eigen::Index parameter_count, AdamOptions options) : options_(options) {
  options_.validate();
  m_.setZero(parameter_count);
  v_.setZero(parameter_count);
}

template <typename Scalar>
void Adam<Scalar>::step(Scalar* params, const Scalar* gradient, double learning_rate) {
  ++t_;
  const Eigen::Index n = m_.size();
  Eigen::Map<autodiff::Vector<Scalar>> theta(params, n);
  const Eigen::Map<const autodiff::Vector<Scalar>> g(gradient, n);
  const Scalar b1 = static_cast<Scalar>(options_.beta1), b2 = static_cast<Scalar>(options_.beta2);
  m_ = b1 * m_ + (Scalar(1) - b1) * g;
  v_ = b2 * v_ + (Scalar(1) - b2) * g.cwiseAbs2();
  const double c1 = 1.0 - std::pow(options_.beta1, static_cast<double>(t_));
  const double c2 = 1.0 - std::pow(options_.beta2, static_cast<double>(t_));
  const Scalar step = static_cast<Scalar>(learning_rate / c1);
  const Scalar root_c2 = static_cast<Scalar>(std::sqrt(c2));
  const Scalar eps = static_cast<Scalar>(options_.epsilon);
  std::vector<Scalar> before;
  for (const auto& entry : rate_scales_) before.push_back(theta(entry.first));
  theta.array() -= step * m_.array() / (v_.array().sqrt() / root_c2 + eps);
  for (std::size_t k = 0; k < rate_scales_.size(); ++k) {
    const auto [i, scale] = rate_scales_[k];
    theta(i) = before[k] - static_cast<Scalar>(learning_rate * scale / c1) * m_(i) / (std::sqrt(v_(i)) / root_c2 + eps);
  }
}

template class Adam<float>;
template class Adam<double>;

}  // namespace nfield::solvers
