// SPDX-License-Identifier: MIT
//
// The math the training strategies share, apart from their classes and options (each
// strategy's options in its own header: adaptive_options.h, balance_options.h,
// causal_options.h; the strategies adaptive_refinement.h, gradient_balancing.h,
// causal_weighting.h; their registry strategy_settings.h):
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

namespace nfield::solvers {

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
