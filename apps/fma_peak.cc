// SPDX-License-Identifier: MIT
// The FMA peak of apps/gemm_rate.h. This file is compiled at -O3 without sanitizers in every
// build (apps/CMakeLists.txt): it measures the chip. Below -O3 the loop over the chains is not
// unrolled and the accumulators live in memory (a sanitizer build at -O1, or -O2, reported a
// quarter of the peak, below what the layer products reach).
#include <immintrin.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

#include "apps/gemm_rate.h"

namespace nfield::apps {

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
