// SPDX-License-Identifier: MIT
//
// What a benchmark's matrix products are measured against: plain Eigen products of the same
// shapes, timed in the same run, so that "% of the GEMM rate" compares a training step with
// this machine as it is at that moment rather than with a nominal peak.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace nfield::apps {

// One dense layer of a training step: forward Z = A Wᵀ (rows × in → rows × out), the weight
// adjoint W̄ = Z̄ᵀ A, and the input adjoint Ā = Z̄ W when something before the layer needs it.
struct GemmShape {
  Eigen::Index in = 0, out = 0;
  bool input_adjoint = true;
};

// Floating-point operations of those products over `rows` rows.
double gemm_flops(const std::vector<GemmShape>& shapes, Eigen::Index rows);

// GFLOP/s of the same products in float on `rows` rows, median of `repeats` timings after one
// untimed run, best of Eigen's own threading and an even split of the rows over the threads
// (the first only when a probe on fewer rows says it can win).
double gemm_gflops(const std::vector<GemmShape>& shapes, Eigen::Index rows, int repeats);

// GFLOP/s of independent float fused multiply-adds in registers on `threads` threads (the
// widest vectors the build targets: AVX-512, else AVX2 + FMA, else scalar std::fma), the best
// of `repeats` timings: the machine's arithmetic ceiling, which no product of any library can
// pass. The best, not the median, because a ceiling is what the chip can do: a timing that
// shared its cores with another process (a parallel test run) only shows less. A training step's products over this is the share of the chip that the step uses,
// whatever the BLAS, so it bounds what any implementation of the same step can reach.
double fma_peak_gflops(int threads, int repeats);

double median(std::vector<double> v);

}  // namespace nfield::apps
