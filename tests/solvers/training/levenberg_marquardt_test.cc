// SPDX-License-Identifier: MIT
//
// The own Levenberg–Marquardt method (solvers/training/levenberg_marquardt.h) on small
// least-squares problems: on a linear one its step is the closed-form damped Gauss–Newton
// step and the radius triples after it; on a nonlinear one its iterates and radii are Ceres'
// (LEVENBERG_MARQUARDT, DENSE_NORMAL_CHOLESKY) iteration by iteration; rejected and non-finite
// trial points shrink the radius by Ceres' doubling factors and never move θ; a collapsed
// radius ends the run; a non-finite start fails; options are validated.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/training/dense_algebra.h"
#include "solvers/training/levenberg_marquardt.h"

namespace nfield::solvers {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// f(θ) and J(θ) (row-major m × P) given by a function; A and g through the BLAS kernels.
class DenseProblem : public NormalEquationsProblem {
 public:
  using Residuals = std::function<void(const Eigen::VectorXd&, Eigen::VectorXd&, RowMajor*)>;
  DenseProblem(Eigen::Index p, Residuals f) : p_(p), f_(std::move(f)) {}
  Eigen::Index parameter_count() const override { return p_; }
  double cost(const Eigen::VectorXd& theta) override {
    ++cost_calls;
    if (nan_trials > 0) {
      --nan_trials;
      return NAN;
    }
    Eigen::VectorXd r;
    f_(theta, r, nullptr);
    return 0.5 * r.squaredNorm();
  }
  double normal_equations(const Eigen::VectorXd& theta, Eigen::MatrixXd& a,
                          Eigen::VectorXd& g) override {
    Eigen::VectorXd r;
    RowMajor j;
    f_(theta, r, &j);
    a.setZero(p_, p_);
    g.setZero(p_);
    dense::add_gram(a, j.data(), j.rows());
    dense::add_transposed_product(g, j.data(), j.rows(), r.data());
    return 0.5 * r.squaredNorm();
  }
  int nan_trials = 0;  // the next `nan_trials` trial costs are NaN
  int cost_calls = 0;

 private:
  Eigen::Index p_;
  Residuals f_;
};

// f = M θ − b, with columns of very different scales.
struct Linear {
  Eigen::MatrixXd m = Eigen::MatrixXd::Random(30, 5) * Eigen::VectorXd::LinSpaced(5, 0.1, 40).asDiagonal();
  Eigen::VectorXd b = Eigen::VectorXd::Random(30);
  DenseProblem problem{5, [this](const Eigen::VectorXd& t, Eigen::VectorXd& r, RowMajor* j) {
                         r = m * t - b;
                         if (j) *j = m;
                       }};
};

TEST(OwnLevenbergMarquardt, StepIsTheDampedGaussNewtonStepOnALinearProblem) {
  Linear linear;
  LevenbergMarquardtOptions options;
  options.initial_radius = 0.7;
  LevenbergMarquardt lm(linear.problem, options);
  const Eigen::VectorXd theta0 = Eigen::VectorXd::Random(5);
  ASSERT_TRUE(lm.start(theta0));
  // The closed form: S = diag(1/(1 + √diag(MᵀM))), D = diag(S MᵀM S) (within the clamp).
  const Eigen::MatrixXd a = linear.m.transpose() * linear.m;
  const Eigen::VectorXd g = linear.m.transpose() * (linear.m * theta0 - linear.b);
  const Eigen::VectorXd s = (1.0 + a.diagonal().array().sqrt()).inverse().matrix();
  const Eigen::MatrixXd scaled = s.asDiagonal() * a * s.asDiagonal();
  const Eigen::MatrixXd damped =
      scaled + Eigen::MatrixXd(scaled.diagonal().asDiagonal()) / options.initial_radius;
  const Eigen::VectorXd expected = -(s.asDiagonal() * damped.ldlt().solve(s.cwiseProduct(g)));
  double model_decrease = 0;
  const Eigen::VectorXd delta = lm.step(&model_decrease);
  ASSERT_EQ(delta.size(), 5);
  EXPECT_LE((delta - expected).norm(), 1e-10 * expected.norm());
  const double cost0 = 0.5 * (linear.m * theta0 - linear.b).squaredNorm();
  const double cost1 = 0.5 * (linear.m * (theta0 + delta) - linear.b).squaredNorm();
  EXPECT_NEAR(model_decrease, cost0 - cost1, 1e-10 * cost0);  // the model is exact here

  // ρ = 1: accepted, and μ ← μ / max(1/3, 1 − (2ρ − 1)³) = 3μ.
  const LmIteration it = lm.iterate();
  EXPECT_TRUE(it.valid);
  EXPECT_TRUE(it.accepted);
  EXPECT_NEAR(it.relative_decrease, 1.0, 1e-8);
  EXPECT_LE((lm.parameters() - (theta0 + expected)).norm(), 1e-10 * theta0.norm());
  EXPECT_NEAR(lm.radius(), 3 * options.initial_radius, 1e-12);
  EXPECT_NEAR(lm.cost(), cost1, 1e-10 * cost0);
}

TEST(OwnLevenbergMarquardt, RejectedAndNonFiniteTrialsShrinkTheRadiusAndKeepTheta) {
  Linear linear;
  LevenbergMarquardt lm(linear.problem, {});
  const Eigen::VectorXd theta0 = Eigen::VectorXd::Random(5);
  ASSERT_TRUE(lm.start(theta0));
  const double cost0 = lm.cost(), radius0 = lm.radius();
  linear.problem.nan_trials = 3;
  // Ceres' rule: μ/2, then μ/2/4, then /8 (the factor doubles with each rejection).
  const double expected[] = {radius0 / 2, radius0 / 8, radius0 / 64};
  for (double radius : expected) {
    const LmIteration it = lm.iterate();
    EXPECT_TRUE(it.valid);
    EXPECT_FALSE(it.accepted);
    EXPECT_TRUE(std::isinf(it.trial_cost));
    EXPECT_EQ(lm.parameters(), theta0);
    EXPECT_EQ(lm.cost(), cost0);
    EXPECT_DOUBLE_EQ(lm.radius(), radius);
  }
  // A finite trial again: accepted, and the factor is back at 2 for the next rejection.
  EXPECT_TRUE(lm.iterate().accepted);
  EXPECT_LT(lm.cost(), cost0);
  const double after = lm.radius();
  linear.problem.nan_trials = 1;
  lm.iterate();
  EXPECT_DOUBLE_EQ(lm.radius(), after / 2);
  EXPECT_EQ(lm.termination(), LmTermination::kRunning);
}

TEST(OwnLevenbergMarquardt, CollapsedRadiusEndsTheRunAsConverged) {
  Linear linear;
  LevenbergMarquardt lm(linear.problem, {});
  ASSERT_TRUE(lm.start(Eigen::VectorXd::Random(5)));
  linear.problem.nan_trials = 1000;
  int iterations = 0;
  while (lm.termination() == LmTermination::kRunning && iterations < 100) {
    lm.iterate();
    ++iterations;
  }
  // 1e4 / 2^(1 + 2 + … + k) <= 1e-32 first at k = 15.
  EXPECT_EQ(iterations, 15);
  EXPECT_EQ(lm.termination(), LmTermination::kConvergence);
  EXPECT_NE(lm.message().find("Minimum trust region radius reached"), std::string::npos);
}

TEST(OwnLevenbergMarquardt, NonFiniteStartFails) {
  DenseProblem problem(2, [](const Eigen::VectorXd& t, Eigen::VectorXd& r, RowMajor* j) {
    r = Eigen::VectorXd::Constant(3, std::log(t(0)));  // NaN for θ₀ < 0
    if (j) *j = RowMajor::Ones(3, 2);
  });
  LevenbergMarquardt lm(problem, {});
  EXPECT_FALSE(lm.start(Eigen::Vector2d(-1, 0)));
  EXPECT_EQ(lm.termination(), LmTermination::kFailure);
  EXPECT_STREQ(to_string(lm.termination()), "FAILURE");
}

// f_i = θ₀ exp(θ₁ tᵢ) + θ₂ − yᵢ: Ceres' LM and the own one, from the same start, iteration by
// iteration (the start is far enough that some steps are rejected).
constexpr int kSamples = 40;
struct ExpFit {
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(kSamples, 0, 2);
  Eigen::VectorXd y = (2.5 * (-1.3 * t.array()).exp() + 0.4 +
                       0.01 * Eigen::VectorXd::Random(kSamples).array()).matrix();
  void evaluate(const double* p, double* r, double* j) const {
    for (int i = 0; i < kSamples; ++i) {
      const double e = std::exp(p[1] * t(i));
      r[i] = p[0] * e + p[2] - y(i);
      if (j) {
        j[3 * i] = e;
        j[3 * i + 1] = p[0] * t(i) * e;
        j[3 * i + 2] = 1;
      }
    }
  }
};

class ExpCost final : public ceres::SizedCostFunction<kSamples, 3> {
 public:
  explicit ExpCost(const ExpFit& fit) : fit_(fit) {}
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    fit_.evaluate(p[0], r, j ? j[0] : nullptr);
    return true;
  }

 private:
  const ExpFit& fit_;
};

TEST(OwnLevenbergMarquardt, IteratesAreCeresDenseNormalCholeskyOnes) {
  const ExpFit fit;
  const Eigen::Vector3d start(-4, 3, 8);
  const int iterations = 25;
  // Ceres: θ and the radius after each iteration.
  std::vector<Eigen::Vector3d> ceres_theta;
  std::vector<double> ceres_radius;
  Eigen::Vector3d theta = start;
  ceres::Problem problem;
  problem.AddResidualBlock(new ExpCost(fit), nullptr, theta.data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = iterations;
  options.function_tolerance = options.gradient_tolerance = options.parameter_tolerance = 0;
  options.update_state_every_iteration = true;
  options.logging_type = ceres::SILENT;
  struct Record final : ceres::IterationCallback {
    Eigen::Vector3d* theta;
    std::vector<Eigen::Vector3d>* thetas;
    std::vector<double>* radii;
    int rejected = 0;
    ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
      if (s.iteration > 0) {
        thetas->push_back(*theta);
        radii->push_back(s.trust_region_radius);
        rejected += !s.step_is_successful;
      }
      return ceres::SOLVER_CONTINUE;
    }
  } record;
  record.theta = &theta;
  record.thetas = &ceres_theta;
  record.radii = &ceres_radius;
  options.callbacks.push_back(&record);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ASSERT_EQ(ceres_theta.size(), static_cast<size_t>(iterations)) << summary.FullReport();
  EXPECT_GT(record.rejected, 0);  // the comparison covers rejected steps too

  DenseProblem own(3, [&fit](const Eigen::VectorXd& p, Eigen::VectorXd& r, RowMajor* j) {
    r.resize(kSamples);
    if (j) j->resize(kSamples, 3);
    fit.evaluate(p.data(), r.data(), j ? j->data() : nullptr);
  });
  LevenbergMarquardt lm(own, {});
  ASSERT_TRUE(lm.start(start));
  for (int i = 0; i < iterations; ++i) {
    lm.iterate();
    ASSERT_LE((lm.parameters() - ceres_theta[i]).norm(), 1e-8 * (1 + ceres_theta[i].norm()))
        << "iteration " << i + 1;
    ASSERT_NEAR(lm.radius(), ceres_radius[i], 1e-8 * ceres_radius[i]) << "iteration " << i + 1;
  }
  EXPECT_NEAR(2 * lm.cost(), 2 * summary.final_cost, 1e-10 + 1e-8 * summary.final_cost);
}

// The kernels against Eigen: JᵀJ and Jᵀf from row-major rows, and the blocked Cholesky over
// several blocks (and a last, partial one) against Eigen's LLT.
TEST(OwnLevenbergMarquardt, DenseKernelsMatchEigen) {
  const Eigen::Index p = 300, m = 170;
  const RowMajor j = RowMajor::Random(m, p);
  const Eigen::VectorXd f = Eigen::VectorXd::Random(m);
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(p, p);  // added to
  Eigen::VectorXd g = Eigen::VectorXd::Ones(p);
  {
    const dense::BlasThreads threads(2);
    dense::add_gram(a, j.data(), m);
    dense::add_transposed_product(g, j.data(), m, f.data());
  }
  const Eigen::MatrixXd expected = Eigen::MatrixXd::Identity(p, p) + j.transpose() * j;
  const Eigen::MatrixXd upper = a.triangularView<Eigen::Upper>();
  EXPECT_LE((upper - Eigen::MatrixXd(expected.triangularView<Eigen::Upper>())).norm(),
            1e-12 * expected.norm());
  EXPECT_LE((g - (Eigen::VectorXd::Ones(p) + j.transpose() * f)).norm(), 1e-12 * g.norm());
  const Eigen::VectorXd x = Eigen::VectorXd::Random(p);
  EXPECT_LE((dense::symmetric_product(a, x) - expected * x).norm(), 1e-12 * (expected * x).norm());

  Eigen::MatrixXd factor = a;
  ASSERT_TRUE(dense::cholesky(factor, 64));  // blocks of 64: four whole ones and 44 columns
  const Eigen::MatrixXd u = factor.triangularView<Eigen::Upper>();
  const Eigen::MatrixXd eigen_u = expected.llt().matrixU();
  EXPECT_LE((u - eigen_u).norm(), 1e-11 * eigen_u.norm());
  Eigen::VectorXd b = expected * x;
  factor = a;
  ASSERT_TRUE(dense::cholesky_solve(factor, b));
  EXPECT_LE((b - x).norm(), 1e-9 * x.norm());
  // Not positive definite: refused.
  Eigen::MatrixXd indefinite = a;
  indefinite(200, 200) = -1;
  EXPECT_FALSE(dense::cholesky(indefinite, 64));
}

TEST(OwnLevenbergMarquardt, OptionsAreValidated) {
  const auto message = [](LevenbergMarquardtOptions o) {
    try {
      o.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message({}), "");
  EXPECT_EQ(message({.initial_radius = 0}), "lm.initial_radius = 0: must be in [1e-12, 1e16]");
  EXPECT_EQ(message({.min_diagonal = 0}), "lm.min_diagonal = 0: must be > 0 and <= max_diagonal");
  EXPECT_EQ(message({.min_relative_decrease = 1}),
            "lm.min_relative_decrease = 1: must be in [0, 1)");
  EXPECT_EQ(message({.max_consecutive_invalid_steps = 0}),
            "lm.max_consecutive_invalid_steps = 0: must be >= 1");
  Linear linear;
  EXPECT_THROW(LevenbergMarquardt(linear.problem, {.max_radius = 1}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
