// SPDX-License-Identifier: MIT
//
// The Cole–Hopf solution of the Burgers benchmark (solvers/problems/burgers_reference.h)
// against the equation itself: a fine finite-difference solution (central differences of the
// flux u²/2 and of u_xx, RK4 in time) approaches it as its grid is refined, at the second
// order of the scheme, and the quadrature agrees with itself at half the node spacing.
#include "solvers/problems/burgers_reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace nfield::solvers {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNu = 0.01 / kPi;

// u on the nodes x_i = −1 + 2i/n at each of `times` (ascending), from u(x, 0) = −sin πx with
// u(±1, t) = 0.
std::vector<Eigen::VectorXd> finite_differences(int n, const std::vector<double>& times) {
  const double dx = 2.0 / n;
  Eigen::VectorXd u(n + 1);
  for (int i = 0; i <= n; ++i) u(i) = -std::sin(kPi * (-1 + i * dx));
  u(0) = u(n) = 0;
  const auto rate = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(n + 1);
    for (int i = 1; i < n; ++i)
      r(i) = -(v(i + 1) * v(i + 1) - v(i - 1) * v(i - 1)) / (4 * dx) +
             kNu * (v(i + 1) - 2 * v(i) + v(i - 1)) / (dx * dx);
    return r;
  };
  std::vector<Eigen::VectorXd> out;
  double t = 0;
  for (const double until : times) {
    // RK4 is stable for diffusion up to ν dt/dx² ≈ 0.69; the advection number is far below 1.
    const int steps = static_cast<int>(std::ceil((until - t) / (0.4 * dx * dx / kNu)));
    const double dt = (until - t) / steps;
    for (int k = 0; k < steps; ++k) {
      const Eigen::VectorXd k1 = rate(u), k2 = rate(u + 0.5 * dt * k1), k3 = rate(u + 0.5 * dt * k2),
                            k4 = rate(u + dt * k3);
      u += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    t = until;
    out.push_back(u);
  }
  return out;
}

double relative_l2(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).norm() / b.norm(); }

TEST(BurgersReference, FiniteDifferencesConvergeToIt) {
  const std::vector<double> times{0.25, 0.5, 1.0};
  std::vector<std::vector<double>> errors;  // [grid][time]
  for (const int n : {512, 1024, 2048}) {
    const std::vector<Eigen::VectorXd> fd = finite_differences(n, times);
    Eigen::MatrixXd points(n + 1, 2);
    for (int i = 0; i <= n; ++i) points(i, 0) = -1 + 2.0 * i / n;
    errors.emplace_back();
    for (size_t k = 0; k < times.size(); ++k) {
      points.col(1).setConstant(times[k]);
      errors.back().push_back(relative_l2(fd[k], burgers_sine_solution(points, {.nu = kNu})));
      std::printf("n = %4d, t = %.2f: relative L2 difference %.3e\n", n, times[k], errors.back().back());
    }
  }
  for (size_t k = 0; k < times.size(); ++k) {
    // Second order: a quarter per halving of dx (4.0 measured at every time, 2026-11-26).
    EXPECT_GT(errors[0][k] / errors[1][k], 3.5) << "t = " << times[k];
    EXPECT_GT(errors[1][k] / errors[2][k], 3.5) << "t = " << times[k];
  }
  // The finest grid is within 1e-4 of it at t = 1, after the shock has formed (8.1e-5).
  EXPECT_LT(errors[2][2], 1e-4);
}

TEST(BurgersReference, QuadratureHasConvergedAndKeepsTheBoundaryAndSymmetry) {
  for (const double t : {0.0, 1e-3, 0.3, 1 / kPi, 1.0, 3.0}) {
    SCOPED_TRACE(t);
    for (const double x : {-1.0, -0.5, -1e-3, 0.0, 2e-3, 0.37, 1.0}) {
      const double u = burgers_sine_solution(x, t, {.nu = kNu});
      EXPECT_NEAR(u, burgers_sine_solution(x, t, {.nu = kNu, .spacing = 0.01}), 1e-13);
      EXPECT_NEAR(u, -burgers_sine_solution(-x, t, {.nu = kNu}), 1e-13);  // odd in x
      EXPECT_LE(std::abs(u), 1.0);
    }
    EXPECT_NEAR(burgers_sine_solution(1.0, t, {.nu = kNu}), 0.0, 1e-13);
  }
  // Inside the shock at t = 1: steep (the published figure, Raissi et al. Fig. 1).
  const double left = burgers_sine_solution(-0.01, 1.0), right = burgers_sine_solution(0.01, 1.0);
  EXPECT_GT(left, 0.5);
  EXPECT_LT(right, -0.5);
  EXPECT_THROW(burgers_sine_solution(0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(burgers_sine_solution(0.1, 0.5, {.nu = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
