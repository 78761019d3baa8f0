// SPDX-License-Identifier: MIT
#include "solvers/problems/burgers_reference.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace nfield::solvers {
namespace {

constexpr double kPi = std::numbers::pi;

[[noreturn]] void reject(const char* field, double value, const char* rule) {
  std::ostringstream out;
  out << "BurgersSineOptions." << field << " = " << value << ": " << rule;
  throw std::invalid_argument(out.str());
}

}  // namespace

void BurgersSineOptions::validate() const {
  if (!(nu >= 1e-4 && nu <= 1e3)) reject("nu", nu, "must be in [1e-4, 1e3]");
  if (!(spacing > 0 && spacing <= 0.05)) reject("spacing", spacing, "must be in (0, 0.05]");
}

double burgers_sine_solution(double x, double t, const BurgersSineOptions& options) {
  options.validate();
  if (!(t >= 0 && t <= 10) || !std::isfinite(x))
    throw std::invalid_argument("burgers_sine_solution: needs a finite x and t in [0, 10], got x = " +
                                std::to_string(x) + ", t = " + std::to_string(t));
  if (t == 0) return -std::sin(kPi * x);
  const double s = std::sqrt(4 * options.nu * t);
  const double reach = std::sqrt(1 / (kPi * options.nu) + 40);
  const int half = static_cast<int>(std::ceil(reach / options.spacing));
  const double scale = 1 / (2 * kPi * options.nu);
  // Exponents first, then the sums of exp(E − max E): the raw weights span e^{±1/(2πν)}.
  std::vector<double> exponent(2 * half + 1), sine(2 * half + 1);
  double largest = -INFINITY;
  for (int k = -half; k <= half; ++k) {
    const double z = k * options.spacing, y = kPi * (x - s * z);
    exponent[k + half] = -z * z - std::cos(y) * scale;
    sine[k + half] = std::sin(y);
    largest = std::max(largest, exponent[k + half]);
  }
  double numerator = 0, denominator = 0;
  for (size_t k = 0; k < exponent.size(); ++k) {
    const double w = std::exp(exponent[k] - largest);
    numerator += sine[k] * w;
    denominator += w;
  }
  return -numerator / denominator;
}

Eigen::VectorXd burgers_sine_solution(const Eigen::MatrixXd& points, const BurgersSineOptions& options) {
  if (points.cols() != 2)
    throw std::invalid_argument("burgers_sine_solution: needs points (x, t) as n x 2, got n x " +
                                std::to_string(points.cols()));
  options.validate();
  Eigen::VectorXd u(points.rows());
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    try {
      u(i) = burgers_sine_solution(points(i, 0), points(i, 1), options);
    } catch (...) {
#pragma omp critical
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  return u;
}

}  // namespace nfield::solvers
