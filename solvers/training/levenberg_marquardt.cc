// SPDX-License-Identifier: MIT
#include "solvers/training/levenberg_marquardt.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "io/text.h"
#include "solvers/training/dense_algebra.h"

namespace nfield::solvers {
namespace {

[[noreturn]] void reject_option(const std::string& option, const std::string& value,
                                const std::string& rule) {
  throw std::invalid_argument("lm." + option + " = " + value + ": " + rule);
}

std::string scientific(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%e", value);
  return buffer;
}

}  // namespace

void LevenbergMarquardtOptions::validate() const {
  if (!(initial_radius >= 1e-12 && initial_radius <= 1e16))
    reject_option("initial_radius", io::format_number(initial_radius), "must be in [1e-12, 1e16]");
  if (!(max_radius >= initial_radius && std::isfinite(max_radius)))
    reject_option("max_radius", io::format_number(max_radius), "must be finite and >= initial_radius");
  if (!(min_radius >= 0 && min_radius < initial_radius))
    reject_option("min_radius", io::format_number(min_radius), "must be >= 0 and < initial_radius");
  if (!(min_diagonal > 0 && min_diagonal <= max_diagonal))
    reject_option("min_diagonal", io::format_number(min_diagonal), "must be > 0 and <= max_diagonal");
  if (!(min_relative_decrease >= 0 && min_relative_decrease < 1))
    reject_option("min_relative_decrease", io::format_number(min_relative_decrease), "must be in [0, 1)");
  if (max_consecutive_invalid_steps < 1)
    reject_option("max_consecutive_invalid_steps", std::to_string(max_consecutive_invalid_steps),
                  "must be >= 1");
}

const char* to_string(LmTermination termination) {
  switch (termination) {
    case LmTermination::kConvergence: return "CONVERGENCE";
    case LmTermination::kFailure: return "FAILURE";
    case LmTermination::kRunning: break;
  }
  return "NO_CONVERGENCE";
}

LevenbergMarquardt::LevenbergMarquardt(NormalEquationsProblem& problem,
                                       LevenbergMarquardtOptions options)
    : problem_(problem), options_(options), radius_(options.initial_radius) {
  options_.validate();
}

bool LevenbergMarquardt::evaluate_at(const Eigen::VectorXd& theta) {
  const double cost = problem_.normal_equations(theta, a_, g_);
  if (!std::isfinite(cost) || !g_.allFinite()) return false;
  for (Eigen::Index j = 0; j < a_.cols(); ++j)
    if (!a_.col(j).head(j + 1).allFinite()) return false;
  cost_ = cost;
  return true;
}

bool LevenbergMarquardt::start(const Eigen::VectorXd& theta) {
  termination_ = LmTermination::kRunning;
  message_.clear();
  decrease_factor_ = 2;
  invalid_steps_ = 0;
  theta_ = theta;
  if (!evaluate_at(theta_)) {
    termination_ = LmTermination::kFailure;
    message_ = "Residual and Jacobian evaluation failed.";
    return false;
  }
  const Eigen::Index p = theta_.size();
  scaling_ = Eigen::VectorXd::Ones(p);
  if (options_.jacobi_scaling)
    scaling_ = (1.0 + a_.diagonal().array().sqrt()).inverse().matrix();
  return true;
}

Eigen::VectorXd LevenbergMarquardt::step(double* model_decrease) {
  const Eigen::Index p = theta_.size();
  // The scaled, damped matrix S A S + D/μ (upper triangle), column by column.
  factor_.resize(p, p);
  const Eigen::VectorXd& s = scaling_;
  for (Eigen::Index j = 0; j < p; ++j)
    factor_.col(j).head(j + 1) = a_.col(j).head(j + 1).cwiseProduct(s.head(j + 1)) * s(j);
  for (Eigen::Index j = 0; j < p; ++j)
    factor_(j, j) += std::clamp(factor_(j, j), options_.min_diagonal, options_.max_diagonal) / radius_;
  Eigen::VectorXd y = -s.cwiseProduct(g_);
  {
    const dense::BlasThreads threads(options_.threads, p);
    if (!dense::cholesky_solve(factor_, y) || !y.allFinite()) return {};
  }
  Eigen::VectorXd delta = s.cwiseProduct(y);
  const double decrease = -(g_.dot(delta) + 0.5 * delta.dot(dense::symmetric_product(a_, delta)));
  if (model_decrease) *model_decrease = decrease;
  if (!(decrease > 0)) return {};
  return delta;
}

void LevenbergMarquardt::reject(double /*quality*/) {
  radius_ /= decrease_factor_;
  decrease_factor_ *= 2;
}

LmIteration LevenbergMarquardt::iterate() {
  LmIteration it;
  double model_decrease = 0;
  const Eigen::VectorXd delta = step(&model_decrease);
  it.valid = delta.size() > 0;
  if (!it.valid) {
    if (++invalid_steps_ >= options_.max_consecutive_invalid_steps) {
      termination_ = LmTermination::kFailure;
      message_ = "Number of consecutive invalid steps more than max_consecutive_invalid_steps: " +
                 std::to_string(options_.max_consecutive_invalid_steps);
    } else {
      reject(0.0);
    }
  } else {
    invalid_steps_ = 0;
    const Eigen::VectorXd trial = theta_ + delta;
    it.trial_cost = problem_.cost(trial);
    if (!std::isfinite(it.trial_cost)) it.trial_cost = std::numeric_limits<double>::infinity();
    it.relative_decrease = (cost_ - it.trial_cost) / model_decrease;
    if (it.trial_cost == cost_) {
      termination_ = LmTermination::kConvergence;
      message_ = "Function tolerance reached. |cost_change|/cost: 0 <= 0";
    } else if (it.relative_decrease > options_.min_relative_decrease) {
      const Eigen::VectorXd previous = theta_;
      const double previous_cost = cost_;
      if (!evaluate_at(trial)) {
        // A and g are lost; the run ends at the last iterate.
        termination_ = LmTermination::kFailure;
        message_ = "Residual and Jacobian evaluation failed.";
        theta_ = previous;
        cost_ = previous_cost;
      } else {
        theta_ = trial;
        it.accepted = true;
        const double rho = it.relative_decrease;
        radius_ = std::min(options_.max_radius,
                           radius_ / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
        decrease_factor_ = 2;
      }
    } else {
      reject(it.relative_decrease);
    }
  }
  it.cost = cost_;
  it.radius = radius_;
  if (termination_ == LmTermination::kRunning && radius_ <= options_.min_radius) {
    termination_ = LmTermination::kConvergence;
    message_ = "Minimum trust region radius reached. Trust region radius: " + scientific(radius_) +
               " <= " + scientific(options_.min_radius);
  }
  return it;
}

}  // namespace nfield::solvers
