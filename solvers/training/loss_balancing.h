// SPDX-License-Identifier: MIT
//
// Accuracy aids that act on the loss and on where its points lie, each optional and set in
// the `training:` section (defaults shown; parsed here so that training_options stays small).
// This file holds their options and the math they share; the training strategies that apply
// them are adaptive_refinement.h, gradient_balancing.h and causal_weighting.h
// (training_strategy.h):
//
//   sampler: uniform          # uniform | sobol | halton (solvers/sampling/random.h)
//
//   adaptive:                 # residual-based adaptive refinement (RAR); absent: off
//     every: 500              # steps between refinements (Adam and L-BFGS)
//     candidates: 10000       # points drawn (like the interior batch) and scored by ‖r‖
//     add: 100                # the highest-scoring ones join a persistent extra set
//     max_points: 2000        # size cap of the set; the oldest points leave first
//
//   balance: fixed            # fixed | grad_norm, or {method: grad_norm, every: 100, alpha: 0.1}
//
//   causal: {epsilon: 1.0, slices: 32, every: 100}   # causal weights in time; absent: off
//
// RAR (Lu, Meng, Mao, Karniadakis 2021, DeepXDE): every `every` steps, candidates are drawn
// for the PDE term, its residual r is evaluated there (a forward pass, no gradient), and
// the `add` points with the largest ‖r‖ are kept. Each freshly drawn PDE batch is followed
// by the whole extra set, so the loss keeps sampling where the equation is worst. An
// L-BFGS stage keeps the points it drew at its start and refines the set behind them every
// `every` iterations, restarting its history each time.
//
// grad_norm (learning-rate annealing, Wang, Teng, Perdikaris 2021, Algorithm 1): with gₖ the
// parameter gradient of term k's loss wₖLₖ (wₖ its fixed `weight`), every `every` Adam steps
//     λ̂ₖ = wₖ · max_θ |g_pde| / mean_θ |gₖ|          (= max|∇w_pde L_pde| / mean|∇Lₖ|)
//     λₖ ← (1 − α) λₖ + α λ̂ₖ,   λ_pde = 1, λ starting at 1,
// and the training loss is Σₖ λₖ wₖ Lₖ. λ balances the gradient scale of each term against
// the PDE term's; the fixed wₖ stays a relative preference on top. L-BFGS stages keep λ
// fixed (a line search needs one objective).
//
// causal (Wang, Sankaran, Perdikaris 2022): the PDE points are grouped into M equal slices
// of [t0, t1]; Lᵢ is the mean of ‖r‖² over slice i (no weight applied) and the PDE loss is
//     L_pde = (w_pde / M) Σᵢ cᵢ Lᵢ,   cᵢ = exp(−ε Σ_{k<i} Lₖ)   (c₀ = 1),
// the cᵢ computed from the current parameters before each gradient and held constant in it.
// A slice is trained only once the ones before it fit, so the solution is learned forward in
// time; min cᵢ → 1 tells that every slice is fitted. L-BFGS stages update the cᵢ every
// `every` iterations (a restart of the L-BFGS history each time, as one line search needs
// one objective).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/config.h"

namespace nfield::solvers {

class Problem;

struct AdaptiveOptions {
  bool enabled = false;
  int every = 500;
  long candidates = 10000;
  long add = 100;
  long max_points = 2000;
};

struct BalanceOptions {
  std::string method = "fixed";  // fixed | grad_norm
  int every = 100;
  double alpha = 0.1;
};

struct CausalOptions {
  bool enabled = false;
  double epsilon = 1.0;
  int slices = 32;
  int every = 100;  // L-BFGS: iterations between weight updates
};

// Readers of the keys above from the `training:` mapping, and writers of their resolved
// form (nothing for adaptive/causal when off).
AdaptiveOptions adaptive_from_config(const io::ConfigNode& training);
BalanceOptions balance_from_config(const io::ConfigNode& training);
CausalOptions causal_from_config(const io::ConfigNode& training);
void write_yaml(YAML::Node& training, const AdaptiveOptions& adaptive, const BalanceOptions& balance,
                const CausalOptions& causal);

// Checks that the problem supports what `training` asks for (a PDE term for adaptive,
// grad_norm and causal; a time axis for causal); errors point at the key in `training`.
void check_against_problem(const io::ConfigNode& training, const AdaptiveOptions& adaptive,
                           const BalanceOptions& balance, const CausalOptions& causal,
                           const Problem& problem);

// λ̂ for one term from the PDE term's gradient and the term's (both of the weighted losses);
// `weight` is the term's fixed weight. Returns `current` when the term has no gradient.
double grad_norm_target(const Eigen::Ref<const Eigen::VectorXd>& pde_gradient,
                        const Eigen::Ref<const Eigen::VectorXd>& term_gradient, double weight,
                        double current);

struct CausalWeights {
  std::vector<double> slice_losses;  // Lᵢ (0 for an empty slice)
  std::vector<double> weights;       // cᵢ
  Eigen::VectorXd point_weights;     // N cᵢ / (M nᵢ) for each point, for ResidualLoss
  double min_weight() const;
};

// From the time of each point and its ‖r‖²: slices of [t0, t1] (the last one closed).
CausalWeights causal_weights(const Eigen::Ref<const Eigen::VectorXd>& times,
                             const Eigen::Ref<const Eigen::VectorXd>& squared_residuals,
                             double t0, double t1, int slices, double epsilon);

// Indices of the `count` largest scores, largest first (ties: lower index first).
std::vector<Eigen::Index> largest(const Eigen::Ref<const Eigen::VectorXd>& scores, Eigen::Index count);

// Appends `rows` to `set`, dropping the oldest rows beyond `max_rows`.
void append_capped(Eigen::MatrixXd& set, const Eigen::MatrixXd& rows, Eigen::Index max_rows);

}  // namespace nfield::solvers
