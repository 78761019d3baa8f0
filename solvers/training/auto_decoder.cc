// SPDX-License-Identifier: MIT
#include "solvers/training/auto_decoder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "solvers/sampling/random.h"
#include "solvers/training/adam.h"
#include "solvers/training/epoch_draws.h"
#include "solvers/training/optimizers.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {
namespace {

template <typename Scalar>
Eigen::Index checked_slot(const fields::Field<Scalar>& field, Eigen::Index size) {
  if (field.latent_offset() < 0) throw std::invalid_argument("the field takes no latent code (field.latent)");
  if (size != field.latent_size())
    throw std::invalid_argument("a latent code of " + std::to_string(size) + " values for a field whose codes have " +
                                std::to_string(field.latent_size()));
  return field.latent_offset();
}

// One instance's training options: its own seed for the points, no meta-learning.
TrainingOptions instance_options(const TrainingOptions& training, std::uint64_t seed) {
  TrainingOptions inner = training;
  inner.seed = seed;
  inner.meta = {};
  return inner;
}

// The progress line of step result.steps of `steps`.
Progress progress_of(const AutoDecoderResult& result, double lr, int steps, double budget_seconds,
                     std::chrono::steady_clock::time_point started) {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  Progress progress;
  progress.optimizer = "adam";
  progress.step = result.steps;
  progress.total_steps = steps;
  progress.learning_rate = lr;
  progress.loss = result.data_loss + result.prior_loss;
  progress.term_names = {"data", "prior"};
  progress.term_losses = {result.data_loss, result.prior_loss};
  progress.steps_per_second = seconds > 0 ? static_cast<double>(result.steps) / seconds : 0;
  progress.eta_seconds = progress.steps_per_second > 0 ? static_cast<double>(steps - result.steps) / progress.steps_per_second : 0;
  if (budget_seconds > 0) progress.eta_seconds = std::min(progress.eta_seconds, std::max(0.0, budget_seconds - seconds));
  return progress;
}

}  // namespace

LatentCodes initial_codes(Eigen::Index instances, int size, double init_std, std::uint64_t seed) {
  Random rng(seed ^ 0xC0DE5EEDull);
  LatentCodes codes(instances, size);
  // Box–Muller from the raw engine: the same codes on every platform.
  for (Eigen::Index k = 0; k < instances; ++k)
    for (int j = 0; j < size; ++j) {
      const double u = 1.0 - uniform01(rng), v = uniform01(rng);
      codes(k, j) = init_std * std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
    }
  return codes;
}

template <typename Scalar>
void set_code(fields::Field<Scalar>& field, const Eigen::Ref<const Eigen::VectorXd>& code) {
  const Eigen::Index slot = checked_slot(field, code.size());
  field.parameters().segment(slot, code.size()) = code.cast<Scalar>();
}

template <typename Scalar>
Eigen::VectorXd code_of(const fields::Field<Scalar>& field) {
  const Eigen::Index slot = checked_slot(field, field.latent_size());
  return field.parameters().segment(slot, field.latent_size()).template cast<double>();
}

template <typename Scalar>
AutoDecoderResult train_auto_decoder(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                                     LatentCodes& codes, const TrainingOptions& training,
                                     const AutoDecoderCallbacks& callbacks) {
  if (tasks.empty()) throw std::invalid_argument("train_auto_decoder: no training instances");
  const AutoDecoderOptions& options = training.auto_decoder;
  options.validate();
  const Eigen::Index c = field.latent_size();
  const Eigen::Index slot = checked_slot(field, codes.cols());
  if (codes.rows() != static_cast<Eigen::Index>(tasks.size()))
    throw std::invalid_argument("train_auto_decoder: " + std::to_string(codes.rows()) + " codes for " +
                                std::to_string(tasks.size()) + " instances");
  const StageOptions& stage = training.stages.front();
  const auto& adam_options = stage.options<AdamStageOptions>();
  const Eigen::Index p = field.parameter_count();
  // One vector for one Adam: θ, then the codes row after row.
  autodiff::Vector<Scalar> all(p + codes.size()), gradient(all.size()), instance_gradient(p);
  all.head(p) = field.parameters();
  for (Eigen::Index k = 0; k < codes.rows(); ++k) all.segment(p + k * c, c) = codes.row(k).transpose().cast<Scalar>();
  Adam<Scalar> adam(all.size(), AdamOptions{.learning_rate = adam_options.lr});
  EpochDraws draws(tasks.size(), training.seed ^ 0xA070DEC0DEull);
  const int batch = options.instances_per_step;
  AutoDecoderResult result;
  const auto started = std::chrono::steady_clock::now();
  const auto write_back = [&] {
    field.parameters() = all.head(p);
    field.parameters().segment(slot, c).setZero();
    for (Eigen::Index k = 0; k < codes.rows(); ++k) codes.row(k) = all.segment(p + k * c, c).template cast<double>().transpose();
  };
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(); };
  for (int step = 0; step < stage.steps; ++step) {
    if (callbacks.stop_requested && callbacks.stop_requested()) {
      write_back();
      return result;
    }
    // A time budget (seconds > 0) ends the stage as a step limit does: finished.
    if (adam_options.seconds > 0 && elapsed() >= adam_options.seconds) break;
    gradient.setZero();
    double data = 0, prior = 0;
    for (int b = 0; b < batch; ++b) {
      const std::size_t k = draws.next();
      const auto z = all.segment(p + static_cast<Eigen::Index>(k) * c, c);
      field.parameters() = all.head(p);
      field.parameters().segment(slot, c) = z;
      const std::uint64_t seed = training.seed + 1 + static_cast<std::uint64_t>(step) * batch + b;
      Trainer<Scalar> trainer(*tasks[k].problem, field, instance_options(training, seed));
      const double loss = trainer.loss_and_gradient_at(field.parameters().data(), instance_gradient.data());
      if (!std::isfinite(loss) || !instance_gradient.allFinite())
        throw std::runtime_error("auto-decoder step " + std::to_string(step + 1) + ", instance " + tasks[k].name +
                                 ": the " + (std::isfinite(loss) ? "gradient" : "loss") +
                                 " is not finite (lr " + std::to_string(adam_options.lr) + " too large?)");
      const double z_norm2 = static_cast<double>(z.squaredNorm());
      data += loss;
      prior += options.prior * z_norm2;
      auto code_gradient = gradient.segment(p + static_cast<Eigen::Index>(k) * c, c);
      code_gradient += instance_gradient.segment(slot, c) + static_cast<Scalar>(2 * options.prior) * z;
      instance_gradient.segment(slot, c).setZero();
      gradient.head(p) += instance_gradient;
    }
    gradient /= static_cast<Scalar>(batch);
    const double lr = adam_options.seconds > 0
                          ? adam_options.learning_rate_at(std::min(1.0, elapsed() / adam_options.seconds))
                          : adam_options.learning_rate(step, stage.steps);
    adam.step(all.data(), gradient.data(), lr);
    result.steps = step + 1;
    result.data_loss = data / batch;
    result.prior_loss = prior / batch;
    if (callbacks.progress)
      callbacks.progress(progress_of(result, lr, stage.steps, adam_options.seconds, started));
  }
  write_back();
  result.finished = true;
  return result;
}

template <typename Scalar>
std::vector<double> fit_code(const Problem& problem, fields::Field<Scalar>& field, const TrainingOptions& training,
                             int steps, double lr, bool fine_tune, std::uint64_t seed,
                             const std::function<void(int)>& after_step) {
  const Eigen::Index c = field.latent_size();
  const Eigen::Index slot = checked_slot(field, c);
  const double prior = training.auto_decoder.prior;
  Trainer<Scalar> trainer(problem, field, instance_options(training, seed));
  autodiff::Vector<Scalar>& theta = field.parameters();
  autodiff::Vector<Scalar> gradient(theta.size());
  Adam<Scalar> adam(theta.size(), AdamOptions{.learning_rate = lr});
  std::vector<double> losses;
  losses.reserve(static_cast<std::size_t>(steps));
  for (int s = 0; s < steps; ++s) {
    const auto z = theta.segment(slot, c);
    const double loss = trainer.loss_and_gradient_at(theta.data(), gradient.data()) +
                        prior * static_cast<double>(z.squaredNorm());
    if (!std::isfinite(loss) || !gradient.allFinite())
      throw std::runtime_error("code fit step " + std::to_string(s + 1) + ": the " +
                               (std::isfinite(loss) ? "gradient" : "loss") + " is not finite (fit_lr " +
                               std::to_string(lr) + " too large?)");
    losses.push_back(loss);
    gradient.segment(slot, c) += static_cast<Scalar>(2 * prior) * z;
    if (!fine_tune) {
      // Zero gradients leave Adam's moments, and so the frozen weights, exactly where they are.
      gradient.head(slot).setZero();
      gradient.tail(gradient.size() - slot - c).setZero();
    }
    adam.step(theta.data(), gradient.data(), lr);
    if (after_step) after_step(s + 1);
  }
  return losses;
}

#define NFIELD_AUTO_DECODER(Scalar)                                                                               \
  template void set_code<Scalar>(fields::Field<Scalar>&, const Eigen::Ref<const Eigen::VectorXd>&);             \
  template Eigen::VectorXd code_of<Scalar>(const fields::Field<Scalar>&);                                        \
  template AutoDecoderResult train_auto_decoder<Scalar>(const std::vector<ProblemInstance>&,                    \
                                                        fields::Field<Scalar>&, LatentCodes&,                   \
                                                        const TrainingOptions&, const AutoDecoderCallbacks&);   \
  template std::vector<double> fit_code<Scalar>(const Problem&, fields::Field<Scalar>&, const TrainingOptions&, \
                                                int, double, bool, std::uint64_t, const std::function<void(int)>&);
NFIELD_AUTO_DECODER(float)
NFIELD_AUTO_DECODER(double)
#undef NFIELD_AUTO_DECODER

}  // namespace nfield::solvers
