// SPDX-License-Identifier: MIT
//
// The `lm` stage (solvers/training/optimizers.h): Levenberg–Marquardt on the loss terms'
// residuals (solvers/training/lm_terms.h), by the own method on the normal equations
// (backend: own, solvers/training/levenberg_marquardt.h) or by Ceres (backend: ceres).
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "io/text.h"
#include "solvers/training/ceres_stage.h"
#include "solvers/training/levenberg_marquardt.h"
#include "solvers/training/lm_terms.h"
#include "solvers/training/optimizers.h"

namespace nfield::solvers {
namespace {

[[noreturn]] void reject(const std::string& option, const std::string& value, const std::string& rule) {
  throw std::invalid_argument(option + " = " + value + ": " + rule);
}

template <typename T>
T in_range_or(const io::ConfigNode& node, std::string_view key, T lowest, T highest, T fallback) {
  return node.has(key) ? node.get_in_range<T>(key, lowest, highest) : fallback;
}

// Why a problem of this size cannot run on `backend` (empty when it can).
std::string too_large(const std::string& backend, double rows, Eigen::Index parameters) {
  if (backend == "ceres") {
    const std::string jacobian = lm_jacobian_too_large(rows, parameters);
    return jacobian.empty() ? jacobian : "a Jacobian of " + jacobian;
  }
  const std::string normal = lm_normal_equations_too_large(parameters);
  return normal.empty() ? normal : "normal equations of " + normal;
}

class LmOptimizer final : public OptimizerOf<LmOptimizer, LmStageOptions> {
 public:
  void read(const io::ConfigNode& s) override {
    options.backend = s.get_choice("backend", {"own", "ceres"}, options.backend);
    // Each backend's default: the own LM has one solver; Ceres' default stays dense_qr.
    const std::string solver = options.backend == "ceres" ? "dense_qr" : "dense_normal_cholesky";
    options.linear_solver = s.get_choice("linear_solver", {"dense_qr", "dense_normal_cholesky"}, solver);
    s.require("linear_solver", options.backend == "ceres" || options.linear_solver == "dense_normal_cholesky",
              "backend: own solves the normal equations by Cholesky (dense_normal_cholesky); "
              "dense_qr needs backend: ceres");
    options.initial_radius = in_range_or(s, "initial_radius", 1e-12, 1e16, options.initial_radius);
    options.resample_every = in_range_or(s, "resample_every", 0, 1 << 30, options.resample_every);
    options.validate();
  }
  void write(YAML::Node& y) const override {
    y["backend"] = options.backend;
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
    const std::string why = too_large(options.backend, size.residual_rows(), size.parameters());
    return why.empty() ? why : "an lm stage here would need " + why;
  }

  // The least-squares problem is fixed for a segment of iterations: the whole stage, or
  // `resample_every` (new points) or adaptive.every (RAR points added) iterations.
  template <typename Scalar>
  bool run_stage(TrainingStage<Scalar>& stage) {
    if (stage.step() >= stage.steps()) return true;
    stage.draw_points();
    return options.backend == "ceres" ? run_ceres(stage) : run_own(stage);
  }

 private:
  // The stage's terms at their current points, after checking that LM can take them.
  template <typename Scalar>
  std::vector<LeastSquaresTerm<Scalar>> terms_of(TrainingStage<Scalar>& stage) const {
    const std::string name = "training stage " + std::to_string(stage.index() + 1) + " (lm): ";
    double rows = 0;
    std::vector<LeastSquaresTerm<Scalar>> terms;
    for (size_t k = 0; k < stage.term_count(); ++k) {
      if (!stage.points(k).groups.empty() || stage.points(k).tangents.size() > 0)
        throw std::runtime_error(name + "loss term '" + stage.term_name(k) +
                                 "' reads groups of points or per-point tangents; Levenberg-Marquardt "
                                 "takes per-point residuals at shared tangents only (use adam or lbfgs)");
      rows += static_cast<double>(stage.points(k).x.rows()) * stage.residual(k).components();
      // λ of training.balance is held fixed here, as in L-BFGS; causal weights are not
      // applied in this stage (its residuals are the plain ones).
      terms.push_back({&stage.layout(k), &stage.points_in_scalar(k), &stage.residual(k), stage.weight(k)});
    }
    const std::string why = too_large(options.backend, rows, stage.field().parameter_count());
    if (!why.empty()) throw std::runtime_error(name + "it would need " + why);
    return terms;
  }

  template <typename Scalar>
  bool run_own(TrainingStage<Scalar>& stage) {
    const int segment = stage.segment_length(options.resample_every, false);
    fields::Field<Scalar>& field = stage.field();
    LevenbergMarquardtOptions lm_options;
    lm_options.initial_radius = options.initial_radius;
    lm_options.threads = field.network().options().threads;
    double radius = options.initial_radius;
    bool stopped = false;
    double last = now_seconds();
    LmTermination termination = LmTermination::kRunning;
    std::string message;
    while (true) {
      // Each segment is a new problem on its points, started at the radius the last ended
      // with (as the Ceres backend does).
      TermsNormalEquations<Scalar> problem(field, terms_of(stage), stage.communicator(),
                                           lm_options.threads, &stage.unknowns());
      const auto report = [&](const std::vector<double>& losses) {
        for (size_t k = 0; k < losses.size(); ++k) stage.set_term_loss(k, losses[k]);
      };
      LevenbergMarquardt lm(problem, lm_options);
      lm.set_radius(radius);
      const int segment_start = stage.step();
      const int iterations = std::min(segment, stage.steps() - stage.step());
      if (lm.start(field.parameters().template cast<double>())) {
        report(problem.losses_at_iterate());
        for (int i = 0; i < iterations && lm.termination() == LmTermination::kRunning; ++i) {
          if (lm.iterate().accepted) field.parameters() = lm.parameters().template cast<Scalar>();
          report(problem.losses_at_iterate());
          if (!finish_iteration(stage, last)) {
            stopped = true;
            break;
          }
        }
      } else {
        // Not finite at the start: a divergence before this stage when the losses are not
        // finite; else the Jacobian is not, and the stage fails at its start.
        problem.cost(field.parameters().template cast<double>());
        report(problem.losses_at_trial());
        if (!stage.check_finite(nullptr)) return false;
      }
      radius = lm.radius();
      termination = lm.termination();
      message = lm.message();
      if (termination == LmTermination::kRunning)
        message = "Maximum number of iterations reached. Number of iterations: " +
                  std::to_string(stage.step() - segment_start) + ".";
      const bool early = termination != LmTermination::kRunning;
      if (stopped || stage.ends_after_segment(segment, segment_start, early)) break;
      stage.renew_points(options.resample_every);
    }
    if (stopped) return false;
    end_stage(stage, to_string(termination), message);
    return true;
  }

  template <typename Scalar>
  bool run_ceres(TrainingStage<Scalar>& stage) {
    // Each segment (see run_stage) is a new Ceres problem that starts from the trust-region
    // radius the last ended with, so the damping carries over.
    if (stage.unknowns().active())
      throw std::runtime_error("training stage " + std::to_string(stage.index() + 1) +
                               " (lm, backend: ceres) cannot train unknown constants; use backend: own");
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
      stopped = !finish_iteration(stage, last);
      return !stopped;
    });
    ceres_options.callbacks.push_back(&callback);
    while (true) {
      const std::vector<LeastSquaresTerm<Scalar>> terms = terms_of(stage);
      costs.clear();
      for (const LeastSquaresTerm<Scalar>& term : terms)
        costs.push_back(std::make_unique<TermCost<Scalar>>(field, term, stage.communicator()));
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
    end_stage(stage, ceres::TerminationTypeToString(summary.termination_type), summary.message);
    return true;
  }
};

}  // namespace

void LmStageOptions::validate() const {
  if (backend != "own" && backend != "ceres") reject("lm.backend", backend, "must be own or ceres");
  if (linear_solver != "dense_qr" && linear_solver != "dense_normal_cholesky")
    reject("lm.linear_solver", linear_solver, "must be dense_qr or dense_normal_cholesky");
  if (backend == "own" && linear_solver != "dense_normal_cholesky")
    reject("lm.linear_solver", linear_solver, "backend own takes dense_normal_cholesky only");
  if (!(initial_radius >= 1e-12 && initial_radius <= 1e16))
    reject("lm.initial_radius", io::format_number(initial_radius), "must be in [1e-12, 1e16]");
  if (resample_every < 0)
    reject("lm.resample_every", std::to_string(resample_every), "must be >= 0");
}

std::string lm_jacobian_too_large(double rows, Eigen::Index parameters) {
  if (rows * static_cast<double>(parameters) <= std::numeric_limits<int>::max()) return "";
  return std::to_string(static_cast<long long>(rows)) + " residuals x " +
         std::to_string(parameters) + " parameters, more than the 2^31 - 1 entries Ceres' " +
         "dense solvers hold; use fewer points (training.batch) or a smaller field";
}

std::string lm_normal_equations_too_large(Eigen::Index parameters) {
  const double p = static_cast<double>(parameters);
  if (p * p <= std::numeric_limits<int>::max()) return "";
  return std::to_string(parameters) + " x " + std::to_string(parameters) +
         " (parameters), more than the 2^31 - 1 entries BLAS's int indexes; use a smaller field";
}

std::unique_ptr<Optimizer> make_lm_optimizer() { return std::make_unique<LmOptimizer>(); }

}  // namespace nfield::solvers
