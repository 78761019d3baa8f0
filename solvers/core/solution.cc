// SPDX-License-Identifier: MIT
#include "solvers/core/solution.h"

namespace nfield::solvers {

template <typename Scalar>
Solution make_solution(const fields::Field<Scalar>& field, std::shared_ptr<const Ansatz> ansatz) {
  Solution solution;
  solution.values = [&field, ansatz](const Eigen::MatrixXd& x) {
    Eigen::MatrixXd n = field.values(x.cast<Scalar>()).template cast<double>();
    return ansatz ? ansatz->values(x, n) : n;
  };
  const NetworkStreams network = [&field](const autodiff::StreamLayout& layout, const Eigen::MatrixXd& x) {
    autodiff::Streams<double> result;
    if constexpr (std::is_same_v<Scalar, double>) {
      field.evaluate(layout, x, result);
    } else {
      autodiff::Streams<Scalar> out;
      field.evaluate(layout, x.cast<Scalar>(), out);
      result.points = out.points;
      result.count = out.count;
      result.data = out.data.template cast<double>();
    }
    return result;
  };
  solution.streams = with_ansatz(network, std::move(ansatz));
  return solution;
}

template <typename Scalar>
std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values(const fields::Field<Scalar>& field,
                                                                          std::shared_ptr<const Ansatz> ansatz) {
  return [&field, ansatz](const Eigen::MatrixXd& x, int scale) {
    Eigen::MatrixXd n = field.values(x.cast<Scalar>(), scale).template cast<double>();
    return ansatz ? ansatz->values(x, n) : n;
  };
}

template Solution make_solution(const fields::Field<float>&, std::shared_ptr<const Ansatz>);
template Solution make_solution(const fields::Field<double>&, std::shared_ptr<const Ansatz>);
template std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values(const fields::Field<float>&,
                                                                                   std::shared_ptr<const Ansatz>);
template std::function<Eigen::MatrixXd(const Eigen::MatrixXd&, int)> scale_values(const fields::Field<double>&,
                                                                                   std::shared_ptr<const Ansatz>);

}  // namespace nfield::solvers
