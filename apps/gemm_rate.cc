// SPDX-License-Identifier: MIT
#include "apps/gemm_rate.h"

#include <omp.h>

#include <algorithm>
#include <chrono>

namespace nfield::apps {

using MatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic>;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double gemm_flops(const std::vector<GemmShape>& shapes, Eigen::Index rows) {
  double flops = 0;
  for (const GemmShape& s : shapes)
    flops += (s.input_adjoint ? 3 : 2) * 2.0 * static_cast<double>(rows) * s.in * s.out;
  return flops;
}

double gemm_gflops(const std::vector<GemmShape>& shapes, Eigen::Index rows, int repeats) {
  std::vector<MatrixF> a, z, w, z_bar, a_bar, w_bar;
  for (const GemmShape& s : shapes) {
    a.push_back(MatrixF::Random(rows, s.in));
    w.push_back(MatrixF::Random(s.out, s.in));
    z.push_back(MatrixF(rows, s.out));
    z_bar.push_back(MatrixF::Random(rows, s.out));
    a_bar.push_back(MatrixF(rows, s.in));
    w_bar.push_back(MatrixF(s.out, s.in));
  }
  const double flops = gemm_flops(shapes, rows);
  const int threads = omp_get_max_threads();
  auto eigen_threaded = [&](Eigen::Index n) {
    for (size_t l = 0; l < shapes.size(); ++l) {
      z[l].topRows(n).noalias() = a[l].topRows(n) * w[l].transpose();
      w_bar[l].noalias() = z_bar[l].topRows(n).transpose() * a[l].topRows(n);
      if (shapes[l].input_adjoint) a_bar[l].topRows(n).noalias() = z_bar[l].topRows(n) * w[l];
    }
  };
  std::vector<MatrixF> partial(threads);
  auto row_split = [&] {
    for (size_t l = 0; l < shapes.size(); ++l) {
#pragma omp parallel num_threads(threads)
      {
        const int t = omp_get_thread_num();
        const Eigen::Index first = rows * t / threads, count = rows * (t + 1) / threads - first;
        z[l].middleRows(first, count).noalias() = a[l].middleRows(first, count) * w[l].transpose();
        partial[t].noalias() = z_bar[l].middleRows(first, count).transpose() * a[l].middleRows(first, count);
        if (shapes[l].input_adjoint)
          a_bar[l].middleRows(first, count).noalias() = z_bar[l].middleRows(first, count) * w[l];
      }
      w_bar[l] = partial[0];
      for (int t = 1; t < threads; ++t) w_bar[l] += partial[t];
    }
  };
  auto seconds_of = [](auto&& run) {
    const auto start = std::chrono::steady_clock::now();
    run();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto time = [&](auto&& run) {
    run();
    std::vector<double> seconds;
    for (int r = 0; r < repeats; ++r) seconds.push_back(seconds_of(run));
    return flops / median(seconds) * 1e-9;
  };
  const double split = time(row_split);
  // Eigen's own threading of the weight adjoint Z̄ᵀA (a small result summed over many rows)
  // can run far below its one-thread rate (docs/experiments.md): a probe on an eighth of the
  // rows tells whether it can win before the full repeats are spent on it.
  const Eigen::Index probe = std::max<Eigen::Index>(rows / 8, 1);
  eigen_threaded(probe);
  const double probe_rate = gemm_flops(shapes, probe) / seconds_of([&] { eigen_threaded(probe); }) * 1e-9;
  if (probe_rate < split / 1.5) return split;
  return std::max(split, time([&] { eigen_threaded(rows); }));
}

}  // namespace nfield::apps
