// SPDX-License-Identifier: MIT
//
// The exact solution of the viscous Burgers benchmark (Raissi, Perdikaris & Karniadakis 2019,
// §3.1; Basdevant et al. 1986):
//
//   u_t + u u_x = ν u_xx,   x ∈ [−1, 1], t ≥ 0,   u(x, 0) = −sin πx,   u(±1, t) = 0,
//
// from the Cole–Hopf transform. u = −2ν φ_x/φ turns the equation into the heat equation
// φ_t = ν φ_xx with φ(y, 0) = exp(−cos(πy)/(2πν)) (up to a constant factor), whose solution on
// the whole line is φ convolved with the heat kernel. The initial value is odd about x = 0
// and about x = ±1 and so is the whole-line solution: it vanishes on x = ±1 and is the
// solution of the problem on [−1, 1]. With η = x − y = √(4νt)·z:
//
//   u(x, t) = − ∫ sin(π(x − sz)) w(z) dz / ∫ w(z) dz,
//   w(z) = exp(−z² − cos(π(x − sz))/(2πν)),   s = √(4νt).
//
// Both integrals are taken by the trapezoidal rule over z ∈ [−Z, Z]: w is smooth and decays
// like a Gaussian, so the rule converges faster than any power of the node spacing (the test
// shows spacings 0.02 and 0.01 agree to rounding). Z must make e^{−Z²} negligible against
// the largest ratio of w's second factor, e^{1/(πν)}: Z² = 1/(πν) + 40.
//
// Pitfalls: for ν = 0.01/π that factor spans e^{±50}; the exponent is shifted by its largest
// value before exp, or the sums overflow. The rule needs each peak of w resolved: where the
// cosine is −1 the exponent's curvature is −2 − 2πt whatever ν, so a peak is about
// 1/√(2 + 2πt) wide, 0.12 at t = 10; the default spacing takes six nodes across it. Times
// above 10 and ν below 1e-4 (Z of 57) are refused. Cost: 2Z/h ≈ 1,200 exponentials a point
// at ν = 0.01/π.
#pragma once

#include <Eigen/Core>

namespace nfield::solvers {

struct BurgersSineOptions {
  double nu = 0.01 / 3.14159265358979323846;  // the viscosity ν > 0
  double spacing = 0.02;                       // node spacing in z of the trapezoidal rule

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

// u at one point (x ∈ R, t ∈ [0, 10]).
double burgers_sine_solution(double x, double t, const BurgersSineOptions& options = {});

// u at each row (x, t) of `points` (n × 2), in parallel over the rows.
Eigen::VectorXd burgers_sine_solution(const Eigen::MatrixXd& points, const BurgersSineOptions& options = {});

}  // namespace nfield::solvers
