// SPDX-License-Identifier: MIT
//
// Meta-learned initialisations by MAML (Finn, Abbeel and Levine 2017, "Model-agnostic
// meta-learning", Alg. 1; the algorithm of Tancik et al., CVPR 2021, for neural fields), with
// its second-order terms, and its first-order variant FOMAML. Issue 28, item 3.
//
//   training:
//     meta:
//       algorithm: maml        # maml | fomaml (reptile: solvers/training/reptile.h)
//       inner_steps: 2         # K plain gradient steps, rate inner_lr (α); inner_optimizer sgd
//       outer_lr: 1.0e-4       # the rate of the outer Adam (constant), not Reptile's ε
//       steps, tasks_per_step, curve_steps   # as for Reptile
//
// The objective of one instance k is its loss after K inner steps from θ,
//
//   F_k(θ) = L_k(φ_K),   φ_0 = θ,   φ_{j+1} = φ_j − α ∇L_k(φ_j),
//
// and the outer loop takes Adam steps on the mean of ∇F_k over the tasks_per_step instances
// of a draw (drawn in epochs, as Reptile's). By the chain rule, with H_j = ∇²L_k(φ_j) symmetric,
//
//   ∇F_k(θ) = (I − α H_0)(I − α H_1) ⋯ (I − α H_{K−1}) ∇L_k(φ_K),
//
// evaluated right to left: v ← ∇L_k(φ_K), then v ← v − α H_j v for j = K−1 … 0. FOMAML drops
// the H_j (v = ∇L_k(φ_K)).
//
// Learned rates (`learn_inner_lr: true`; Meta-SGD, Li, Zhou, Chen and Li 2017): α becomes a
// vector, one rate per parameter shared by the K steps, φ_{j+1} = φ_j − α ⊙ ∇L_k(φ_j), started
// at inner_lr and moved by its own outer Adam at outer_lr. Then ∂φ_{j+1}/∂φ_j = I − diag(α) H_j,
// so the backward step is v ← v − H_j (α ⊙ v), and with v = ∂F/∂φ_{j+1} on entry to step j,
// ∂F/∂α = −Σ_j ∇L_k(φ_j) ⊙ v: no products beyond MAML's. A few steps can then move each
// parameter by its own amount, which one rate for a SIREN's first and last layers cannot.
// The rates are part of the initialisation: held-out fits from the learned θ use them, and the
// checkpoint holds them (/meta/inner_rates).
//
// The Hessian–vector products. nfield's streams are forward-mode in the field's inputs and
// its reverse pass is first order in the parameters, so there is no exact H v (Pearlmutter's
// R-operator would need a forward-mode pass in a parameter direction through the reverse
// pass). H v is taken by a central difference of the gradient along v's direction,
//
//   H v ≈ ‖v‖ (∇L(φ + h v̂) − ∇L(φ − h v̂)) / 2h,   v̂ = v/‖v‖,   h = √ε (1 + rms(φ)),
//
// with ε the scalar type's machine epsilon and rms(φ) = ‖φ‖/√P. Why √ε and not the ε^{1/3}
// that balances an O(h²) truncation error against the O(ε/h) rounding for a function of unit
// scale: a SIREN's third derivatives along its first layer's weights carry ω₀³, so the
// truncation term dominates at ε^{1/3}. On the test's SIREN (float, two inner steps) the
// meta-gradient's relative error against double was 1e-3 at h = ε^{1/3}(1 + rms(φ)) and 5e-5 at
// this h; in double the products are exact to the test's check of ∇F_k against central
// differences of F_k itself (tests/solvers/training/maml_test.cc, 1e-6 of ‖∇F_k‖ asserted).
// Cost per instance: K + 1 gradients, and 2K more for the products (Reptile: K).
//
// Inner steps use the instance's points drawn once per draw (all pixels when the batch covers
// them), the same points for the inner steps and the outer loss, as Tancik et al.'s code does.
// Only plain gradient steps are differentiated: inner_optimizer adam is refused at config load.
// A loss or gradient that is not finite stops the run naming the outer step and the instance.
#pragma once

#include <cstdint>

#include "solvers/training/reptile.h"

namespace nfield::solvers {

// The inner steps' rates: one for all parameters, or one each (learned; not owned).
template <typename Scalar>
struct InnerRates {
  double scalar = 1e-2;
  const autodiff::Vector<Scalar>* per_parameter = nullptr;
};

template <typename Scalar>
struct MamlGradient {
  double loss_before = 0;                  // L_k(θ)
  double loss_after = 0;                   // F_k(θ) = L_k(φ_K)
  autodiff::Vector<Scalar> gradient;       // ∇F_k(θ)
  autodiff::Vector<Scalar> rate_gradient;  // ∂F_k/∂α with per-parameter rates (else empty)
};

// One instance's objective and its gradients at θ = field.parameters() (left unchanged).
// `first_order`: FOMAML's ∇L_k(φ_K). Throws std::runtime_error when a loss is not finite.
template <typename Scalar>
MamlGradient<Scalar> maml_gradient(const Problem& problem, fields::Field<Scalar>& field,
                                   const TrainingOptions& training, const InnerRates<Scalar>& rates, int inner_steps,
                                   bool first_order, std::uint64_t seed);

// Runs meta.steps outer steps (meta.algorithm maml or fomaml) over `tasks`, moving
// field.parameters() and, with meta.learn_inner_lr, the per-parameter rates in
// `learned_rates` (sized and set to inner_lr here). MetaResult's losses: the mean L_k(θ)
// (`before`) and F_k(θ) (`loss`).
template <typename Scalar>
MetaResult run_maml(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                    const TrainingOptions& training, const MetaOptions& meta, const MetaCallbacks& callbacks = {},
                    autodiff::Vector<Scalar>* learned_rates = nullptr);

}  // namespace nfield::solvers
