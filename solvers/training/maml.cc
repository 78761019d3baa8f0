// SPDX-License-Identifier: MIT
#include "solvers/training/maml.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "solvers/training/adam.h"
#include "solvers/training/epoch_draws.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {
namespace {

// H(φ) v by a central difference of the gradient along v (maml.h: the step h).
template <typename Scalar>
autodiff::Vector<Scalar> hessian_times(Trainer<Scalar>& trainer, const autodiff::Vector<Scalar>& phi,
                                       const autodiff::Vector<Scalar>& v, double lr) {
  const double norm = static_cast<double>(v.norm());
  if (norm == 0) return autodiff::Vector<Scalar>::Zero(v.size());
  const double rms = static_cast<double>(phi.norm()) / std::sqrt(static_cast<double>(phi.size()));
  const double h = std::sqrt(static_cast<double>(std::numeric_limits<Scalar>::epsilon())) * (1.0 + rms);
  const autodiff::Vector<Scalar> step = static_cast<Scalar>(h / norm) * v;
  const autodiff::Vector<Scalar> ahead = phi + step, behind = phi - step;
  autodiff::Vector<Scalar> plus(v.size()), minus(v.size());
  finite_loss_and_gradient(trainer, ahead.data(), plus, "a Hessian product", lr);
  finite_loss_and_gradient(trainer, behind.data(), minus, "a Hessian product", lr);
  return static_cast<Scalar>(norm / (2 * h)) * (plus - minus);
}

}  // namespace

template <typename Scalar>
MamlGradient<Scalar> maml_gradient(const Problem& problem, fields::Field<Scalar>& field,
                                   const TrainingOptions& training, const InnerRates<Scalar>& rates, int inner_steps,
                                   bool first_order, std::uint64_t seed) {
  TrainingOptions inner = training;
  inner.seed = seed;
  inner.meta = {};
  const autodiff::Vector<Scalar> theta = field.parameters();
  Trainer<Scalar> trainer(problem, field, inner);
  const auto scaled = [&](const autodiff::Vector<Scalar>& v) -> autodiff::Vector<Scalar> {
    if (rates.per_parameter) return rates.per_parameter->cwiseProduct(v);
    return static_cast<Scalar>(rates.scalar) * v;
  };
  std::vector<autodiff::Vector<Scalar>> phi{theta}, gradients;
  MamlGradient<Scalar> result;
  for (int j = 0; j < inner_steps; ++j) {
    gradients.emplace_back(theta.size());
    const double loss = finite_loss_and_gradient(trainer, phi.back().data(), gradients.back(),
                                                 "inner step " + std::to_string(j + 1), rates.scalar);
    if (j == 0) result.loss_before = loss;
    phi.push_back(phi.back() - scaled(gradients.back()));
  }
  // v = ∂F/∂φ_{j+1} on entry to step j of the backward loop (maml.h).
  autodiff::Vector<Scalar>& v = result.gradient;
  v.resize(theta.size());
  result.loss_after =
      finite_loss_and_gradient(trainer, phi.back().data(), v, "the loss after the inner steps", rates.scalar);
  if (rates.per_parameter) result.rate_gradient = autodiff::Vector<Scalar>::Zero(theta.size());
  for (int j = inner_steps - 1; j >= 0; --j) {
    const auto J = static_cast<std::size_t>(j);
    if (rates.per_parameter) result.rate_gradient -= gradients[J].cwiseProduct(v);
    if (!first_order) v -= hessian_times(trainer, phi[J], scaled(v), rates.scalar);
  }
  field.parameters() = theta;
  return result;
}

template <typename Scalar>
MetaResult run_maml(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                    const TrainingOptions& training, const MetaOptions& meta, const MetaCallbacks& callbacks,
                    autodiff::Vector<Scalar>* learned_rates) {
  if (tasks.empty()) throw std::invalid_argument("run_maml: no training instances");
  if (meta.learn_inner_lr && !learned_rates)
    throw std::invalid_argument("run_maml: learn_inner_lr needs somewhere to put the rates");
  meta.validate();  // includes: inner_optimizer sgd
  const bool first_order = meta.algorithm == "fomaml";
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  EpochDraws draws(tasks.size(), training.seed ^ 0x9E3779B97F4A7C15ull);
  autodiff::Vector<Scalar>& theta = field.parameters();
  Adam<Scalar> adam(theta.size(), AdamOptions{.learning_rate = meta.outer_lr});
  autodiff::Vector<Scalar> sum(theta.size()), rate_sum;
  InnerRates<Scalar> rates{meta.inner_lr, nullptr};
  std::optional<Adam<Scalar>> rate_adam;
  if (meta.learn_inner_lr) {
    *learned_rates = autodiff::Vector<Scalar>::Constant(theta.size(), static_cast<Scalar>(meta.inner_lr));
    rates.per_parameter = learned_rates;
    rate_adam.emplace(theta.size(), AdamOptions{.learning_rate = meta.outer_lr});
    rate_sum.resize(theta.size());
  }
  MetaResult result;
  for (int step = 0; step < meta.steps; ++step) {
    if (callbacks.stop_requested && callbacks.stop_requested()) return result;
    sum.setZero();
    if (rate_adam) rate_sum.setZero();
    double before = 0, after = 0;
    for (int b = 0; b < meta.tasks_per_step; ++b) {
      const std::size_t k = draws.next();
      const std::uint64_t seed = training.seed + 1 + static_cast<std::uint64_t>(step) * meta.tasks_per_step + b;
      try {
        const MamlGradient<Scalar> task =
            maml_gradient(*tasks[k].problem, field, training, rates, meta.inner_steps, first_order, seed);
        before += task.loss_before;
        after += task.loss_after;
        sum += task.gradient;
        if (rate_adam) rate_sum += task.rate_gradient;
      } catch (const std::runtime_error& e) {
        throw std::runtime_error("meta step " + std::to_string(step + 1) + ", instance " + tasks[k].name + ": " +
                                 e.what());
      }
    }
    sum /= static_cast<Scalar>(meta.tasks_per_step);
    adam.step(theta.data(), sum.data());
    if (rate_adam) {
      rate_sum /= static_cast<Scalar>(meta.tasks_per_step);
      rate_adam->step(learned_rates->data(), rate_sum.data());
    }
    result.steps = step + 1;
    result.mean_first_loss = before / meta.tasks_per_step;
    result.mean_last_loss = after / meta.tasks_per_step;
    if (callbacks.progress)
      callbacks.progress(meta_progress(meta.algorithm.c_str(), result, meta.steps, meta.outer_lr,
                                       std::chrono::duration<double>(Clock::now() - started).count()));
  }
  result.finished = true;
  return result;
}

#define NFIELD_MAML(Scalar)                                                                                   \
  template MamlGradient<Scalar> maml_gradient<Scalar>(const Problem&, fields::Field<Scalar>&,                \
                                                      const TrainingOptions&, const InnerRates<Scalar>&, int, \
                                                      bool, std::uint64_t);                                   \
  template MetaResult run_maml<Scalar>(const std::vector<ProblemInstance>&, fields::Field<Scalar>&,           \
                                       const TrainingOptions&, const MetaOptions&, const MetaCallbacks&,      \
                                       autodiff::Vector<Scalar>*);
NFIELD_MAML(float)
NFIELD_MAML(double)
#undef NFIELD_MAML

}  // namespace nfield::solvers
