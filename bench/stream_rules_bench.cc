// SPDX-License-Identifier: MIT
//
// Micro-benchmarks of the derivative-stream rules (Google Benchmark), for profiling the
// pieces of a training step; `nfield bench` times whole steps against the GEMM rate.
// Run: build/bench/stream_rules_bench
#include <benchmark/benchmark.h>

#include "fields/activations.h"
#include "fields/field.h"

namespace {

using namespace nfield;

void BM_SineStreamsForwardBackward(benchmark::State& state) {
  const Eigen::Index points = state.range(0), width = 256;
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  autodiff::Streams<float> z, y, y_bar, z_bar;
  z.resize(points, layout.count(), width);
  z.data.setRandom();
  y_bar.resize(points, layout.count(), width);
  y_bar.data.setRandom();
  const auto sine = fields::make_activation<float>({"sine", 30.0});
  std::vector<autodiff::Matrix<float>> tables;
  for (auto _ : state) {
    sine->derivatives(z.stream(0), layout.forward_order() + 1, tables);
    autodiff::elementwise_forward(layout, tables, z, y);
    autodiff::elementwise_backward(layout, tables, z, y_bar, z_bar);
    benchmark::DoNotOptimize(z_bar.data.data());
  }
  state.SetItemsProcessed(state.iterations() * points * width);
}
BENCHMARK(BM_SineStreamsForwardBackward)->Arg(128)->Arg(512);

void BM_TaylorOrder4ForwardBackward(benchmark::State& state) {
  const Eigen::Index points = state.range(0), width = 256;
  autodiff::StreamSpec spec = autodiff::StreamSpec::values(2);
  Eigen::MatrixXd directions(2, 4);
  directions << 1, 0, 1, 1, 0, 1, 1, -1;
  spec.set_taylor(directions, 4);
  const autodiff::StreamLayout layout(spec);
  autodiff::Streams<float> z, y, y_bar, z_bar;
  z.resize(points, layout.count(), width);
  z.data.setRandom();
  y_bar.resize(points, layout.count(), width);
  y_bar.data.setRandom();
  const auto sine = fields::make_activation<float>({"sine", 30.0});
  std::vector<autodiff::Matrix<float>> tables;
  for (auto _ : state) {
    sine->derivatives(z.stream(0), layout.forward_order() + 1, tables);
    autodiff::elementwise_forward(layout, tables, z, y);
    autodiff::elementwise_backward(layout, tables, z, y_bar, z_bar);
    benchmark::DoNotOptimize(z_bar.data.data());
  }
  state.SetItemsProcessed(state.iterations() * points * width);
}
BENCHMARK(BM_TaylorOrder4ForwardBackward)->Arg(128);

void BM_SirenLaplacianGradient(benchmark::State& state) {
  fields::FieldOptions options;
  options.hidden = {64, 64, 64};
  fields::Field<float> field(options, {128, 1});
  const autodiff::StreamLayout layout(autodiff::StreamSpec::laplacian(2));
  const autodiff::Matrix<float> x = autodiff::Matrix<float>::Random(state.range(0), 2);
  autodiff::LambdaLoss<float> loss([](Eigen::Index, const autodiff::StreamLayout&,
                                      const autodiff::Streams<float>& out,
                                      autodiff::Streams<float>& adjoint) {
    adjoint.stream(3) = out.stream(3);
    return 0.5 * out.stream(3).squaredNorm();
  });
  autodiff::Vector<float> gradient(field.parameter_count());
  for (auto _ : state) {
    gradient.setZero();
    benchmark::DoNotOptimize(field.network().value_and_gradient(field.parameters().data(), layout, x,
                                                                loss, gradient.data()));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_SirenLaplacianGradient)->Arg(1024);

}  // namespace

BENCHMARK_MAIN();
