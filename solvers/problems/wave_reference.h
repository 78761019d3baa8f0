// SPDX-License-Identifier: MIT
//
// A finite-difference reference solution of the wave equation
//
//   u_tt = c(x, t)² Δu + f(x, t)   on a box [lower, upper] ⊂ Rᵈ (d = 1–3), t ∈ [t0, t1],
//   u = g (Dirichlet) or ∂u/∂n = g (Neumann) on each face,  u(·, t0) = u0,  u_t(·, t0) = v0,
//
// for the error metrics of a wave problem that has no closed form (configs/wave_2d.yaml's
// Gaussian pulse). The problem file (wave.cc) reads `equation.reference` into
// WaveReferenceOptions and the `conditions:` list into WaveReferenceData.
//
// The scheme. Nodes xᵢ on a uniform grid with spacing h_a = (upper_a − lower_a)/N_a, the
// (2d+1)-point Laplacian Δ_h, and leapfrog in time:
//
//   uⁿ⁺¹ = 2uⁿ − uⁿ⁻¹ + Δt² (c² Δ_h uⁿ + fⁿ),   u¹ = u⁰ + Δt v0 + ½Δt² (c² Δ_h u⁰ + f⁰).
//
// Both differences are second order, so the error falls like h² once Δt ∝ h (the test
// wave_reference_test.cc shows the factor 4 per halving of h against a standing wave). The
// scheme is stable for c_max Δt √(Σ_a 1/h_a²) ≤ 1; Δt is `cfl` times that limit, shortened so
// that a whole number of steps spans the time between snapshots. Dirichlet nodes take
// g(x, tⁿ⁺¹); on a Neumann face the ghost node beyond it is its mirror image plus 2h·g (a
// central difference of the outward derivative). Where faces of both kinds meet, the
// Dirichlet value wins.
//
// What is kept: u and u_t at `snapshots` times spread evenly over [t0, t1] (u_t from the
// central difference (uⁿ⁺¹ − uⁿ⁻¹)/2Δt, v0 at t0), as float. values() interpolates them:
// Catmull–Rom cubics in each space axis (third order; clamped at the faces) and the cubic
// Hermite polynomial in t, whose error, Δ⁴ max|u_tttt|/384 for a snapshot spacing Δ, is far
// below the scheme's at the default settings.
//
// Pitfalls: a speed or source that depends on t is evaluated on every node at every step
// (muparser), which dominates the cost; memory is 2 · 4 bytes · nodes · snapshots
// (512² nodes and 101 snapshots: 212 MB), checked against a 4 GiB limit.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "io/expression.h"
#include "solvers/core/domain.h"

namespace nfield::solvers {

struct WaveReferenceOptions {
  // Cells along the longest side of the box; the other sides get cells of about the same
  // size. 0: 4096 in 1D, 512 in 2D, 96 in 3D.
  int cells = 0;
  double cfl = 0.5;     // Δt as a share of the stability limit, in (0, 1]
  int snapshots = 101;  // ≥ 2, kept times including t0 and t1
};

// One face's condition.
struct WaveFaceCondition {
  bool dirichlet = true;  // else Neumann: ∂u/∂n = value along the outward normal
  io::Expression value{"0"};
};

// Expressions over the domain's variables in its column order (x…, t).
struct WaveReferenceData {
  io::Expression speed{"1"}, source{"0"}, initial_value{"0"}, initial_velocity{"0"};
  // Indexed 2·axis + (upper ? 1 : 0); every face needs one.
  std::vector<std::optional<WaveFaceCondition>> faces;
};

class WaveReference {
 public:
  // Solves up to t1. Throws std::invalid_argument for a domain without time, a face without
  // a condition, options out of range or too much memory (the message names the option);
  // std::runtime_error when the speed is not positive and finite at a node, or the solution
  // stops being finite. `progress`, when set, is called about every two seconds with the
  // steps done and their total.
  WaveReference(const Domain& domain, const WaveReferenceData& data, const WaveReferenceOptions& options,
                std::function<void(long, long)> progress = nullptr);

  // u at the rows of x (n × (space_dim + 1), t last); points outside the box or time
  // interval are clamped into them.
  Eigen::VectorXd values(const Eigen::MatrixXd& x) const;

  const std::array<int, 3>& cells() const { return cells_; }
  double time_step() const { return dt_; }
  long steps() const { return steps_; }

 private:
  Eigen::Index node(const std::array<int, 3>& i) const {
    return i[0] + static_cast<Eigen::Index>(stride_[1]) * i[1] + static_cast<Eigen::Index>(stride_[2]) * i[2];
  }
  double interpolate_space(const Eigen::VectorXf& snapshot, const Eigen::RowVectorXd& x) const;
  // The constructor's steps: the grid from the domain and options (checked), Δt, the time loop.
  struct Stepper;  // nodes, coefficients and boundary values of the leapfrog (wave_reference.cc)
  Eigen::Index set_up_grid(const Domain& domain, const WaveReferenceData& data,
                           const WaveReferenceOptions& options);
  long choose_time_step(Stepper& stepper, const WaveReferenceOptions& options);
  void march(Stepper& stepper, long steps_per_snapshot, const std::function<void(long, long)>& progress);

  int dim_ = 0;
  std::array<int, 3> cells_{0, 0, 0};       // N_a (1 beyond dim_: a single node)
  std::array<Eigen::Index, 3> stride_{1, 1, 1};
  std::array<double, 3> lower_{0, 0, 0}, h_{1, 1, 1};
  double t0_ = 0, t1_ = 0, dt_ = 0, snapshot_spacing_ = 0;
  long steps_ = 0;
  std::vector<Eigen::VectorXf> u_, u_t_;  // per snapshot, per node
};

}  // namespace nfield::solvers
