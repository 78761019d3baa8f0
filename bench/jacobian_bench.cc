// SPDX-License-Identifier: MIT
//
// Cost of per-point residual Jacobians (Sequential::residuals_and_jacobian) against the
// summed gradient pass (value_and_gradient) and against N one-point reverse passes, which
// give the same rows one at a time. Residual r = Δu − 1 on a tanh MLP, double, 1 thread.
// Run: build/bench/jacobian_bench
#include <benchmark/benchmark.h>

#include "fields/field.h"

namespace {

using namespace nfield;
using autodiff::Matrix;
using autodiff::Streams;
using autodiff::StreamLayout;

class LaplacianResidual final : public autodiff::StreamResidual<double> {
 public:
  int components() const override { return 1; }
  void evaluate(Eigen::Index, const StreamLayout& layout, const Streams<double>& out,
                Matrix<double>& r) const override {
    r = out.stream(layout.op(0)).col(0).array() - 1.0;
  }
  void backward(Eigen::Index, const StreamLayout& layout, const Streams<double>&,
                const Matrix<double>& r_bar, Streams<double>& adjoint) const override {
    adjoint.stream(layout.op(0)).col(0) += r_bar.col(0);
  }
};

struct Setup {
  explicit Setup(int width, Eigen::Index points)
      : field(options(width), {.block_points = 128, .threads = 1}),
        x(Eigen::MatrixXd::Random(points, 2)) {}
  static fields::FieldOptions options(int width) {
    fields::FieldOptions o;
    o.type = "mlp";
    o.activation = "tanh";
    o.hidden = {width, width, width};
    return o;
  }
  fields::Field<double> field;
  StreamLayout layout{autodiff::StreamSpec::laplacian(2)};
  Eigen::MatrixXd x;
  LaplacianResidual residual;
  autodiff::LambdaLoss<double> loss{[this](Eigen::Index first, const StreamLayout& l,
                                           const Streams<double>& out, Streams<double>& adjoint) {
    Matrix<double> r;
    residual.evaluate(first, l, out, r);
    residual.backward(first, l, out, (2.0 * r).eval(), adjoint);
    return r.squaredNorm();
  }};
};

void set_counters(benchmark::State& state, const Setup& s) {
  state.counters["P"] = static_cast<double>(s.field.parameter_count());
  state.counters["N"] = static_cast<double>(s.x.rows());
}

void BM_SummedGradient(benchmark::State& state) {
  Setup s(static_cast<int>(state.range(0)), state.range(1));
  Eigen::VectorXd g(s.field.parameter_count());
  for (auto _ : state) {
    g.setZero();
    benchmark::DoNotOptimize(s.field.network().value_and_gradient(
        s.field.parameters().data(), s.layout, s.x, s.loss, g.data()));
  }
  set_counters(state, s);
}

void BM_Jacobian(benchmark::State& state) {
  Setup s(static_cast<int>(state.range(0)), state.range(1));
  const Eigen::Index n = s.x.rows(), p = s.field.parameter_count();
  Eigen::VectorXd r(n);
  Eigen::VectorXd j(n * p);
  for (auto _ : state) {
    s.field.network().residuals_and_jacobian(s.field.parameters().data(), s.layout, s.x,
                                             s.residual, r.data(), j.data());
    benchmark::DoNotOptimize(j.data());
  }
  set_counters(state, s);
}

// Row n of J as the gradient of r(xₙ) alone: one reverse pass per point.
void BM_OnePointReversePasses(benchmark::State& state) {
  Setup s(static_cast<int>(state.range(0)), state.range(1));
  const Eigen::Index n = s.x.rows(), p = s.field.parameter_count();
  Eigen::MatrixXd j(p, n);
  const autodiff::LambdaLoss<double> one([&s](Eigen::Index first, const StreamLayout& l,
                                              const Streams<double>& out,
                                              Streams<double>& adjoint) {
    Matrix<double> r;
    s.residual.evaluate(first, l, out, r);
    s.residual.backward(first, l, out, Matrix<double>::Ones(r.rows(), 1), adjoint);
    return r(0, 0);
  });
  for (auto _ : state) {
    j.setZero();
    for (Eigen::Index i = 0; i < n; ++i)
      s.field.network().value_and_gradient(s.field.parameters().data(), s.layout, s.x.row(i), one,
                                           j.col(i).data());
    benchmark::DoNotOptimize(j.data());
  }
  set_counters(state, s);
}

BENCHMARK(BM_SummedGradient)->Args({32, 2048})->Args({64, 2048})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Jacobian)->Args({32, 2048})->Args({64, 2048})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OnePointReversePasses)->Args({32, 2048})->Args({64, 2048})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
