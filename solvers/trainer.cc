// SPDX-License-Identifier: MIT
#include "solvers/trainer.h"

#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <chrono>
#include <sstream>

#include "solvers/hard_constraints.h"

namespace nfield::solvers {
namespace {

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

template <typename Scalar>
Trainer<Scalar>::Trainer(const Problem& problem, fields::Field<Scalar>& field,
                         TrainingOptions options)
    : problem_(problem), field_(field), options_(std::move(options)), rng_(options_.seed) {
  terms_ = with_ansatz(problem_.loss_terms(), problem_.ansatz());  // hard conditions: u = A + D·N
  for (const LossTerm& term : terms_) {
    names_.push_back(term.name);
    layouts_.emplace_back(term.spec);
    if (!options_.batch.count(term.batch_key))
      throw std::invalid_argument("training.batch has no entry '" + term.batch_key +
                                  "' for loss term '" + term.name + "'");
  }
  losses_.assign(terms_.size(), 0.0);
  points_.resize(terms_.size());
  points_scalar_.resize(terms_.size());
  residuals_.resize(terms_.size());
  field_.network().set_options({options_.block, options_.threads});
}

template <typename Scalar>
Trainer<Scalar>::~Trainer() = default;

template <typename Scalar>
void Trainer<Scalar>::resample() {
  for (size_t k = 0; k < terms_.size(); ++k) {
    points_[k] = terms_[k].sample(rng_, options_.batch.at(terms_[k].batch_key));
    points_scalar_[k] = points_[k].template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient(const Scalar* params, Scalar* gradient) {
  Eigen::Map<autodiff::Vector<Scalar>>(gradient, field_.parameter_count()).setZero();
  double total = 0;
  for (size_t k = 0; k < terms_.size(); ++k) {
    const ResidualLoss<Scalar> loss(*residuals_[k], terms_[k].weight, points_[k].rows());
    losses_[k] = field_.network().value_and_gradient(params, layouts_[k], points_scalar_[k], loss,
                                                     gradient);
    total += losses_[k];
  }
  return total;
}

template <typename Scalar>
void Trainer<Scalar>::report(const Callbacks& callbacks, const StageOptions& stage, double lr) {
  if (!callbacks.progress) return;
  Progress p;
  p.stage = stage_;
  p.optimizer = stage.optimizer;
  p.step = global_step_;
  p.total_steps = options_.total_steps();
  p.learning_rate = lr;
  p.term_names = names_;
  p.term_losses = losses_;
  for (double l : losses_) p.loss += l;
  const double elapsed = now_seconds() - started_;
  const long done = global_step_ - started_step_;
  p.steps_per_second = elapsed > 0 ? done / elapsed : 0;
  p.eta_seconds = p.steps_per_second > 0 ? (p.total_steps - p.step) / p.steps_per_second : 0;
  callbacks.progress(p);
}

template <typename Scalar>
bool Trainer<Scalar>::run_adam(const StageOptions& stage, const Callbacks& callbacks) {
  if (!adam_) adam_ = std::make_unique<Adam<Scalar>>(field_.parameter_count(), AdamOptions{stage.lr});
  autodiff::Vector<Scalar> gradient(field_.parameter_count());
  for (; stage_step_ < stage.steps; ++stage_step_) {
    if (callbacks.stop_requested && callbacks.stop_requested()) return false;
    const double start = now_seconds();
    if (global_step_ % options_.resample_every == 0 || !residuals_[0]) resample();
    loss_and_gradient(field_.parameters().data(), gradient.data());
    const double lr = stage.learning_rate(stage_step_);
    adam_->step(field_.parameters().data(), gradient.data(), lr);
    step_ms_.push_back(1e3 * (now_seconds() - start));
    ++global_step_;
    report(callbacks, stage, lr);
    if (options_.checkpoint_every > 0 && global_step_ % options_.checkpoint_every == 0 &&
        callbacks.checkpoint) {
      ++stage_step_;  // the saved state resumes after this step
      callbacks.checkpoint();
      --stage_step_;
    }
  }
  return true;
}

namespace {

// The summed loss as a Ceres first-order function, in double whatever the training scalar.
template <typename Scalar>
class LossFunction final : public ceres::FirstOrderFunction {
 public:
  LossFunction(int parameters, std::function<double(const Scalar*, Scalar*)> evaluate)
      : parameters_(parameters), evaluate_(std::move(evaluate)), theta_(parameters), gradient_(parameters) {}
  bool Evaluate(const double* parameters, double* cost, double* gradient) const override {
    theta_ = Eigen::Map<const Eigen::VectorXd>(parameters, parameters_).cast<Scalar>();
    *cost = evaluate_(theta_.data(), gradient_.data());
    if (gradient) Eigen::Map<Eigen::VectorXd>(gradient, parameters_) = gradient_.template cast<double>();
    return std::isfinite(*cost);
  }
  int NumParameters() const override { return parameters_; }

 private:
  int parameters_;
  std::function<double(const Scalar*, Scalar*)> evaluate_;
  mutable autodiff::Vector<Scalar> theta_, gradient_;
};

class StepCallback final : public ceres::IterationCallback {
 public:
  explicit StepCallback(std::function<bool()> on_step) : on_step_(std::move(on_step)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) return ceres::SOLVER_CONTINUE;
    return on_step_() ? ceres::SOLVER_CONTINUE : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  std::function<bool()> on_step_;
};

}  // namespace

template <typename Scalar>
bool Trainer<Scalar>::run_lbfgs(const StageOptions& stage, const Callbacks& callbacks) {
  if (stage_step_ >= stage.steps) return true;
  resample();
  Eigen::VectorXd theta = field_.parameters().template cast<double>();
  auto* function = new LossFunction<Scalar>(
      static_cast<int>(field_.parameter_count()),
      [this](const Scalar* p, Scalar* g) { return loss_and_gradient(p, g); });
  ceres::GradientProblem problem(function);  // takes ownership
  ceres::GradientProblemSolver::Options options;
  options.line_search_direction_type = ceres::LBFGS;
  options.max_lbfgs_rank = stage.memory;
  options.max_num_iterations = stage.steps - stage_step_;
  options.function_tolerance = 0;
  options.gradient_tolerance = 0;
  options.parameter_tolerance = 0;
  options.logging_type = ceres::SILENT;
  options.update_state_every_iteration = true;
  bool stopped = false;
  double last = now_seconds();
  StepCallback callback([&] {
    // Ceres has just accepted a step; the parameter block holds it.
    field_.parameters() = theta.cast<Scalar>();
    const double t = now_seconds();
    step_ms_.push_back(1e3 * (t - last));
    last = t;
    ++stage_step_;
    ++global_step_;
    report(callbacks, stage, 0.0);
    if (options_.checkpoint_every > 0 && global_step_ % options_.checkpoint_every == 0 &&
        callbacks.checkpoint)
      callbacks.checkpoint();
    stopped = callbacks.stop_requested && callbacks.stop_requested();
    return !stopped;
  });
  options.callbacks.push_back(&callback);
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(options, problem, theta.data(), &summary);
  field_.parameters() = theta.cast<Scalar>();
  // Converged early (no further decrease possible): the stage is done.
  if (!stopped) {
    global_step_ += stage.steps - stage_step_;
    stage_step_ = stage.steps;
  }
  return !stopped;
}

template <typename Scalar>
bool Trainer<Scalar>::run(const Callbacks& callbacks) {
  started_ = now_seconds();
  started_step_ = global_step_;
  for (; stage_ < static_cast<int>(options_.stages.size()); ++stage_) {
    const StageOptions& stage = options_.stages[stage_];
    const bool finished = stage.optimizer == "lbfgs" ? run_lbfgs(stage, callbacks)
                                                     : run_adam(stage, callbacks);
    if (!finished) return false;
    double total = 0;
    for (double l : losses_) total += l;
    stage_losses_.push_back(total);
    stage_step_ = 0;
    adam_.reset();
  }
  return true;
}

template <typename Scalar>
void Trainer<Scalar>::save_state(io::H5Writer& file) const {
  file.create_group("trainer");
  file.write_attribute("trainer", "stage", static_cast<std::int64_t>(stage_));
  file.write_attribute("trainer", "stage_step", static_cast<std::int64_t>(stage_step_));
  file.write_attribute("trainer", "global_step", static_cast<std::int64_t>(global_step_));
  std::ostringstream engine;
  engine << rng_;
  file.write_attribute("trainer", "random_engine", engine.str());
  if (adam_) {
    file.write("trainer/adam/m", adam_->first_moment());
    file.write("trainer/adam/v", adam_->second_moment());
    file.write_attribute("trainer/adam/m", "t", static_cast<std::int64_t>(adam_->steps()));
  }
  for (size_t k = 0; k < terms_.size(); ++k)
    if (points_[k].size() > 0) file.write("trainer/points/" + std::to_string(k), points_[k]);
  file.write("trainer/stage_losses", stage_losses_);
}

template <typename Scalar>
void Trainer<Scalar>::load_state(const io::H5Reader& file) {
  stage_ = static_cast<int>(file.read_attribute<std::int64_t>("trainer", "stage"));
  stage_step_ = static_cast<int>(file.read_attribute<std::int64_t>("trainer", "stage_step"));
  global_step_ = file.read_attribute<std::int64_t>("trainer", "global_step");
  std::istringstream engine(file.read_attribute<std::string>("trainer", "random_engine"));
  engine >> rng_;
  if (file.has_dataset("trainer/adam/m") && stage_ < static_cast<int>(options_.stages.size())) {
    adam_ = std::make_unique<Adam<Scalar>>(field_.parameter_count(),
                                           AdamOptions{options_.stages[stage_].lr});
    adam_->first_moment() = file.read_vector<Scalar>("trainer/adam/m");
    adam_->second_moment() = file.read_vector<Scalar>("trainer/adam/v");
    adam_->set_steps(file.read_attribute<std::int64_t>("trainer/adam/m", "t"));
  }
  for (size_t k = 0; k < terms_.size(); ++k) {
    const std::string name = "trainer/points/" + std::to_string(k);
    if (!file.has_dataset(name)) continue;
    points_[k] = file.read_matrix<double>(name);
    points_scalar_[k] = points_[k].template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
  if (file.has_dataset("trainer/stage_losses")) {
    const Eigen::VectorXd s = file.read_vector<double>("trainer/stage_losses");
    stage_losses_.assign(s.data(), s.data() + s.size());
  }
}

template class Trainer<float>;
template class Trainer<double>;

}  // namespace nfield::solvers
