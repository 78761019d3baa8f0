// SPDX-License-Identifier: MIT
#include "solvers/training/optimizers.h"

#include <ceres/cost_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "solvers/training/adam.h"

namespace nfield::solvers {
namespace {

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

[[noreturn]] void reject(const std::string& option, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument(option + " = " + value + ": " + rule);
}

// Shortest form ("0", "1e-13"): std::to_string would print both as 0.000000.
std::string text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

template <typename T>
T in_range_or(const io::ConfigNode& node, std::string_view key, T lowest, T highest, T fallback) {
  return node.has(key) ? node.get_in_range<T>(key, lowest, highest) : fallback;
}

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
    // A non-finite trial point is rejected: the line search then tries a shorter step.
    return std::isfinite(*cost) && (!gradient || gradient_.allFinite());
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
// Jacobian pass runs in parallel inside. Over R ranks each computes the rows of its share of
// the points and gathers the others' (every rank's Ceres then solves the same whole
// problem, so all take the same step): the network passes split, the dense solve does not.
template <typename Scalar>
class TermCost final : public ceres::CostFunction {
 public:
  TermCost(const fields::Field<Scalar>& network, const autodiff::StreamLayout& layout,
           const autodiff::Matrix<Scalar>& points, const Residual& residual, double weight,
           Communicator& communicator)
      : network_(network), layout_(layout), points_(points), communicator_(communicator),
        share_(share_of(points.rows(), communicator.rank(), communicator.size())),
        residual_(residual, weight, points.rows(), share_.first) {
    this->set_num_residuals(static_cast<int>(points.rows() * residual_.components()));
    this->mutable_parameter_block_sizes()->push_back(static_cast<int>(network.parameter_count()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Index m = this->num_residuals(), p = network_.parameter_count();
    double* jacobian = jacobians ? jacobians[0] : nullptr;
    if (communicator_.size() == 1) {
      evaluate_rows(parameters[0], residuals, jacobian);
    } else {
      const std::size_t c = residual_.components();
      std::vector<std::size_t> rows(communicator_.size()), entries(communicator_.size());
      for (int r = 0; r < communicator_.size(); ++r) {
        rows[r] = c * share_of(points_.rows(), r, communicator_.size()).count;
        entries[r] = rows[r] * static_cast<std::size_t>(p);
      }
      mine_r_.resize(static_cast<Eigen::Index>(rows[communicator_.rank()]));
      if (jacobian) mine_j_.resize(static_cast<Eigen::Index>(entries[communicator_.rank()]));
      evaluate_rows(parameters[0], mine_r_.data(), jacobian ? mine_j_.data() : nullptr);
      communicator_.allgather(mine_r_.data(), rows, residuals);
      if (jacobian) communicator_.allgather(mine_j_.data(), entries, jacobian);
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
  // The residuals and Jacobian rows of this rank's points (all of them with one rank).
  void evaluate_rows(const double* theta, double* residuals, double* jacobian) const {
    if (share_.count == 0) return;
    const Eigen::Index m = share_.count * residual_.components(), p = network_.parameter_count();
    const autodiff::Batch<Scalar> batch{points_.middleRows(share_.first, share_.count)};
    if constexpr (std::is_same_v<Scalar, double>) {
      network_.residuals_and_jacobian(theta, layout_, batch, residual_, residuals, jacobian);
    } else {
      theta_ = Eigen::Map<const Eigen::VectorXd>(theta, p).cast<Scalar>();
      r_.resize(m);
      if (jacobian) j_.resize(m * p);
      network_.residuals_and_jacobian(theta_.data(), layout_, batch, residual_, r_.data(),
                                      jacobian ? j_.data() : nullptr);
      Eigen::Map<Eigen::VectorXd>(residuals, m) = r_.template cast<double>();
      if (jacobian) Eigen::Map<Eigen::VectorXd>(jacobian, m * p) = j_.template cast<double>();
    }
  }

  const fields::Field<Scalar>& network_;
  const autodiff::StreamLayout& layout_;
  const autodiff::Matrix<Scalar>& points_;
  Communicator& communicator_;
  Share share_;
  ScaledResidual<Scalar> residual_;
  mutable autodiff::Vector<Scalar> theta_, r_, j_;
  mutable Eigen::VectorXd mine_r_, mine_j_;
  mutable double loss_at_iterate_ = NAN;
};


// After a Ceres iteration has been accepted or rejected: its time since the last, the step
// counters, progress and checkpoints. Returns false when a stop is requested.
template <typename Scalar>
bool finish_ceres_step(TrainingStage<Scalar>& stage, double& last) {
  const double t = now_seconds();
  stage.finish_step(0.0, 1e3 * (t - last));
  last = t;
  return !stage.stop_requested();
}

// The report of a Ceres stage: why it ended, when short of its steps (CONVERGENCE: no
// decrease found; FAILURE: the line search or the linear solver gave up).
template <typename Scalar>
void end_ceres_stage(TrainingStage<Scalar>& stage, ceres::TerminationType type, const std::string& message) {
  const std::string termination = ceres::TerminationTypeToString(type);
  if (stage.step() >= stage.steps()) stage.set_termination(termination, message);
  else stage.end_early(type == ceres::FAILURE ? "failed" : "converged", termination, message);
}

class AdamOptimizer final : public OptimizerOf<AdamOptimizer, AdamStageOptions> {
 public:
  AdamOptimizer() = default;
  // A copy takes the options, not the moments: each run of a stage starts from its own.
  AdamOptimizer(const AdamOptimizer& other) : OptimizerOf(other) {}

  void read(const io::ConfigNode& s) override {
    AdamStageOptions& o = options;
    o.lr = s.get_or("lr", o.lr);
    s.require("lr", o.lr > 0, "expected a learning rate > 0");
    o.schedule = s.get_choice("schedule", {"constant", "cosine", "exponential"}, o.schedule);
    o.lr_final = s.get_or("lr_final", std::min(o.lr_final, o.lr));
    s.require("lr_final", o.lr_final > 0, "expected a learning rate > 0");
    o.seconds = s.get_or("seconds", o.seconds);
    s.require("seconds", o.seconds >= 0 && std::isfinite(o.seconds),
              "expected a number of seconds >= 0 (0: no time limit)");
    o.validate();
  }
  void write(YAML::Node& y) const override {
    y["lr"] = options.lr;
    y["schedule"] = options.schedule;
    y["lr_final"] = options.lr_final;
    if (options.seconds > 0) y["seconds"] = options.seconds;
  }

  template <typename Scalar>
  bool run_stage(TrainingStage<Scalar>& stage) {
    Adam<Scalar>& adam = state<Scalar>(stage.field().parameter_count());
    stage.set_time_budget(options.seconds);
    fields::Field<Scalar>& field = stage.field();
    autodiff::Vector<Scalar> gradient(field.parameter_count());
    // The state before the last update: its parameters' loss was finite. A non-finite step
    // goes back to it, so that what is kept (and checkpointed) is never a NaN state.
    struct {
      autodiff::Vector<Scalar> theta, m, v;
      std::int64_t t = -1;  // -1: none yet in this stage (the field is as the stage began)
    } good;
    const auto go_back = [&] {
      if (good.t < 0) return;
      field.parameters() = good.theta;
      adam.first_moment() = good.m;
      adam.second_moment() = good.v;
      adam.set_steps(good.t);
    };
    while (stage.step() < stage.steps()) {
      if (stage.stop_requested()) return false;
      const double start = now_seconds();
      stage.prepare_step();
      stage.step_gradient(gradient.data());
      const double lr =
          lr_scale_ * (options.seconds > 0
                           ? options.learning_rate_at(std::min(1.0, stage.seconds() / options.seconds))
                           : options.learning_rate(stage.step(), stage.steps()));
      bool finite = stage.check_finite(gradient.data());
      if (finite) {
        good.theta = field.parameters();
        good.m = adam.first_moment();
        good.v = adam.second_moment();
        good.t = adam.steps();
        adam.step(field.parameters().data(), gradient.data(), lr);
        finite = stage.check_finite_parameters();
      }
      if (!finite) {
        go_back();
        if (!stage.retry_after_divergence()) return false;
        lr_scale_ *= 0.5;
        continue;
      }
      stage.finish_step(lr, 1e3 * (now_seconds() - start));
      // The stage is over when its budget is spent (its steps count what was run).
      if (options.seconds > 0 && stage.seconds() >= options.seconds) {
        if (stage.step() < stage.steps())
          stage.end_early("time_budget", "", "its " + text(options.seconds) + " s were spent");
        break;
      }
    }
    return true;
  }

  void save(io::H5Writer& file, const std::string& group) const override {
    const auto write = [&](const auto& m, const auto& v, std::int64_t t) {
      file.write(group + "/adam/m", m);
      file.write(group + "/adam/v", v);
      file.write_attribute(group + "/adam/m", "t", t);
    };
    if (float_) write(float_->first_moment(), float_->second_moment(), float_->steps());
    else if (double_) write(double_->first_moment(), double_->second_moment(), double_->steps());
    else if (loaded_) write(loaded_->m, loaded_->v, loaded_->t);
    else return;
    // Only after a retry (training.on_divergence): checkpoints of other runs stay as they were.
    if (lr_scale_ != 1) file.write_attribute(group + "/adam/m", "lr_scale", lr_scale_);
  }
  void load(const io::H5Reader& file, const std::string& group) override {
    if (!file.has_dataset(group + "/adam/m")) return;
    // Read in double (exact for float moments); the training scalar is known when it runs.
    loaded_ = Moments{file.read_vector<double>(group + "/adam/m"),
                      file.read_vector<double>(group + "/adam/v"),
                      file.read_attribute<std::int64_t>(group + "/adam/m", "t")};
    lr_scale_ = file.has_attribute(group + "/adam/m", "lr_scale")
                    ? file.read_attribute<double>(group + "/adam/m", "lr_scale")
                    : 1.0;
  }

 private:
  struct Moments {
    Eigen::VectorXd m, v;
    std::int64_t t = 0;
  };

  template <typename Scalar>
  Adam<Scalar>& state(Eigen::Index parameters) {
    std::unique_ptr<Adam<Scalar>>* adam;
    if constexpr (std::is_same_v<Scalar, float>) adam = &float_;
    else adam = &double_;
    if (!*adam) {
      *adam = std::make_unique<Adam<Scalar>>(parameters, AdamOptions{options.lr});
      if (loaded_) {
        (*adam)->first_moment() = loaded_->m.template cast<Scalar>();
        (*adam)->second_moment() = loaded_->v.template cast<Scalar>();
        (*adam)->set_steps(loaded_->t);
        loaded_.reset();
      }
    }
    return **adam;
  }

  // Halved at each retry after a divergence (training.on_divergence: restore_and_halve_lr).
  double lr_scale_ = 1;
  // One of the two, in the training scalar, once the stage runs.
  std::unique_ptr<Adam<float>> float_;
  std::unique_ptr<Adam<double>> double_;
  std::optional<Moments> loaded_;
};

class LbfgsOptimizer final : public OptimizerOf<LbfgsOptimizer, LbfgsStageOptions> {
 public:
  void read(const io::ConfigNode& s) override {
    options.memory = in_range_or(s, "memory", 1, 1000, options.memory);
    options.resample_every = in_range_or(s, "resample_every", 0, 1 << 30, options.resample_every);
    options.validate();
  }
  void write(YAML::Node& y) const override {
    y["memory"] = options.memory;
    y["resample_every"] = options.resample_every;
  }

  template <typename Scalar>
  bool run_stage(TrainingStage<Scalar>& stage) {
    if (stage.step() >= stage.steps()) return true;
    stage.draw_points();
    // λ stays as it is for the whole stage, and causal weights and the RAR set for a segment
    // of `every` iterations: a line search needs one objective. Each segment restarts Ceres
    // (and so the L-BFGS history) on the updated objective.
    const int segment = stage.segment_length(options.resample_every, true);
    stage.update_weights();
    fields::Field<Scalar>& field = stage.field();
    Eigen::VectorXd theta = field.parameters().template cast<double>();
    auto* function = new LossFunction<Scalar>(
        static_cast<int>(field.parameter_count()),
        [&stage](const Scalar* p, Scalar* g) { return stage.loss_and_gradient(p, g); });
    ceres::GradientProblem problem(function);  // takes ownership
    ceres::GradientProblemSolver::Options ceres_options;
    ceres_options.line_search_direction_type = ceres::LBFGS;
    ceres_options.max_lbfgs_rank = options.memory;
    ceres_options.function_tolerance = 0;
    ceres_options.gradient_tolerance = 0;
    ceres_options.parameter_tolerance = 0;
    ceres_options.logging_type = ceres::SILENT;
    ceres_options.update_state_every_iteration = true;
    bool stopped = false;
    double last = now_seconds();
    StepCallback callback([&](const ceres::IterationSummary&) {
      // Ceres has just accepted a step; the parameter block holds it.
      field.parameters() = theta.cast<Scalar>();
      stopped = !finish_ceres_step(stage, last);
      return !stopped;
    });
    ceres_options.callbacks.push_back(&callback);
    ceres::GradientProblemSolver::Summary summary;
    while (true) {
      ceres_options.max_num_iterations = std::min(segment, stage.steps() - stage.step());
      const int segment_start = stage.step();
      ceres::Solve(ceres_options, problem, theta.data(), &summary);
      field.parameters() = theta.cast<Scalar>();
      // Ceres refuses to start from a point whose loss or gradient is not finite: the run has
      // diverged before this stage (find out where, for the report).
      // (Its initial_cost stays at its default, -1, when that first evaluation fails.)
      if (summary.termination_type == ceres::FAILURE && summary.iterations.empty()) {
        autodiff::Vector<Scalar> gradient(field.parameter_count());
        stage.loss_and_gradient(field.parameters().data(), gradient.data());
        if (!stage.check_finite(gradient.data())) return false;
      }
      // A segment that ends early (its line search found no decrease) ends the stage only
      // when the objective cannot change (no segments) or it made no step at all: an update
      // of the weights or points can give L-BFGS somewhere to go again.
      const bool early = summary.termination_type != ceres::NO_CONVERGENCE;
      if (stopped || stage.ends_after_segment(segment, segment_start, early)) break;
      stage.renew_points(options.resample_every);
      stage.update_weights();
    }
    if (stopped) return false;
    end_ceres_stage(stage, summary.termination_type, summary.message);
    return true;
  }
};

class LmOptimizer final : public OptimizerOf<LmOptimizer, LmStageOptions> {
 public:
  void read(const io::ConfigNode& s) override {
    options.linear_solver =
        s.get_choice("linear_solver", {"dense_qr", "dense_normal_cholesky"}, options.linear_solver);
    options.initial_radius = in_range_or(s, "initial_radius", 1e-12, 1e16, options.initial_radius);
    options.resample_every = in_range_or(s, "resample_every", 0, 1 << 30, options.resample_every);
    options.validate();
  }
  void write(YAML::Node& y) const override {
    y["linear_solver"] = options.linear_solver;
    y["initial_radius"] = options.initial_radius;
    y["resample_every"] = options.resample_every;
  }
  std::string refuse(const ProblemSize& size) const override {
    if (size.grouped_term) {
      const std::string grouped = size.grouped_term();
      if (!grouped.empty())
        return "loss term '" + grouped + "' reads groups of points or per-point tangents; Levenberg-Marquardt "
               "takes per-point residuals at shared tangents only (use adam or lbfgs)";
    }
    const std::string too_large = lm_jacobian_too_large(size.residual_rows(), size.parameters());
    return too_large.empty() ? too_large : "an lm stage here would need a Jacobian of " + too_large;
  }

  template <typename Scalar>
  bool run_stage(TrainingStage<Scalar>& stage) {
    if (stage.step() >= stage.steps()) return true;
    stage.draw_points();
    const std::string name = "training stage " + std::to_string(stage.index() + 1) + " (lm): ";
    // The least-squares problem is fixed for a segment of iterations: the whole stage, or
    // `resample_every` (new points) or adaptive.every (RAR points added) iterations. Each
    // segment is a new Ceres problem that starts from the trust-region radius the last ended
    // with, so the damping carries over.
    const int segment = stage.segment_length(options.resample_every, false);
    fields::Field<Scalar>& field = stage.field();
    Eigen::VectorXd theta = field.parameters().template cast<double>();
    ceres::Solver::Options ceres_options;
    ceres_options.minimizer_type = ceres::TRUST_REGION;
    ceres_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    ceres_options.linear_solver_type = options.linear_solver == "dense_normal_cholesky"
                                           ? ceres::DENSE_NORMAL_CHOLESKY
                                           : ceres::DENSE_QR;
    ceres_options.initial_trust_region_radius = options.initial_radius;
    // Run the steps asked for; stop early only when no step decreases the loss any more
    // (the trust region collapses), not at Ceres' default relative tolerances, which end
    // far above the accuracy a double-precision field can reach.
    ceres_options.function_tolerance = 0;
    ceres_options.gradient_tolerance = 0;
    ceres_options.parameter_tolerance = 0;
    // Evaluation is parallel inside each cost function already.
    ceres_options.num_threads = 1;
    ceres_options.logging_type = ceres::SILENT;
    ceres_options.update_state_every_iteration = true;
    bool stopped = false;
    double last = now_seconds();
    std::vector<std::unique_ptr<TermCost<Scalar>>> costs;
    ceres::Solver::Summary summary;
    StepCallback callback([&](const ceres::IterationSummary& summary) {
      field.parameters() = theta.template cast<Scalar>();
      double total = 0;
      for (size_t k = 0; k < costs.size(); ++k) {
        const double loss = costs[k]->loss_at_iterate();
        stage.set_term_loss(k, loss);
        total += loss;
      }
      // Ceres' cost is ½Σf²; should its last Jacobian not have been at the iterate, recompute.
      if (!(std::abs(total - 2 * summary.cost) <= 1e-9 * 2 * summary.cost))
        for (size_t k = 0; k < costs.size(); ++k) stage.set_term_loss(k, costs[k]->loss_at(theta.data()));
      stopped = !finish_ceres_step(stage, last);
      return !stopped;
    });
    ceres_options.callbacks.push_back(&callback);
    while (true) {
      // Ceres counts the entries of its dense Jacobian in an int.
      double rows = 0;
      for (size_t k = 0; k < stage.term_count(); ++k) {
        if (!stage.points(k).groups.empty() || stage.points(k).tangents.size() > 0)
          throw std::runtime_error(name + "loss term '" + stage.term_name(k) +
                                   "' reads groups of points or per-point tangents; Levenberg-Marquardt "
                                   "takes per-point residuals at shared tangents only (use adam or lbfgs)");
        rows += static_cast<double>(stage.points(k).x.rows()) * stage.residual(k).components();
      }
      const std::string too_large = lm_jacobian_too_large(rows, field.parameter_count());
      if (!too_large.empty())
        throw std::runtime_error(name + "its Jacobian would be " + too_large);
      costs.clear();
      for (size_t k = 0; k < stage.term_count(); ++k)
        // λ of training.balance is held fixed here, as in L-BFGS; causal weights are not
        // applied in this stage (its residuals are the plain ones).
        costs.push_back(std::make_unique<TermCost<Scalar>>(field, stage.layout(k),
                                                           stage.points_in_scalar(k),
                                                           stage.residual(k), stage.weight(k),
                                                           stage.communicator()));
      ceres::Problem::Options problem_options;
      problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      ceres::Problem problem(problem_options);
      for (const auto& cost : costs) problem.AddResidualBlock(cost.get(), nullptr, theta.data());
      ceres_options.max_num_iterations = std::min(segment, stage.steps() - stage.step());
      const int segment_start = stage.step();
      summary = ceres::Solver::Summary{};
      ceres::Solve(ceres_options, &problem, &summary);
      // Ceres cannot start where a residual is not finite: the run diverged before this
      // stage. (Failing later, e.g. after too many non-finite trial steps, ends the stage at
      // its last iterate, reported as failed.)
      if (summary.termination_type == ceres::FAILURE && summary.iterations.empty()) {
        for (size_t k = 0; k < costs.size(); ++k) stage.set_term_loss(k, costs[k]->loss_at(theta.data()));
        if (!stage.check_finite(nullptr)) return false;
      }
      field.parameters() = theta.cast<Scalar>();
      if (summary.iterations.size() <= 1)  // no step taken: report the losses at the start
        for (size_t k = 0; k < costs.size(); ++k) stage.set_term_loss(k, costs[k]->loss_at(theta.data()));
      if (!summary.iterations.empty())
        ceres_options.initial_trust_region_radius = summary.iterations.back().trust_region_radius;
      // As in L-BFGS: an early end (the trust region collapsed) ends the stage only when the
      // problem cannot change or the segment made no step at all.
      const bool early = summary.termination_type != ceres::NO_CONVERGENCE;
      if (stopped || stage.ends_after_segment(segment, segment_start, early)) break;
      stage.renew_points(options.resample_every);
    }
    if (stopped) return false;
    end_ceres_stage(stage, summary.termination_type, summary.message);
    return true;
  }
};

}  // namespace

void AdamStageOptions::validate() const {
  if (!(lr > 0)) reject("adam.lr", text(lr), "must be > 0");
  if (schedule != "constant" && schedule != "cosine" && schedule != "exponential")
    reject("adam.schedule", schedule, "must be constant, cosine or exponential");
  if (!(lr_final > 0)) reject("adam.lr_final", text(lr_final), "must be > 0");
  if (!(seconds >= 0 && std::isfinite(seconds)))
    reject("adam.seconds", text(seconds), "must be finite and >= 0");
}

double AdamStageOptions::learning_rate(int step, int steps) const {
  return learning_rate_at(steps > 1 ? static_cast<double>(step) / (steps - 1) : 1.0);
}

double AdamStageOptions::learning_rate_at(double progress) const {
  if (schedule == "cosine")
    return lr_final + 0.5 * (lr - lr_final) * (1 + std::cos(std::numbers::pi * progress));
  if (schedule == "exponential") return lr * std::pow(lr_final / lr, progress);
  return lr;
}

void LbfgsStageOptions::validate() const {
  if (memory < 1 || memory > 1000) reject("lbfgs.memory", std::to_string(memory), "must be in [1, 1000]");
  if (resample_every < 0)
    reject("lbfgs.resample_every", std::to_string(resample_every), "must be >= 0");
}

void LmStageOptions::validate() const {
  if (linear_solver != "dense_qr" && linear_solver != "dense_normal_cholesky")
    reject("lm.linear_solver", linear_solver, "must be dense_qr or dense_normal_cholesky");
  if (!(initial_radius >= 1e-12 && initial_radius <= 1e16))
    reject("lm.initial_radius", text(initial_radius), "must be in [1e-12, 1e16]");
  if (resample_every < 0)
    reject("lm.resample_every", std::to_string(resample_every), "must be >= 0");
}

std::string lm_jacobian_too_large(double rows, Eigen::Index parameters) {
  if (rows * static_cast<double>(parameters) <= std::numeric_limits<int>::max()) return "";
  return std::to_string(static_cast<long long>(rows)) + " residuals x " +
         std::to_string(parameters) + " parameters, more than the 2^31 - 1 entries Ceres' " +
         "dense solvers hold; use fewer points (training.batch) or a smaller field";
}

void register_optimizers(Registry<OptimizerFactory>& registry) {
  registry.add("adam", [] { return std::make_unique<AdamOptimizer>(); });
  registry.add("lbfgs", [] { return std::make_unique<LbfgsOptimizer>(); });
  registry.add("lm", [] { return std::make_unique<LmOptimizer>(); });
}

namespace {
Registry<OptimizerFactory>& optimizers() {
  static Registry<OptimizerFactory> registry = [] {
    Registry<OptimizerFactory> r("optimizer");
    register_optimizers(r);
    return r;
  }();
  return registry;
}
}  // namespace

void register_optimizer(std::string_view name, OptimizerFactory factory) {
  optimizers().add(name, std::move(factory));
}

std::unique_ptr<Optimizer> make_optimizer(std::string_view name) { return optimizers().at(name)(); }

std::vector<std::string> optimizer_names() { return optimizers().names(); }

}  // namespace nfield::solvers
