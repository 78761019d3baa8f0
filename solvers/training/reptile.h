// SPDX-License-Identifier: MIT
//
// Meta-learned initialisations by Reptile (Nichol, Achiam and Schulman 2018, "On first-order
// meta-learning algorithms", Alg. 2 with one task at a time per draw; applied to neural
// fields by Tancik et al., "Learned initializations for optimizing coordinate-based neural
// representations", CVPR 2021). Issue 28, item 3.
//
//   training:
//     meta:
//       algorithm: reptile       # reptile | maml | fomaml (solvers/training/maml.h; case-insensitive)
//       steps: 1000              # outer steps
//       tasks_per_step: 4        # instances drawn per outer step (without replacement: epochs)
//       inner_steps: 2           # K: steps that adapt a copy of θ to one instance
//       inner_optimizer: sgd     # sgd | adam (a fresh Adam per instance)
//       inner_lr: 1.0e-2         # α
//       outer_lr: 1.0            # ε at the first outer step, annealed linearly to 0
//       curve_steps: 10          # held-out curves from the learned θ: this many inner steps
//
// The outer loop, per step i of N: draw B instances k₁ … k_B of the family
// (Problem::instances, equation.family; in epochs: a shuffled order of all instances, drawn
// in turn and shuffled again when used up, so each weighs the same over an epoch and a
// B that equals the family's size takes the exact mean over it every step); for each, start from θ and take K inner steps on
// that instance's loss L_k, θ̃_k = U_k^K(θ); then move the initialisation toward the adapted
// weights,
//
//   θ ← θ + ε_i · (1/B) Σ_b (θ̃_{k_b} − θ),    ε_i = ε (1 − i/N).
//
// Why it learns an initialisation: for K = 1 and SGD, θ̃_k − θ = −α ∇L_k(θ), so the update
// is SGD on the mean task loss; for K ≥ 2 its expectation adds α ∇(∇L_k · ∇L_k)-type terms
// that favour points from which the tasks' gradients agree, where a few steps go far on every
// task (Nichol et al. Sec. 5). On a family of constant signals c_k and a field that can be
// any constant, the fixed point for K = 1 is the field equal to the mean of the c_k (the
// minimiser of the mean of (u − c_k)²): tests/solvers/training/reptile_test.cc checks that.
//
// The inner steps run through the existing machinery: one Trainer per draw on that instance
// (its points drawn once, by the seed of the draw; all of a picture's pixels when the batch
// covers them), its loss_and_gradient_at for each step, and either plain gradient steps
// (sgd, θ ← θ − α g) or the in-house Adam (solvers/training/adam.h). SGD is the default, as
// in Tancik et al.'s inner loop: its step is linear in the gradient, so the expected Reptile
// update is the first-order meta-gradient above and the fixed point of the constant family
// is the mean; a fresh Adam's first step is about α·sign(g) per parameter, whose fixed
// point on that family is the median instead. Adam remains a choice because an SGD inner
// rate that suits one layer of a SIREN can be far off for another.
//
// Progress lines: outer step, `loss` the mean over the draws of the loss at the last inner
// step (evaluated before its update: after K − 1 updates), `before` the mean loss at θ
// itself (before adaptation), the rate in outer steps per second and the ETA. A loss or
// gradient that is not finite stops the run with an error naming the outer step and the
// instance.
// The meta run's driver (outputs, checkpoint, held-out curves) is solvers/run/meta_run.h.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fields/field.h"
#include "solvers/training/meta_options.h"
#include "solvers/core/problem.h"
#include "solvers/core/problem_capabilities.h"

namespace nfield::solvers {

struct TrainingOptions;
struct Progress;
template <typename Scalar>
class Trainer;

// trainer.loss_and_gradient_at(params, gradient); std::runtime_error "WHERE: the loss (or
// gradient) is not finite (inner_lr LR too large?)" when either is not.
template <typename Scalar>
double finite_loss_and_gradient(Trainer<Scalar>& trainer, const Scalar* params, autodiff::Vector<Scalar>& gradient,
                                const std::string& where, double lr);

// K steps of `optimizer` (sgd | adam) at rate `lr` on `problem`'s loss, from and into
// field.parameters(); `training` gives the batch, block and threads, `seed` the points.
// Returns the loss before each step. `after_step(s)` is called after step s (1-based).
// `rates` (sgd only): a rate per parameter instead of lr (MAML's learned rates, maml.h).
template <typename Scalar>
std::vector<double> adapt(const Problem& problem, fields::Field<Scalar>& field, const TrainingOptions& training,
                          const std::string& optimizer, double lr, int steps, std::uint64_t seed,
                          const std::function<void(int)>& after_step = {},
                          const autodiff::Vector<Scalar>* rates = nullptr);

struct MetaCallbacks {
  std::function<bool()> stop_requested;           // polled every outer step
  std::function<void(const Progress&)> progress;  // after every outer step
};

struct MetaResult {
  long steps = 0;                // outer steps taken
  bool finished = false;         // all of them (false: stopped)
  double mean_first_loss = 0;    // of the last outer step: at θ, before adaptation
  double mean_last_loss = 0;     // and at the last inner step (before its update)
};

// The progress line of a meta-learning outer loop after `result.steps` of `total_steps`
// (`rate`: the outer step size, `seconds`: the wall time so far).
Progress meta_progress(const char* algorithm, const MetaResult& result, int total_steps, double rate, double seconds);

// Runs meta.steps outer steps over `tasks`, moving field.parameters() (the initialisation).
// Throws std::runtime_error when a loss is not finite.
template <typename Scalar>
MetaResult run_reptile(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                          const TrainingOptions& training, const MetaOptions& meta,
                          const MetaCallbacks& callbacks = {});

}  // namespace nfield::solvers
