// SPDX-License-Identifier: MIT
#include "solvers/trainer.h"

#include <ceres/cost_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>

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
  balance_.assign(terms_.size(), 1.0);
  pde_ = problem_.residual_term();
  if ((options_.adaptive.enabled || options_.causal.enabled || options_.balance.method != "fixed") &&
      (pde_ < 0 || pde_ >= static_cast<int>(terms_.size())))
    throw std::invalid_argument("training.adaptive, balance and causal need a PDE residual term");
  if (options_.causal.enabled && !problem_.domain().has_time())
    throw std::invalid_argument("training.causal needs a time axis (domain.time)");
  if (options_.sampler != "uniform")
    for (size_t k = 0; k < terms_.size(); ++k)
      // Seeds apart from the engine's and from each other (UnitSequence mixes them further).
      sequences_.emplace_back(options_.sampler, options_.seed * 0x100000001B3ull + 7919 * (k + 1));
  points_.resize(terms_.size());
  points_scalar_.resize(terms_.size());
  tangents_scalar_.resize(terms_.size());
  residuals_.resize(terms_.size());
  field_.set_evaluation({options_.block, options_.threads});
}

template <typename Scalar>
Trainer<Scalar>::~Trainer() = default;

template <typename Scalar>
void Trainer<Scalar>::resample() {
  for (size_t k = 0; k < terms_.size(); ++k) {
    {
      const AttachSequence attach(rng_, sequences_.empty() ? nullptr : &sequences_[k]);
      points_[k] = terms_[k].sample(rng_, options_.batch.at(terms_[k].batch_key));
    }
    if (static_cast<int>(k) == pde_) previous_adaptive_rows_ = adaptive_points_.rows();
    if (static_cast<int>(k) == pde_ && adaptive_points_.rows() > 0) {
      if (!points_[k].groups.empty() || points_[k].tangents.size() > 0)
        throw std::logic_error("training.adaptive: loss term '" + terms_[k].name +
                               "' reads groups of points or per-point tangents; refinement adds "
                               "single points");
      Eigen::MatrixXd joined(points_[k].x.rows() + adaptive_points_.rows(), points_[k].x.cols());
      joined << points_[k].x, adaptive_points_;
      points_[k].x = std::move(joined);
    }
    points_scalar_[k] = points_[k].x.template cast<Scalar>();
    tangents_scalar_[k] = points_[k].tangents.template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
}

template <typename Scalar>
double Trainer<Scalar>::term_loss(size_t k, const Scalar* params, double weight, Scalar* gradient) {
  const bool causal = options_.causal.enabled && static_cast<int>(k) == pde_ &&
                      causal_.point_weights.size() == points_[k].x.rows();
  const ResidualLoss<Scalar> loss(*residuals_[k], weight, points_[k].residual_rows(),
                                  causal ? &causal_.point_weights : nullptr);
  const autodiff::Batch<Scalar> batch{points_scalar_[k],
                                      tangents_scalar_[k].size() > 0 ? &tangents_scalar_[k] : nullptr,
                                      points_[k].groups};
  return field_.value_and_gradient(params, layouts_[k], batch, loss, gradient);
}

template <typename Scalar>
double Trainer<Scalar>::loss_and_gradient(const Scalar* params, Scalar* gradient) {
  Eigen::Map<autodiff::Vector<Scalar>>(gradient, field_.parameter_count()).setZero();
  double total = 0;
  for (size_t k = 0; k < terms_.size(); ++k) {
    losses_[k] = term_loss(k, params, terms_[k].weight * balance_[k], gradient);
    total += losses_[k];
  }
  return total;
}

template <typename Scalar>
void Trainer<Scalar>::balanced_gradient(Scalar* gradient) {
  const Eigen::Index n = field_.parameter_count();
  std::vector<autodiff::Vector<Scalar>> g(terms_.size());
  for (size_t k = 0; k < terms_.size(); ++k) {
    g[k] = autodiff::Vector<Scalar>::Zero(n);
    losses_[k] = term_loss(k, field_.parameters().data(), terms_[k].weight, g[k].data());
  }
  const Eigen::VectorXd pde = g[pde_].template cast<double>();
  const double alpha = options_.balance.alpha;
  Eigen::Map<autodiff::Vector<Scalar>> sum(gradient, n);
  sum.setZero();
  for (size_t k = 0; k < terms_.size(); ++k) {
    if (static_cast<int>(k) != pde_) {
      const double target = grad_norm_target(pde, g[k].template cast<double>(), terms_[k].weight, balance_[k]);
      balance_[k] = (1 - alpha) * balance_[k] + alpha * target;
    }
    sum += static_cast<Scalar>(balance_[k]) * g[k];
    losses_[k] *= balance_[k];
  }
}

template <typename Scalar>
Eigen::VectorXd Trainer<Scalar>::squared_residuals(size_t k, const Eigen::MatrixXd& x,
                                                   const Residual& residual) const {
  autodiff::Streams<Scalar> out;
  field_.evaluate(layouts_[k], x.cast<Scalar>(), out);
  autodiff::Streams<double> out_d;
  out_d.points = out.points;
  out_d.count = out.count;
  out_d.data = out.data.template cast<double>();
  Eigen::MatrixXd r;
  residual.evaluate(0, layouts_[k], out_d, r);
  return r.rowwise().squaredNorm();
}

template <typename Scalar>
void Trainer<Scalar>::begin_stage() {
  field_.begin_stage(stage_);
  for (size_t k = 0; k < terms_.size(); ++k) {
    if (!terms_[k].begin_stage) continue;
    terms_[k].begin_stage(stage_);
    if (residuals_[k]) residuals_[k] = terms_[k].residual(points_[k]);
  }
}

std::string lm_jacobian_too_large(double rows, Eigen::Index parameters) {
  if (rows * static_cast<double>(parameters) <= std::numeric_limits<int>::max()) return "";
  return std::to_string(static_cast<long long>(rows)) + " residuals x " +
         std::to_string(parameters) + " parameters, more than the 2^31 - 1 entries Ceres' " +
         "dense solvers hold; use fewer points (training.batch) or a smaller field";
}

template <typename Scalar>
int Trainer<Scalar>::segment_length(const StageOptions& stage, bool with_causal) const {
  int segment = stage.steps;
  if (stage.resample_every > 0) segment = std::min(segment, stage.resample_every);
  if (with_causal && options_.causal.enabled) segment = std::min(segment, options_.causal.every);
  if (options_.adaptive.enabled) segment = std::min(segment, options_.adaptive.every);
  return segment;
}

template <typename Scalar>
bool Trainer<Scalar>::stage_ends(const StageOptions& stage, int segment, int segment_start,
                                 bool early) const {
  return stage_step_ >= stage.steps ||
         (early && (segment >= stage.steps || stage_step_ == segment_start));
}

template <typename Scalar>
void Trainer<Scalar>::renew_points(const StageOptions& stage) {
  if (options_.adaptive.enabled) refine();
  if (stage.resample_every > 0)
    resample();
  else if (options_.adaptive.enabled)
    join_adaptive_points();
}

template <typename Scalar>
void Trainer<Scalar>::join_adaptive_points() {
  // The stage's own points stay; only the extra set behind them changes.
  const Eigen::Index own = points_[pde_].x.rows() - previous_adaptive_rows_;
  Eigen::MatrixXd joined(own + adaptive_points_.rows(), points_[pde_].x.cols());
  joined << points_[pde_].x.topRows(own), adaptive_points_;
  points_[pde_].x = std::move(joined);
  points_scalar_[pde_] = points_[pde_].x.template cast<Scalar>();
  residuals_[pde_] = terms_[pde_].residual(points_[pde_]);
  previous_adaptive_rows_ = adaptive_points_.rows();
}

template <typename Scalar>
void Trainer<Scalar>::refine() {
  TermPoints candidates;
  {
    const AttachSequence attach(rng_, sequences_.empty() ? nullptr : &sequences_[pde_]);
    candidates = terms_[pde_].sample(rng_, options_.adaptive.candidates);
  }
  const auto residual = terms_[pde_].residual(candidates);
  const std::vector<Eigen::Index> best =
      largest(squared_residuals(pde_, candidates.x, *residual), options_.adaptive.add);
  append_capped(adaptive_points_, candidates.x(best, Eigen::all), options_.adaptive.max_points);
}

template <typename Scalar>
void Trainer<Scalar>::update_causal() {
  const Eigen::VectorXd r2 = squared_residuals(pde_, points_[pde_].x, *residuals_[pde_]);
  const auto [t0, t1] = problem_.domain().time();
  causal_ = solvers::causal_weights(points_[pde_].x.col(problem_.domain().time_column()), r2, t0, t1,
                                    options_.causal.slices, options_.causal.epsilon);
}

template <typename Scalar>
std::vector<std::pair<std::string, double>> Trainer<Scalar>::extra_metrics() const {
  std::vector<std::pair<std::string, double>> out;
  if (options_.causal.enabled && !causal_.weights.empty())
    out.emplace_back("causal_min_weight", causal_.min_weight());
  if (options_.balance.method != "fixed")
    for (size_t k = 0; k < terms_.size(); ++k) out.emplace_back("balance_weight_" + names_[k], balance_[k]);
  if (options_.adaptive.enabled)
    out.emplace_back("adaptive_points", static_cast<double>(adaptive_points_.rows()));
  return out;
}

template <typename Scalar>
Progress Trainer<Scalar>::progress(const StageOptions& stage, double lr) const {
  Progress p;
  p.stage = stage_;
  p.optimizer = stage.optimizer;
  p.step = global_step_;
  p.total_steps = options_.total_steps();
  p.learning_rate = lr;
  p.term_names = names_;
  p.term_losses = losses_;
  for (double l : losses_) p.loss += l;
  if (options_.causal.enabled && !causal_.weights.empty())
    p.extras.emplace_back("causal min w", causal_.min_weight());
  const double elapsed = now_seconds() - stage_started_;
  const long done = global_step_ - stage_started_step_;
  p.steps_per_second = elapsed > 0 ? done / elapsed : 0;
  p.eta_seconds = p.steps_per_second > 0 ? (p.total_steps - p.step) / p.steps_per_second : 0;
  if (stage.seconds > 0) {
    // A time budget ends the stage first when it is shorter than its steps would take.
    const double left = std::max(0.0, stage.seconds - elapsed);
    const double later = p.steps_per_second > 0
                             ? (p.total_steps - (p.step - stage_step_ + stage.steps)) / p.steps_per_second
                             : 0;
    p.eta_seconds = std::min(p.eta_seconds, left + std::max(0.0, later));
  }
  return p;
}

template <typename Scalar>
void Trainer<Scalar>::report(const Callbacks& callbacks, const StageOptions& stage, double lr) {
  if (callbacks.progress) callbacks.progress(progress(stage, lr));
}

template <typename Scalar>
bool Trainer<Scalar>::run_adam(const StageOptions& stage, const Callbacks& callbacks) {
  if (!adam_) adam_ = std::make_unique<Adam<Scalar>>(field_.parameter_count(), AdamOptions{stage.lr});
  autodiff::Vector<Scalar> gradient(field_.parameter_count());
  for (; stage_step_ < stage.steps; ++stage_step_) {
    if (callbacks.stop_requested && callbacks.stop_requested()) return false;
    const double start = now_seconds();
    const bool refine_now = options_.adaptive.enabled && global_step_ > 0 &&
                            global_step_ % options_.adaptive.every == 0;
    if (refine_now) refine();
    const bool drawn = std::all_of(residuals_.begin(), residuals_.end(), [](const auto& r) { return r != nullptr; });
    if (refine_now || global_step_ % options_.resample_every == 0 || !drawn) resample();
    if (options_.causal.enabled) update_causal();
    if (options_.balance.method == "grad_norm" && global_step_ % options_.balance.every == 0)
      balanced_gradient(gradient.data());
    else
      loss_and_gradient(field_.parameters().data(), gradient.data());
    const double spent = now_seconds() - stage_started_;
    const double lr = stage.seconds > 0 ? stage.learning_rate_at(std::min(1.0, spent / stage.seconds))
                                        : stage.learning_rate(stage_step_);
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
    if (stage.seconds > 0 && now_seconds() - stage_started_ >= stage.seconds) {
      ++stage_step_;  // the stage is over: its budget is spent (the steps count what was run)
      break;
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
  using OnStep = std::function<bool(const ceres::IterationSummary&)>;
  explicit StepCallback(OnStep on_step) : on_step_(std::move(on_step)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) return ceres::SOLVER_CONTINUE;
    return on_step_(summary) ? ceres::SOLVER_CONTINUE : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

 private:
  OnStep on_step_;
};

// One loss term as a Ceres cost function: N·C residuals √(w/N)·r (point-major) over the
// single parameter block θ. Ceres evaluates it from one thread (num_threads = 1); the
// Jacobian pass runs in parallel inside.
template <typename Scalar>
class TermCost final : public ceres::CostFunction {
 public:
  TermCost(const fields::Field<Scalar>& network, const autodiff::StreamLayout& layout,
           const autodiff::Matrix<Scalar>& points,
           std::unique_ptr<autodiff::StreamResidual<Scalar>> residual)
      : network_(network), layout_(layout), points_(points), residual_(std::move(residual)) {
    this->set_num_residuals(static_cast<int>(points.rows() * residual_->components()));
    this->mutable_parameter_block_sizes()->push_back(static_cast<int>(network.parameter_count()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Index m = this->num_residuals(), p = network_.parameter_count();
    double* jacobian = jacobians ? jacobians[0] : nullptr;
    if constexpr (std::is_same_v<Scalar, double>) {
      network_.residuals_and_jacobian(parameters[0], layout_, autodiff::Batch<Scalar>{points_}, *residual_, residuals,
                                      jacobian);
    } else {
      theta_ = Eigen::Map<const Eigen::VectorXd>(parameters[0], p).cast<Scalar>();
      r_.resize(m);
      if (jacobian) j_.resize(m * p);
      network_.residuals_and_jacobian(theta_.data(), layout_, autodiff::Batch<Scalar>{points_}, *residual_, r_.data(),
                                      jacobian ? j_.data() : nullptr);
      Eigen::Map<Eigen::VectorXd>(residuals, m) = r_.template cast<double>();
      if (jacobian) Eigen::Map<Eigen::VectorXd>(jacobian, m * p) = j_.template cast<double>();
    }
    const Eigen::Map<const Eigen::VectorXd> r(residuals, m);
    if (!r.allFinite()) return false;
    if (jacobian) {
      if (!Eigen::Map<const Eigen::VectorXd>(jacobian, m * p).allFinite()) return false;
      // A trust-region method evaluates Jacobians only at its iterates.
      loss_at_iterate_ = r.squaredNorm();
    }
    return true;
  }

  // This term's loss (Σ f²) at the last point where the Jacobian was evaluated.
  double loss_at_iterate() const { return loss_at_iterate_; }
  // Its loss at θ, from a forward pass.
  double loss_at(const double* theta) const {
    Eigen::VectorXd r(this->num_residuals());
    const double* parameters[] = {theta};
    return Evaluate(parameters, r.data(), nullptr) ? r.squaredNorm() : NAN;
  }

 private:
  const fields::Field<Scalar>& network_;
  const autodiff::StreamLayout& layout_;
  const autodiff::Matrix<Scalar>& points_;
  std::unique_ptr<autodiff::StreamResidual<Scalar>> residual_;
  mutable autodiff::Vector<Scalar> theta_, r_, j_;
  mutable double loss_at_iterate_ = NAN;
};

}  // namespace

template <typename Scalar>
bool Trainer<Scalar>::run_lbfgs(const StageOptions& stage, const Callbacks& callbacks) {
  if (stage_step_ >= stage.steps) return true;
  resample();
  // λ stays as it is for the whole stage, and causal weights and the RAR set for a segment
  // of `every` iterations: a line search needs one objective. Each segment restarts Ceres
  // (and so the L-BFGS history) on the updated objective.
  const int segment = segment_length(stage, options_.causal.enabled);
  if (options_.causal.enabled) update_causal();
  Eigen::VectorXd theta = field_.parameters().template cast<double>();
  auto* function = new LossFunction<Scalar>(
      static_cast<int>(field_.parameter_count()),
      [this](const Scalar* p, Scalar* g) { return loss_and_gradient(p, g); });
  ceres::GradientProblem problem(function);  // takes ownership
  ceres::GradientProblemSolver::Options options;
  options.line_search_direction_type = ceres::LBFGS;
  options.max_lbfgs_rank = stage.memory;
  options.function_tolerance = 0;
  options.gradient_tolerance = 0;
  options.parameter_tolerance = 0;
  options.logging_type = ceres::SILENT;
  options.update_state_every_iteration = true;
  bool stopped = false;
  double last = now_seconds();
  StepCallback callback([&](const ceres::IterationSummary&) {
    // Ceres has just accepted a step; the parameter block holds it.
    field_.parameters() = theta.cast<Scalar>();
    stopped = !finish_ceres_step(stage, callbacks, last);
    return !stopped;
  });
  options.callbacks.push_back(&callback);
  while (true) {
    options.max_num_iterations = std::min(segment, stage.steps - stage_step_);
    const int segment_start = stage_step_;
    ceres::GradientProblemSolver::Summary summary;
    ceres::Solve(options, problem, theta.data(), &summary);
    field_.parameters() = theta.cast<Scalar>();
    // A segment that ends early (its line search found no decrease) ends the stage only when
    // the objective cannot change (no segments) or it made no step at all: an update of the
    // weights or points can give L-BFGS somewhere to go again.
    const bool early = summary.termination_type != ceres::NO_CONVERGENCE;
    if (stopped || stage_ends(stage, segment, segment_start, early)) break;
    renew_points(stage);
    if (options_.causal.enabled) update_causal();
  }
  // Converged early (no further decrease possible): the stage is done.
  if (!stopped) {
    global_step_ += stage.steps - stage_step_;
    stage_step_ = stage.steps;
  }
  return !stopped;
}

template <typename Scalar>
bool Trainer<Scalar>::finish_ceres_step(const StageOptions& stage, const Callbacks& callbacks,
                                        double& last) {
  const double t = now_seconds();
  step_ms_.push_back(1e3 * (t - last));
  last = t;
  ++stage_step_;
  ++global_step_;
  report(callbacks, stage, 0.0);
  if (options_.checkpoint_every > 0 && global_step_ % options_.checkpoint_every == 0 &&
      callbacks.checkpoint)
    callbacks.checkpoint();
  return !(callbacks.stop_requested && callbacks.stop_requested());
}

template <typename Scalar>
bool Trainer<Scalar>::run_lm(const StageOptions& stage, const Callbacks& callbacks) {
  if (stage_step_ >= stage.steps) return true;
  resample();
  // The least-squares problem is fixed for a segment of iterations: the whole stage, or
  // `resample_every` (new points) or adaptive.every (RAR points added) iterations. Each
  // segment is a new Ceres problem that starts from the trust-region radius the last ended
  // with, so the damping carries over.
  const int segment = segment_length(stage, false);
  Eigen::VectorXd theta = field_.parameters().template cast<double>();
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type =
      stage.linear_solver == "dense_normal_cholesky" ? ceres::DENSE_NORMAL_CHOLESKY : ceres::DENSE_QR;
  options.initial_trust_region_radius = stage.initial_radius;
  // Run the steps asked for; stop early only when no step decreases the loss any more
  // (the trust region collapses), not at Ceres' default relative tolerances, which end
  // far above the accuracy a double-precision field can reach.
  options.function_tolerance = 0;
  options.gradient_tolerance = 0;
  options.parameter_tolerance = 0;
  // Evaluation is parallel inside each cost function already.
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.update_state_every_iteration = true;
  bool stopped = false;
  double last = now_seconds();
  std::vector<std::unique_ptr<TermCost<Scalar>>> costs;
  StepCallback callback([&](const ceres::IterationSummary& summary) {
    field_.parameters() = theta.template cast<Scalar>();
    double total = 0;
    for (size_t k = 0; k < costs.size(); ++k) total += losses_[k] = costs[k]->loss_at_iterate();
    // Ceres' cost is ½Σf²; should its last Jacobian not have been at the iterate, recompute.
    if (!(std::abs(total - 2 * summary.cost) <= 1e-9 * 2 * summary.cost))
      for (size_t k = 0; k < costs.size(); ++k) losses_[k] = costs[k]->loss_at(theta.data());
    stopped = !finish_ceres_step(stage, callbacks, last);
    return !stopped;
  });
  options.callbacks.push_back(&callback);
  while (true) {
    // Ceres counts the entries of its dense Jacobian in an int.
    double rows = 0;
    for (size_t k = 0; k < terms_.size(); ++k) {
      if (!points_[k].groups.empty() || points_[k].tangents.size() > 0)
        throw std::runtime_error("training stage " + std::to_string(stage_ + 1) +
                                 " (lm): loss term '" + terms_[k].name +
                                 "' reads groups of points or per-point tangents; "
                                 "Levenberg-Marquardt takes per-point residuals at shared "
                                 "tangents only (use adam or lbfgs)");
      rows += static_cast<double>(points_[k].x.rows()) * residuals_[k]->components();
    }
    const std::string too_large = lm_jacobian_too_large(rows, field_.parameter_count());
    if (!too_large.empty())
      throw std::runtime_error("training stage " + std::to_string(stage_ + 1) +
                               " (lm): its Jacobian would be " + too_large);
    costs.clear();
    for (size_t k = 0; k < terms_.size(); ++k)
      costs.push_back(std::make_unique<TermCost<Scalar>>(
          field_, layouts_[k], points_scalar_[k],
          // λ of training.balance is held fixed here, as in L-BFGS; causal weights are not
          // applied in this stage (its residuals are the plain ones).
          std::make_unique<ScaledResidual<Scalar>>(*residuals_[k], terms_[k].weight * balance_[k],
                                                   points_[k].x.rows())));
    ceres::Problem::Options problem_options;
    problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    for (const auto& cost : costs) problem.AddResidualBlock(cost.get(), nullptr, theta.data());
    options.max_num_iterations = std::min(segment, stage.steps - stage_step_);
    const int segment_start = stage_step_;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    // Failing later (e.g. too many non-finite trial steps) ends the stage at its last iterate.
    if (summary.termination_type == ceres::FAILURE && summary.iterations.empty())
      throw std::runtime_error("training stage " + std::to_string(stage_ + 1) +
                               " (lm): Ceres failed: " + summary.message);
    field_.parameters() = theta.cast<Scalar>();
    if (summary.iterations.size() <= 1)  // no step taken: report the losses at the start
      for (size_t k = 0; k < costs.size(); ++k) losses_[k] = costs[k]->loss_at(theta.data());
    if (!summary.iterations.empty())
      options.initial_trust_region_radius = summary.iterations.back().trust_region_radius;
    // As in L-BFGS: an early end (the trust region collapsed) ends the stage only when the
    // problem cannot change or the segment made no step at all.
    const bool early = summary.termination_type != ceres::NO_CONVERGENCE;
    if (stopped || stage_ends(stage, segment, segment_start, early)) break;
    renew_points(stage);
  }
  if (!stopped) {
    global_step_ += stage.steps - stage_step_;
    stage_step_ = stage.steps;
  }
  return !stopped;
}

template <typename Scalar>
bool Trainer<Scalar>::run(const Callbacks& callbacks) {
  for (; stage_ < static_cast<int>(options_.stages.size()); ++stage_) {
    const StageOptions& stage = options_.stages[stage_];
    const double stage_started = stage_started_ = now_seconds();
    stage_started_step_ = global_step_;
    begin_stage();
    if (callbacks.stage_begins) callbacks.stage_begins(progress(stage, stage.lr));
    const bool finished = stage.optimizer == "lbfgs" ? run_lbfgs(stage, callbacks)
                          : stage.optimizer == "lm"  ? run_lm(stage, callbacks)
                                                     : run_adam(stage, callbacks);
    if (!finished) return false;
    double total = 0;
    for (double l : losses_) total += l;
    stage_losses_.push_back(total);
    stage_seconds_.push_back(now_seconds() - stage_started);
    stage_errors_.push_back(callbacks.stage_error ? callbacks.stage_error()
                                                  : std::numeric_limits<double>::quiet_NaN());
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
    // Points with a context (rays and their pixels) are drawn anew on resume.
    if (points_[k].x.size() > 0 && !points_[k].context) {
      file.write("trainer/points/" + std::to_string(k), points_[k].x);
      if (!points_[k].groups.empty())
        file.write("trainer/groups/" + std::to_string(k),
                   std::vector<std::int64_t>(points_[k].groups.begin(), points_[k].groups.end()));
      if (points_[k].tangents.size() > 0)
        file.write("trainer/tangents/" + std::to_string(k), points_[k].tangents);
    }
  file.write("trainer/stage_losses", stage_losses_);
  file.write("trainer/stage_errors", stage_errors_);
  for (size_t k = 0; k < sequences_.size(); ++k)
    file.write_attribute("trainer", "sequence_" + std::to_string(k), sequences_[k].state());
  if (adaptive_points_.rows() > 0) file.write("trainer/adaptive_points", adaptive_points_);
  file.write("trainer/balance_weights", balance_);
  if (!causal_.weights.empty()) file.write("trainer/causal_weights", causal_.weights);
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
    points_[k] = TermPoints(file.read_matrix<double>(name));
    const std::string groups = "trainer/groups/" + std::to_string(k);
    if (file.has_dataset(groups)) {
      const auto g = file.read_vector<std::int64_t>(groups);
      points_[k].groups.assign(g.data(), g.data() + g.size());
    }
    const std::string tangents = "trainer/tangents/" + std::to_string(k);
    if (file.has_dataset(tangents)) points_[k].tangents = file.read_matrix<double>(tangents);
    points_scalar_[k] = points_[k].x.template cast<Scalar>();
    tangents_scalar_[k] = points_[k].tangents.template cast<Scalar>();
    residuals_[k] = terms_[k].residual(points_[k]);
  }
  if (file.has_dataset("trainer/stage_losses")) {
    const Eigen::VectorXd s = file.read_vector<double>("trainer/stage_losses");
    stage_losses_.assign(s.data(), s.data() + s.size());
  }
  if (file.has_dataset("trainer/stage_errors")) {
    const Eigen::VectorXd e = file.read_vector<double>("trainer/stage_errors");
    stage_errors_.assign(e.data(), e.data() + e.size());
  }
  // Wall times are not state (a resumed run must end bit-identical): unknown for stages run
  // before the resume.
  stage_seconds_.assign(stage_losses_.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < sequences_.size(); ++k) {
    const std::string name = "sequence_" + std::to_string(k);
    if (file.has_attribute("trainer", name))
      sequences_[k].set_state(file.read_attribute<std::string>("trainer", name));
  }
  adaptive_points_.resize(0, 0);
  if (file.has_dataset("trainer/adaptive_points"))
    adaptive_points_ = file.read_matrix<double>("trainer/adaptive_points");
  if (file.has_dataset("trainer/balance_weights")) {
    const Eigen::VectorXd b = file.read_vector<double>("trainer/balance_weights");
    if (b.size() == static_cast<Eigen::Index>(balance_.size())) balance_.assign(b.data(), b.data() + b.size());
  }
  if (file.has_dataset("trainer/causal_weights")) {
    const Eigen::VectorXd c = file.read_vector<double>("trainer/causal_weights");
    causal_.weights.assign(c.data(), c.data() + c.size());
  }
}

template class Trainer<float>;
template class Trainer<double>;

}  // namespace nfield::solvers
