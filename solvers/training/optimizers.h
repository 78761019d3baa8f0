// SPDX-License-Identifier: MIT
//
// The optimizers of the library and their stage options (the keys of
// `training.stages[i]` besides `optimizer` and `steps`; solvers/training/training_options.h lists
// them). register_optimizers() in optimizers.cc adds them to the registry of
// solvers/training/optimizer.h; adding one adds its class there and one line.
//
//   adam   each step draws new points for every term (every `resample_every` steps),
//          sums the terms' parameter gradients (one chunked forward/reverse pass per term)
//          and takes one Adam step at the stage's scheduled learning rate.
//   lbfgs  draws one point set per term and minimizes the summed loss on it with Ceres'
//          L-BFGS (ceres::GradientProblemSolver), one step per Ceres iteration.
//   lm     draws one point set per term and minimizes the same loss as a least-squares
//          problem by Levenberg–Marquardt: N·C residuals √(w/N)·r per loss term at the
//          term's points, so ½Σf² is half the loss (solvers/training/lm_terms.h). Jacobian
//          rows come from the reverse pass per point (Sequential::residuals_and_jacobian), in
//          the training scalar, converted to double. One step per LM iteration, a rejected
//          step included. Two backends, with the same trust-region rule:
//            own    (default) the normal equations JᵀJ δ = −Jᵀf damped as Ceres' LM damps them,
//                   JᵀJ by BLAS syrk on the training's threads, solved by LAPACK's Cholesky
//                   (solvers/training/levenberg_marquardt.h); over MPI ranks one allreduce of
//                   JᵀJ and Jᵀf. Memory 2·P² doubles; time m·P² (+ P³/3) per accepted step.
//            ceres  Ceres' LEVENBERG_MARQUARDT (ceres::Problem, one parameter block θ, one cost
//                   function per loss term), its dense linear solver the stage's
//                   linear_solver: it factors the (Σ N·C) × P Jacobian (memory and time as
//                   N·P and N·P², on one thread); over MPI the Jacobian rows are gathered.
//          Both suit small fields (P up to a few thousand) and a few thousand points.
//
// (An L-BFGS or LM stage restarts its history, and draws new points, when resumed.)
#pragma once

#include <Eigen/Core>

#include <string>

#include "io/registry.h"
#include "solvers/training/optimizer.h"

namespace nfield::solvers {

// validate() throws std::invalid_argument naming the option, its value and the rule
// ("lm.initial_radius = 0: must be in [1e-12, 1e16]"); the config reader reports the same
// rules at the key.

struct AdamStageOptions {
  double lr = 1e-3;                   // initial learning rate
  std::string schedule = "constant";  // constant | cosine | exponential
  double lr_final = 1e-5;             // learning rate at the last step (cosine, exponential)
  double seconds = 0;                 // > 0 ends the stage after this much wall time

  void validate() const;
  // The learning rate at step `step` (0-based) of a stage of `steps` steps.
  double learning_rate(int step, int steps) const;
  // The same at a fraction of the stage done, in [0, 1].
  double learning_rate_at(double progress) const;
};

struct LbfgsStageOptions {
  int memory = 20;         // history length
  int resample_every = 0;  // new points every k iterations (0: one set for the stage)

  void validate() const;
};

struct LmStageOptions {
  std::string backend = "own";                          // own | ceres
  // dense_normal_cholesky | dense_qr (ceres only; the config's default with backend: ceres)
  std::string linear_solver = "dense_normal_cholesky";
  double initial_radius = 1e4;  // the initial trust-region radius (Ceres' name and default)
  int resample_every = 0;                  // new points every k iterations (0: one set)

  void validate() const;
};

// Ceres' dense solvers index the Jacobian with an int: for rows × parameters beyond 2³¹ − 1,
// the end of a message ("R residuals x P parameters, more than … ; use fewer points …");
// empty when it fits. The lm stage refuses to start such a problem, load_run such a config.
std::string lm_jacobian_too_large(double rows, Eigen::Index parameters);
// The own backend's limit: P² entries of JᵀJ indexed by BLAS's int ("P x P (parameters), …").
std::string lm_normal_equations_too_large(Eigen::Index parameters);

// The lm stage's optimizer (solvers/training/lm_optimizer.cc).
std::unique_ptr<Optimizer> make_lm_optimizer();

void register_optimizers(Registry<OptimizerFactory>& registry);

}  // namespace nfield::solvers
