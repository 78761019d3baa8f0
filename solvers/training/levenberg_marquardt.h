// SPDX-License-Identifier: MIT
//
// Levenberg–Marquardt on the normal equations: the trust-region method of Ceres'
// LEVENBERG_MARQUARDT strategy (ceres-solver internal/ceres/levenberg_marquardt_strategy.cc and
// trust_region_minimizer.cc, 2.1), made for dense problems with few parameters and many
// residuals, where all of the work is JᵀJ and its Cholesky factor. The `lm` stage runs it with
// `backend: own` (solvers/training/lm_optimizer.cc); its problem is the loss terms'
// residuals (solvers/training/lm_terms.h).
//
// Problem: minimise C(θ) = ½‖f(θ)‖² over θ ∈ ℝᴾ, f: ℝᴾ → ℝᵐ, with J = ∂f/∂θ. The problem gives
// C at trial points and, at iterates, A = JᵀJ and g = Jᵀf (never J itself: a problem may
// sum them over chunks of rows or over MPI ranks).
//
// One iteration at the iterate θ, radius μ (Ceres' rule, step by step):
//   1. Jacobi scaling (Ceres' jacobi_scaling, on by default): s_j = 1/(1 + √A_jj), computed
//      from the first iterate of a run (start) and kept for the run; with S = diag(s) the
//      scaled system is Â = S A S, ĝ = S g.
//   2. D = diag(Â) clamped to [min_diagonal, max_diagonal] (Ceres' min/max_lm_diagonal).
//   3. Solve (Â + D/μ) y = −ĝ by Cholesky; δ = S y. (Ceres minimises ‖Ĵy + f‖² + ‖√(D/μ) y‖²,
//      whose normal equations these are.) A factorisation that fails or a non-finite y makes
//      the step invalid, as does a model decrease
//         L = −(gᵀδ + ½ δᵀAδ) = ½‖f‖² − ½‖f + Jδ‖²
//      that is not positive. An invalid step counts as a rejected one with quality 0 (rule 6);
//      max_consecutive_invalid_steps of them in a row end the run (FAILURE).
//   4. C at θ + δ; a non-finite value there counts as +∞ (the step is rejected: a NaN trial
//      point never becomes the iterate).
//   5. Step quality ρ = (C(θ) − C(θ + δ)) / L. Accepted when ρ > min_relative_decrease
//      (Ceres: 1e-3): θ ← θ + δ and A, g are evaluated there (a non-finite A or g there ends
//      the run, FAILURE, at the last iterate); then
//         μ ← min(max_radius, μ / max(1/3, 1 − (2ρ − 1)³)),   ν ← 2.
//   6. Rejected: μ ← μ / ν, ν ← 2ν (ν starts at 2 in each run).
//   7. μ ≤ min_radius ends the run (CONVERGENCE: no step lowers C any more); so does a trial
//      point with exactly C(θ) (Ceres' function_tolerance check at 0, as the stage runs Ceres).
// Ceres' gradient, function and parameter tolerances are not kept otherwise: the stage runs
// them at 0 (it takes the steps asked for).
//
// What differs from Ceres' dense normal Cholesky (the work, not the iterates: same rule,
// same steps up to round-off): A is formed once per accepted iterate, by BLAS syrk on all the
// training's threads, and kept for rejected steps, which then cost one Cholesky factor only
// (Ceres re-forms JᵀJ, on one thread, for every solve); the factor is blocked over LAPACK's
// potrf and BLAS's trsm and syrk (solvers/training/dense_algebra.h).
// Memory: two P × P matrices (A and the factor) and no m × P Jacobian beyond what the
// problem keeps.
#pragma once

#include <Eigen/Core>

#include <string>

namespace nfield::solvers {

struct LevenbergMarquardtOptions {
  double initial_radius = 1e4;            // μ at the start (Ceres' initial_trust_region_radius)
  double max_radius = 1e16;               // Ceres' max_trust_region_radius
  double min_radius = 1e-32;              // Ceres' min_trust_region_radius
  double min_diagonal = 1e-6;             // Ceres' min_lm_diagonal
  double max_diagonal = 1e32;             // Ceres' max_lm_diagonal
  double min_relative_decrease = 1e-3;    // Ceres' min_relative_decrease
  int max_consecutive_invalid_steps = 5;  // Ceres' max_num_consecutive_invalid_steps
  bool jacobi_scaling = true;             // Ceres' jacobi_scaling
  int threads = 0;                        // BLAS/LAPACK threads (0: OpenMP's default)

  // std::invalid_argument naming the option, its value and the rule.
  void validate() const;
};

// The least-squares problem as the method sees it.
class NormalEquationsProblem {
 public:
  virtual ~NormalEquationsProblem() = default;
  virtual Eigen::Index parameter_count() const = 0;
  // ½‖f(θ)‖² (non-finite where f is).
  virtual double cost(const Eigen::VectorXd& theta) = 0;
  // At θ: A = JᵀJ (upper triangle; resized P × P and overwritten) and g = Jᵀf; returns ½‖f‖².
  virtual double normal_equations(const Eigen::VectorXd& theta, Eigen::MatrixXd& jtj,
                                  Eigen::VectorXd& jtf) = 0;
};

// How a run ended (Ceres' names, for the stage's report).
enum class LmTermination { kRunning, kConvergence, kFailure };
const char* to_string(LmTermination termination);

// One iteration, as it happened.
struct LmIteration {
  bool valid = false;     // the solve gave a step with a positive model decrease
  bool accepted = false;  // θ moved
  double cost = 0;        // C at the iterate after the iteration
  double trial_cost = 0;  // C at θ + δ (+∞ where not finite; 0 when invalid)
  double relative_decrease = 0;  // ρ
  double radius = 0;             // μ after the update
};

class LevenbergMarquardt {
 public:
  LevenbergMarquardt(NormalEquationsProblem& problem, LevenbergMarquardtOptions options);

  // Starts a run at θ: evaluates A and g there and fixes the Jacobi scaling, with the radius
  // options.initial_radius (or the one set_radius gave). False, and termination() FAILURE,
  // when C, A or g is not finite there.
  bool start(const Eigen::VectorXd& theta);
  // One iteration (call while termination() is kRunning).
  LmIteration iterate();

  const Eigen::VectorXd& parameters() const { return theta_; }
  double cost() const { return cost_; }
  double radius() const { return radius_; }
  // The radius the next start begins with (a stage's segments carry it over).
  void set_radius(double radius) { radius_ = radius; }
  LmTermination termination() const { return termination_; }
  const std::string& message() const { return message_; }

  // The step δ of rule 3 at the current iterate and radius, or an empty vector when the
  // step is invalid (for tests and the iteration itself).
  Eigen::VectorXd step(double* model_decrease = nullptr);

 private:
  void reject(double quality);
  bool evaluate_at(const Eigen::VectorXd& theta);

  NormalEquationsProblem& problem_;
  LevenbergMarquardtOptions options_;
  Eigen::VectorXd theta_, g_, scaling_;
  Eigen::MatrixXd a_, factor_;
  double cost_ = 0;
  double radius_;
  double decrease_factor_ = 2;
  int invalid_steps_ = 0;
  LmTermination termination_ = LmTermination::kRunning;
  std::string message_;
};

}  // namespace nfield::solvers
