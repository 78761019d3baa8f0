// SPDX-License-Identifier: MIT
#include "solvers/training/reptile.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "solvers/training/adam.h"
#include "solvers/training/epoch_draws.h"
#include "solvers/sampling/random.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {

template <typename Scalar>
double finite_loss_and_gradient(Trainer<Scalar>& trainer, const Scalar* params, autodiff::Vector<Scalar>& gradient,
                                const std::string& where, double lr) {
  const double loss = trainer.loss_and_gradient_at(params, gradient.data());
  if (!std::isfinite(loss) || !gradient.allFinite())
    throw std::runtime_error(where + ": the " + (std::isfinite(loss) ? "gradient" : "loss") + " is not finite (inner_lr " +
                             std::to_string(lr) + " too large?)");
  return loss;
}

template <typename Scalar>
std::vector<double> adapt(const Problem& problem, fields::Field<Scalar>& field, const TrainingOptions& training,
                          const std::string& optimizer, double lr, int steps, std::uint64_t seed,
                          const std::function<void(int)>& after_step, const autodiff::Vector<Scalar>* rates) {
  TrainingOptions inner = training;
  inner.seed = seed;
  inner.meta = {};
  Trainer<Scalar> trainer(problem, field, inner);
  autodiff::Vector<Scalar>& theta = field.parameters();
  autodiff::Vector<Scalar> gradient(theta.size());
  std::optional<Adam<Scalar>> adam;
  if (optimizer == "adam") adam.emplace(theta.size(), AdamOptions{.learning_rate = lr});
  std::vector<double> losses;
  losses.reserve(static_cast<std::size_t>(steps));
  for (int s = 0; s < steps; ++s) {
    const double loss =
        finite_loss_and_gradient(trainer, theta.data(), gradient, "inner step " + std::to_string(s + 1), lr);
    losses.push_back(loss);
    if (adam)
      adam->step(theta.data(), gradient.data(), lr);
    else if (rates)
      theta -= rates->cwiseProduct(gradient);
    else
      theta -= static_cast<Scalar>(lr) * gradient;
    if (after_step) after_step(s + 1);
  }
  return losses;
}

Progress meta_progress(const char* algorithm, const MetaResult& result, int total_steps, double rate,
                       double seconds) {
  Progress p;
  p.optimizer = algorithm;
  p.step = result.steps;
  p.total_steps = total_steps;
  p.learning_rate = rate;
  p.loss = result.mean_last_loss;
  p.term_names = {"before"};
  p.term_losses = {result.mean_first_loss};
  p.steps_per_second = seconds > 0 ? static_cast<double>(result.steps) / seconds : 0;
  p.eta_seconds = p.steps_per_second > 0 ? static_cast<double>(total_steps - result.steps) / p.steps_per_second : 0;
  return p;
}

template <typename Scalar>
MetaResult run_reptile(const std::vector<ProblemInstance>& tasks, fields::Field<Scalar>& field,
                          const TrainingOptions& training, const MetaOptions& meta,
                          const MetaCallbacks& callbacks) {
  if (tasks.empty()) throw std::invalid_argument("run_reptile: no training instances");
  meta.validate();
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  EpochDraws draws(tasks.size(), training.seed ^ 0x9E3779B97F4A7C15ull);
  autodiff::Vector<Scalar> theta = field.parameters(), sum(theta.size());
  MetaResult result;
  for (int step = 0; step < meta.steps; ++step) {
    if (callbacks.stop_requested && callbacks.stop_requested()) {
      field.parameters() = theta;
      return result;
    }
    sum.setZero();
    double first = 0, last = 0;
    for (int b = 0; b < meta.tasks_per_step; ++b) {
      const std::size_t k = draws.next();
      field.parameters() = theta;
      // A seed per draw: each adaptation draws its own points (all pixels: the same ones).
      const std::uint64_t seed = training.seed + 1 + static_cast<std::uint64_t>(step) * meta.tasks_per_step + b;
      std::vector<double> inner;
      try {
        inner = adapt(*tasks[k].problem, field, training, meta.inner_optimizer, meta.inner_lr, meta.inner_steps, seed);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error("meta step " + std::to_string(step + 1) + ", instance " + tasks[k].name + ": " +
                                 e.what());
      }
      first += inner.front();
      last += inner.back();
      sum += field.parameters() - theta;
    }
    // ε annealed linearly to 0 (Nichol et al. 2018, Sec. 6).
    const double epsilon = meta.outer_lr * (1.0 - static_cast<double>(step) / meta.steps);
    theta += static_cast<Scalar>(epsilon / meta.tasks_per_step) * sum;
    result.steps = step + 1;
    result.mean_first_loss = first / meta.tasks_per_step;
    result.mean_last_loss = last / meta.tasks_per_step;
    if (callbacks.progress)
      callbacks.progress(meta_progress("reptile", result, meta.steps, epsilon,
                                       std::chrono::duration<double>(Clock::now() - started).count()));
  }
  field.parameters() = theta;
  result.finished = true;
  return result;
}

#define NFIELD_REPTILE(Scalar)                                                                                    \
  template double finite_loss_and_gradient<Scalar>(Trainer<Scalar>&, const Scalar*, autodiff::Vector<Scalar>&,   \
                                                   const std::string&, double);                                  \
  template std::vector<double> adapt<Scalar>(const Problem&, fields::Field<Scalar>&, const TrainingOptions&,    \
                                             const std::string&, double, int, std::uint64_t,                     \
                                             const std::function<void(int)>&, const autodiff::Vector<Scalar>*); \
  template MetaResult run_reptile<Scalar>(const std::vector<ProblemInstance>&, fields::Field<Scalar>&,         \
                                             const TrainingOptions&, const MetaOptions&, const MetaCallbacks&);
NFIELD_REPTILE(float)
NFIELD_REPTILE(double)
#undef NFIELD_REPTILE

}  // namespace nfield::solvers
