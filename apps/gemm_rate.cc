// SPDX-License-Identifier: MIT
#include "apps/gemm_rate.h"

#include <immintrin.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

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

namespace {

// Twelve independent chains hide the FMA latency (4 cycles, two pipes on current x86 cores:
// 8 in flight are enough) and fit in the 16 or 32 vector registers with the two constants.
constexpr int kChains = 12;

// One vector type V with its set1 and fma: the chains run in registers, then sum to a float
// that the caller keeps (so no chain is optimised away).
template <class V, int Lanes, class Set1, class Fma>
float fma_chains(long iterations, Set1 set1, Fma fma) {
  V acc[kChains];
  for (int c = 0; c < kChains; ++c) acc[c] = set1(static_cast<float>(c));
  const V m = set1(0.999999f), b = set1(1e-7f);
  for (long i = 0; i < iterations; ++i)
    for (int c = 0; c < kChains; ++c) acc[c] = fma(acc[c], m, b);
  alignas(64) float lanes[Lanes];
  float sum = 0;
  for (int c = 0; c < kChains; ++c) {
    std::memcpy(lanes, &acc[c], sizeof lanes);
    for (float v : lanes) sum += v;
  }
  return sum;
}

#if defined(__AVX512F__)
constexpr int kLanes = 16;
float fma_chains(long iterations) {
  return fma_chains<__m512, kLanes>(iterations, [](float v) { return _mm512_set1_ps(v); },
                                    [](__m512 a, __m512 m, __m512 b) { return _mm512_fmadd_ps(a, m, b); });
}
#elif defined(__AVX2__) && defined(__FMA__)
constexpr int kLanes = 8;
float fma_chains(long iterations) {
  return fma_chains<__m256, kLanes>(iterations, [](float v) { return _mm256_set1_ps(v); },
                                    [](__m256 a, __m256 m, __m256 b) { return _mm256_fmadd_ps(a, m, b); });
}
#else
constexpr int kLanes = 1;
float fma_chains(long iterations) {
  return fma_chains<float, kLanes>(iterations, [](float v) { return v; },
                                   [](float a, float m, float b) { return std::fma(a, m, b); });
}
#endif

}  // namespace

double fma_peak_gflops(int threads, int repeats) {
  const long iterations = 200'000'000 / kLanes;  // ~40 ms a run at 115 GFLOP/s a thread
  volatile float sink = 0;  // keeps the chains from being optimised away
  auto run = [&] {
    const auto start = std::chrono::steady_clock::now();
#pragma omp parallel num_threads(threads)
    {
      const float s = fma_chains(iterations);
#pragma omp critical
      sink = sink + s;
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  run();
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) seconds.push_back(run());
  const double flops = 2.0 * kLanes * kChains * static_cast<double>(iterations) * threads;
  return flops / *std::min_element(seconds.begin(), seconds.end()) * 1e-9;
}

}  // namespace nfield::apps
