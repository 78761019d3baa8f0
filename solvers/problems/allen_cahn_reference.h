// SPDX-License-Identifier: MIT
//
// A reference solution of the Allen–Cahn benchmark (Raissi, Perdikaris & Karniadakis 2019,
// §4.2; PINNacle), computed by a Fourier spectral method:
//
//   u_t = ε u_xx + ρ (u − u³),   x ∈ [−1, 1] periodic, t ∈ [0, T],   u(x, 0) = x² cos πx,
//
// with ε = 1e-4 and ρ = 5 (the benchmark's u_t − 0.0001 u_xx + 5u³ − 5u = 0).
//
// Space: N equally spaced nodes x_j = −1 + 2j/N, j = 0 … N − 1, and the discrete Fourier
// transform v_m of u, wavenumbers k_m = π m (period 2), m = −N/2 … N/2 − 1. The linear part
// is diagonal there, L_m = −ε k_m², and is integrated exactly; the reaction is taken on the
// nodes (pseudo-spectral, no dealiasing: the cubic's aliased modes lie where the spectrum is
// already below rounding once N resolves the fronts).
//
// Time: ETDRK4 (Cox & Matthews 2002) with the coefficients of Kassam & Trefethen (2005),
// the φ-functions of hL evaluated as means over M = 32 points of a circle of radius 1 around
// each hL_m, so that they do not cancel catastrophically where |hL| is small. Fourth order in
// h; stable here for h up to about 0.05 (the reaction's rate is at most 10 where |u| ≤ 1).
//
// Pitfalls: u(x, 0) is periodic in value (−1 at both ends) but not in slope (u_x = ∓2 at
// x = ±1): a kink that the diffusion smooths only over √(εt) ≈ 0.01, so the spectrum decays
// slowly at first: N = 1024 and 2048 differ by up to 4e-4 next to x = ±1 before t ≈ 0.1,
// by 2e-6 after t = 0.3 and 2e-9 at t = 1 (tests/solvers/problems/allen_cahn_reference_test.cc). The fronts that form are √(2ε/ρ) ≈ 6e-3 wide: N = 512 puts two or three nodes
// across one; the default 1024 puts five.
//
// Between the kept snapshots the solution is the Fourier interpolant in x (exact for the
// discrete solution) and cubic Lagrange in t over the four nearest snapshots.
#pragma once

#include <Eigen/Core>

namespace nfield::solvers {

struct AllenCahnOptions {
  double diffusion = 1e-4;  // ε > 0
  double reaction = 5;      // ρ ≥ 0
  int modes = 1024;         // N: nodes and Fourier modes, even, 16 … 65536
  double dt = 1e-3;         // the largest time step h; each snapshot interval takes a whole number of steps
  double t_end = 1;         // T > 0
  int snapshots = 201;      // solutions kept over [0, T], equally spaced, ≥ 4

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

class AllenCahnReference {
 public:
  // Solves the problem (the cost: T/h steps of four FFT pairs of size N; timed in
  // docs/experiments.md).
  explicit AllenCahnReference(const AllenCahnOptions& options = {});

  const AllenCahnOptions& options() const { return options_; }
  // u on the nodes at each snapshot: row k at time t_k = k T / (snapshots − 1), column j at x_j.
  const Eigen::MatrixXd& snapshots() const { return values_; }
  double time(int k) const;
  double node(int j) const;

  // u at (x, t): x any real (periodic), t ∈ [0, T]. Throws std::invalid_argument outside.
  double operator()(double x, double t) const;
  // u at each row (x, t) of `points` (n × 2), in parallel over the rows.
  Eigen::VectorXd evaluate(const Eigen::MatrixXd& points) const;

 private:
  double interpolate_in_x(int snapshot, double x) const;

  AllenCahnOptions options_;
  Eigen::MatrixXd values_;        // snapshots × N
  Eigen::MatrixXcd coefficients_;  // snapshots × N: the DFT of each row over N
};

}  // namespace nfield::solvers
