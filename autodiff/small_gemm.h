// SPDX-License-Identifier: MIT
//
// Float matrix products for the layers of narrow fields, on one thread:
//
//   C ← β C + op(A) op(B),   op(X) = X or Xᵀ,   C m × n, op(A) m × k, op(B) k × n,
//
// every matrix column-major with its leading dimension. The three products of an affine
// layer z = W a + b over the stacked streams (rows = points · streams, fields/dense.h) are
//   forward        Z = A Wᵀ      small_gemm(kNone, kTranspose, …, β = 0)
//   input adjoint  Ā = Z̄ W       small_gemm(kNone, kNone, …, β = 0)
//   weights        W̄ += Z̄ᵀ A     small_gemm(kTranspose, kNone, …, β = 1).
//
// Why not Eigen's product: at the shapes of these layers (k and n of 16–256, m of a block of
// 128 points times its streams) Eigen's float product leaves about half of an AVX2 core's FMA
// rate unused; the measured rates of both are in docs/experiments.md (2026-11-28).
//
// Method (the Goto/BLIS scheme): op(B) is copied in blocks of kc × nc into panels of nr
// columns laid out k-major (nr consecutive floats per k), op(A) in blocks of mc × kc into
// panels of mr rows (mr consecutive floats per k), so the innermost loop reads both operands
// contiguously whatever their transposition; a micro-kernel keeps an mr × nr tile of C in
// registers through the whole kc-long sum: per k it loads mr/8 vectors of A, broadcasts nr
// values of B and issues (mr/8)·nr fused multiply-adds. With AVX2 and FMA: mr = 16, nr = 6,
// twelve accumulators, and three registers left for the operands. The blocks (kc = 256,
// mc = 128, nc = 264) keep A's block (128 KiB) and B's (264 KiB) in a 512 KiB L2 and one
// panel of A (16 KiB) in L1 while the panels of B stream past it: per k the kernel then
// reads 24 bytes from L2 instead of the 64 of A's panel (BLIS's order; the other order, a
// panel of B held in L1, was slower at narrow widths and no faster at wide ones;
// docs/experiments.md, 2026-11-28, session 27). Copying costs m·k + k·n moves against
// 2 m n k flops: 1/32 of the arithmetic at n = 16, 1/512 at n = 256. The
// weight gradient copies both operands across their storage order; those copies go through
// 8 × 8 register transposes, without which they cost more than the products at width 16.
//
// Without AVX2 and FMA a portable kernel of the same shape runs instead (the compiler
// vectorises what it can). There is no AVX-512 kernel: no machine this project runs on has
// AVX-512 to test it on.
//
// Rounding: each element is one float sum of k products accumulated in k order within a
// block of kc, blocks added in order; its error is bounded by the usual k·u·Σ|a||b|
// (u = 2⁻²⁴), which tests/autodiff/small_gemm_test.cc asserts against a double product.
// β = 0 never reads C (C may hold NaN or be uninitialised).
#pragma once

#include <Eigen/Core>

namespace nfield::autodiff {

enum class GemmOp { kNone, kTranspose };

void small_gemm(GemmOp op_a, GemmOp op_b, Eigen::Index m, Eigen::Index n, Eigen::Index k, const float* a,
                Eigen::Index lda, const float* b, Eigen::Index ldb, float beta, float* c, Eigen::Index ldc);

// Whether small_gemm beats Eigen's product for C m × n with inner dimension k: both sides of
// C at least 16, and n or k at least 24. Below that the copies into panels and the padding of
// a tile cost more than the kernel gains (a 16 × 16 layer, an output layer of 1–4 columns);
// measured per shape in docs/experiments.md, 2026-11-28.
inline bool small_gemm_pays(Eigen::Index m, Eigen::Index n, Eigen::Index k) {
  return m >= 16 && n >= 16 && (n >= 24 || k >= 24);
}

// Which micro-kernel this build runs: "avx2-fma 16x6" or "portable 16x6".
const char* small_gemm_kernel_name();

}  // namespace nfield::autodiff
