// SPDX-License-Identifier: MIT
//
// Example 3 — integrals from a field trained through its derivative (AutoInt, Lindell et al.
// 2021), written with the library's pieces instead of `nfield run` (configs/autoint_cos.yaml
// does the same from a config).
//
// What it shows: a loss on a tangent stream (∂Φ/∂x, not Φ), so the field learns an
// antiderivative of f = cos(k·x); then every integral ∫ₐᵇ f dx is Φ(b) − Φ(a), two values of
// the field, checked against the exact integrals and against adaptive quadrature of the
// fitted ∂Φ/∂x, which needs many more evaluations for the same answer.
//
// Run:   build/examples/autoint_integrals --steps 3000
//        (rel. L2 error 3.1e-3 over 1000 intervals, 7 s; Adam alone: `nfield run
//        configs/autoint_cos.yaml` adds Levenberg–Marquardt and reaches 4.4e-6)
// Small: build/examples/autoint_integrals --steps 400 --max-error 3e-2
//        (1.7e-2, about 1 s on the 2-core machine)
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "fields/field.h"
#include "integrators/segment_integrals.h"
#include "solvers/training/adam.h"

using namespace nfield;

// 3. Train on new uniform points every step (x is the batch the loss reads).
void train(fields::Field<double>& field, const autodiff::StreamLayout& layout, const autodiff::StreamLoss<double>& loss,
           Eigen::MatrixXd& x, int steps, double lr, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(-1, 1);
  solvers::Adam<double> adam(field.parameter_count(), {lr});
  autodiff::Vector<double> gradient(field.parameter_count());
  const auto start = std::chrono::steady_clock::now();
  for (int step = 1; step <= steps; ++step) {
    for (Eigen::Index i = 0; i < x.rows(); ++i) x(i, 0) = uniform(rng);
    gradient.setZero();
    const double mse = field.value_and_gradient(field.parameters().data(), layout, autodiff::Batch<double>{x}, loss,
                                                gradient.data());
    const double rate = lr * 0.5 * (1 + std::cos(M_PI * (step - 1) / steps));  // cosine schedule
    adam.step(field.parameters().data(), gradient.data(), rate);
    if (step == 1 || step % std::max(1, steps / 10) == 0 || step == steps)
      std::printf("step %5d  loss %.3e  (%.1f s)\n", step, mse,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
}

int main(int argc, char** argv) {
  int steps = 3000, batch = 512, intervals = 1000;
  double k = 10, lr = 2e-3, max_error = 1;
  CLI::App app{"Fit an antiderivative through its derivative and read integrals from its values"};
  app.add_option("--steps", steps, "Adam steps")->check(CLI::Range(1, 1000000))->capture_default_str();
  app.add_option("--batch", batch, "Points per step")->check(CLI::Range(1, 1 << 20))->capture_default_str();
  app.add_option("--k", k, "f(x) = cos(k x) on [-1, 1]")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--lr", lr, "Learning rate")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--intervals", intervals, "Random intervals to integrate over")
      ->check(CLI::Range(1, 10000000))->capture_default_str();
  app.add_option("--max-error", max_error, "Exit 1 if the integrals' relative L2 error is above this")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  // 1. A small SIREN Φ: one input, one output, in double.
  fields::FieldOptions options;
  options.type = "siren";
  options.input_dim = 1;
  options.output_dim = 1;
  options.hidden = {32, 32};
  options.first_omega = k;
  options.hidden_omega = 1;
  fields::Field<double> field(options);

  // 2. The loss reads the tangent stream along x (stream 1 of the gradient layout), not the
  //    value: L = (1/N) Σ (∂Φ/∂x − f)², whose adjoint goes to that stream only.
  const autodiff::StreamLayout gradient_layout(autodiff::StreamSpec::gradient(1));
  Eigen::MatrixXd x(batch, 1);
  autodiff::LambdaLoss<double> loss([&](Eigen::Index first, const autodiff::StreamLayout&,
                                        const autodiff::Streams<double>& out, autodiff::Streams<double>& adjoint) {
    const Eigen::VectorXd f = (k * x.col(0).segment(first, out.points)).array().cos();
    const Eigen::VectorXd r = out.stream(1).col(0) - f;
    adjoint.stream(1).col(0) = 2 * r / static_cast<double>(batch);
    return r.squaredNorm() / static_cast<double>(batch);
  });

  // 3. Train on new uniform points every step (train above).
  std::mt19937_64 rng(0);
  train(field, gradient_layout, loss, x, steps, lr, rng);
  std::uniform_real_distribution<double> uniform(-1, 1);

  // 4. Integrals over random intervals from Φ's values at their ends.
  Eigen::MatrixXd a(intervals, 1), b(intervals, 1);
  for (int i = 0; i < intervals; ++i) {
    a(i, 0) = uniform(rng);
    b(i, 0) = uniform(rng);
    if (a(i, 0) > b(i, 0)) std::swap(a(i, 0), b(i, 0));
  }
  const integrators::PointFunction phi = [&field](const Eigen::MatrixXd& p) -> Eigen::VectorXd {
    return field.values(p).col(0);
  };
  const Eigen::VectorXd from_ends = integrators::antiderivative_differences(phi, a, b);
  const Eigen::VectorXd exact = ((k * b.array()).sin() - (k * a.array()).sin()) / k;
  const double error = (from_ends - exact).norm() / exact.norm();

  // 5. The same integrals by adaptive Gauss–Kronrod quadrature of the fitted ∂Φ/∂x.
  const integrators::PointFunction derivative = [&](const Eigen::MatrixXd& p) -> Eigen::VectorXd {
    autodiff::Streams<double> out;
    field.evaluate(gradient_layout, p, out);
    return out.stream(1).col(0);
  };
  integrators::AdaptiveQuadratureOptions quadrature_options;
  quadrature_options.tolerance = 0.1 * (from_ends - exact).norm() / std::sqrt(static_cast<double>(intervals));
  const auto quadrature = integrators::adaptive_gauss_kronrod(derivative, a, b, quadrature_options);
  std::printf("%d integrals of cos(%g x): rel. L2 error %.3e from 2 values each; quadrature of the fitted "
              "derivative: %.3e with %.1f evaluations each\n",
              intervals, k, error, (quadrature.integrals - exact).norm() / exact.norm(),
              static_cast<double>(quadrature.evaluations) / intervals);
  return error <= max_error ? 0 : 1;
}
