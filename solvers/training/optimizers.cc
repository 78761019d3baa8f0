// SPDX-License-Identifier: MIT
#include "solvers/training/optimizers.h"

#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include "io/text.h"
#include "solvers/training/adam.h"
#include "solvers/training/ceres_stage.h"
#include "solvers/training/trained_unknowns.h"

namespace nfield::solvers {
namespace {

[[noreturn]] void reject(const std::string& option, const std::string& value,
                         const std::string& rule) {
  throw std::invalid_argument(option + " = " + value + ": " + rule);
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
    // Unknown constants with an `lr` of their own step at it (through the stage's schedule).
    if (const UnknownConstants* unknowns = stage.unknowns().constants())
      for (int i = 0; i < unknowns->count(); ++i)
        if (const auto& lr = unknowns->items()[static_cast<std::size_t>(i)].lr)
          adam.set_rate_scale(stage.field().network_parameter_count() + i, *lr / options.lr);
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
          stage.end_early("time_budget", "", "its " + io::format_number(options.seconds) + " s were spent");
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
      stopped = !finish_iteration(stage, last);
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
    end_stage(stage, ceres::TerminationTypeToString(summary.termination_type), summary.message);
    return true;
  }
};

}  // namespace

void AdamStageOptions::validate() const {
  if (!(lr > 0)) reject("adam.lr", io::format_number(lr), "must be > 0");
  if (schedule != "constant" && schedule != "cosine" && schedule != "exponential")
    reject("adam.schedule", schedule, "must be constant, cosine or exponential");
  if (!(lr_final > 0)) reject("adam.lr_final", io::format_number(lr_final), "must be > 0");
  if (!(seconds >= 0 && std::isfinite(seconds)))
    reject("adam.seconds", io::format_number(seconds), "must be finite and >= 0");
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

void register_optimizers(Registry<OptimizerFactory>& registry) {
  registry.add("adam", [] { return std::make_unique<AdamOptimizer>(); });
  registry.add("lbfgs", [] { return std::make_unique<LbfgsOptimizer>(); });
  registry.add("lm", [] { return make_lm_optimizer(); });
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
