// SPDX-License-Identifier: MIT
//
// Latent codes per instance, trained with the field: the auto-decoder of DeepSDF (Park et al.,
// "DeepSDF: learning continuous signed distance functions for shape representation", CVPR
// 2019, Sec. 4). Issue 28, items 1 and 2.
//
//   field:
//     latent: {size: 32}           # c: the code joins the first hidden layer (fields/field_options.h)
//   training:
//     auto_decoder:
//       instances_per_step: 8      # B
//       prior: 1.0e-4              # λ
//       init_std: 0.01             # codes start from N(0, init_std² I)
//       fit_steps: 300             # a new instance's code: Adam steps at fit_lr
//       fit_lr: 1.0e-2
//       interpolation_steps: 5     # outputs between two training codes (solvers/run/latent_run.h)
//     stages: [{optimizer: adam, steps: 2000, lr: 1.0e-3, schedule: cosine, lr_final: 1.0e-5}]
//
// There is no encoder: instance k's code z_k is a free parameter, and the codes Z = (z_1 … z_K)
// and the network's weights θ are one vector for one Adam. Each step draws B instances (in
// epochs: a shuffled order of all, drawn in turn) and lowers
//
//   L(θ, Z) = (1/B) Σ_b [ L_{k_b}(θ, z_{k_b}) + λ ‖z_{k_b}‖² ],
//
// L_k being instance k's own training loss (its Problem's loss terms on points drawn for that
// draw). λ‖z‖² is the negative log-density of a Gaussian prior N(0, I/(2λ)) on the codes, in
// the units of the data loss: it keeps the codes in a ball where the network has learned to
// read them, which is what lets a new instance's code be found by gradient descent from 0.
// Instance k's pass runs the field with z_k written into the field's own code slot
// (Field::latent_offset); that pass's gradient in the slot is ∂L_k/∂z_k. Codes not drawn in a
// step get no gradient that step (Adam's moments still move them a little, as in DeepSDF's
// training with a dense Adam over its embedding table).
//
// A new instance (fit_code; `nfield fit-code`): the network frozen, its code starts at 0, the
// prior's mean, and takes fit_steps Adam steps at fit_lr on L_k + λ‖z‖², DeepSDF's inference.
// With `fine_tune` every parameter moves from the trained field (the code too), at the same
// rate: the variant that adapts the network itself to the new signal.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fields/field.h"
#include "solvers/core/problem.h"
#include "solvers/core/problem_capabilities.h"
#include "solvers/training/auto_decoder_options.h"

namespace nfield::solvers {

struct TrainingOptions;
struct Progress;

// The codes of a family, one row per training instance (K × c), beside the field.
using LatentCodes = Eigen::MatrixXd;

// Draws K codes from N(0, init_std² I) with `seed`.
LatentCodes initial_codes(Eigen::Index instances, int size, double init_std, std::uint64_t seed);

// Writes `code` into the field's code slot. Throws std::invalid_argument when the field takes
// no code or the size differs.
template <typename Scalar>
void set_code(fields::Field<Scalar>& field, const Eigen::Ref<const Eigen::VectorXd>& code);
template <typename Scalar>
Eigen::VectorXd code_of(const fields::Field<Scalar>& field);

struct AutoDecoderCallbacks {
  std::function<bool()> stop_requested;           // polled every step
  std::function<void(const Progress&)> progress;  // after every step
};

struct AutoDecoderResult {
  long steps = 0;           // steps taken
  bool finished = false;    // all of them (false: stopped)
  double data_loss = 0;     // of the last step: the mean of the drawn instances' losses
  double prior_loss = 0;    // and the mean of λ‖z‖² over them
};

// Trains field.parameters() and `codes` (K × c, K = tasks.size()) for training.stages[0]
// (an Adam stage: its steps, rate and schedule; with `seconds`, until that much wall time has
// passed or the steps are done, the schedule following the fraction of the time spent). Throws std::runtime_error naming the step and
// the instance when a loss is not finite.
template <typename Scalar>
AutoDecoderResult train_auto_decoder(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                                     LatentCodes& codes, const TrainingOptions& training,
                                     const AutoDecoderCallbacks& callbacks = {});

// Fits the field's code to `problem` as above, from the code in the field's slot (set it to 0
// first for DeepSDF's inference); `seed` draws the points (once). Returns the loss (data term
// plus prior) before each step; after_step(s) is called after step s (1-based).
template <typename Scalar>
std::vector<double> fit_code(const Problem& problem, fields::Field<Scalar>& field, const TrainingOptions& training,
                             int steps, double lr, bool fine_tune, std::uint64_t seed,
                             const std::function<void(int)>& after_step = {});

}  // namespace nfield::solvers
