// SPDX-License-Identifier: MIT
#include "autodiff/small_gemm.h"

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <new>

// NFIELD_GEMM_FORCE_PORTABLE: the portable kernel on an AVX2 build too (its test).
#if defined(__AVX2__) && defined(__FMA__) && !defined(NFIELD_GEMM_FORCE_PORTABLE)
#include <immintrin.h>
#define NFIELD_GEMM_AVX2 1
#endif

namespace nfield::autodiff {
namespace {

using Index = Eigen::Index;

constexpr Index kMr = 16, kNr = 6;  // pack() holds up to kMr line pointers: kNr ≤ kMr
constexpr Index kKc = 256, kMc = 128, kNc = 44 * kNr;

#if NFIELD_GEMM_AVX2
// rows[i] ← column i of the 8 × 8 block whose row r is rows[r].
inline void transpose8(__m256 rows[8]) {
  __m256 t[8], u[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = _mm256_unpacklo_ps(rows[2 * i], rows[2 * i + 1]);
    t[2 * i + 1] = _mm256_unpackhi_ps(rows[2 * i], rows[2 * i + 1]);
  }
  for (int i = 0; i < 2; ++i) {
    u[4 * i] = _mm256_shuffle_ps(t[4 * i], t[4 * i + 2], 0x44);
    u[4 * i + 1] = _mm256_shuffle_ps(t[4 * i], t[4 * i + 2], 0xEE);
    u[4 * i + 2] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0x44);
    u[4 * i + 3] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0xEE);
  }
  for (int i = 0; i < 4; ++i) {
    rows[i] = _mm256_permute2f128_ps(u[i], u[i + 4], 0x20);
    rows[i + 4] = _mm256_permute2f128_ps(u[i], u[i + 4], 0x31);
  }
}

// dst[p · stride + r] ← src[r][p] for r < 8 (rows of `lines` < 8 read as zero) and p < depth,
// depth a multiple of 8; each store writes 8 floats, so with stride < 8 later stores
// overwrite the spill of earlier ones and dst needs 8 − stride floats of slack.
inline void transpose_lines(const float* const src[], int lines, Index depth, float* dst, Index stride) {
  __m256 block[8];
  for (Index p = 0; p < depth; p += 8) {
    for (int r = 0; r < 8; ++r) block[r] = r < lines ? _mm256_loadu_ps(src[r] + p) : _mm256_setzero_ps();
    transpose8(block);
    for (int q = 0; q < 8; ++q) _mm256_storeu_ps(dst + (p + q) * stride, block[q]);
  }
}
#endif

// dst[p · stride + r] ← lines[r][p] for r < count, 0 for count ≤ r < width; p < depth. The
// transposing copy of both packs (a panel's width is at most its stride).
void copy_transposed(const float* const lines[], Index count, Index width, Index depth, float* dst, Index stride) {
  Index done = 0;
#if NFIELD_GEMM_AVX2
  done = depth - depth % 8;
  for (Index group = 0; group < width; group += 8)
    transpose_lines(lines + group, static_cast<int>(std::clamp<Index>(count - group, 0, 8)), done, dst + group, stride);
#endif
  for (Index r = 0; r < width; ++r)
    for (Index p = done; p < depth; ++p) dst[p * stride + r] = r < count ? lines[r][p] : 0.0f;
}

// Panels start on cache lines: a 32-byte load of a row of A then never straddles two lines.
class PackBuffer {
 public:
  explicit PackBuffer(Index floats)
      : data_(static_cast<float*>(std::aligned_alloc(64, static_cast<std::size_t>((floats * 4 + 63) / 64 * 64)))) {
    if (!data_) throw std::bad_alloc();
  }
  float* data() const { return data_.get(); }

 private:
  struct Free {
    void operator()(float* p) const { std::free(p); }
  };
  std::unique_ptr<float, Free> data_;
};

// Elements (x, p), x in [x0, x0 + count), p in [p0, p0 + depth), into panels of `width` x's,
// k-major (width consecutive floats per p), zero-padded to whole panels. Element (x, p) is
// m[(p0 + p)·ld + x0 + x] when `along_x` (x contiguous), else m[(x0 + x)·ld + p0 + p].
// op(A) packs with x = its row (along_x without transposition), op(B) with x = its column
// (along_x when transposed).
void pack(bool along_x, const float* m, Index ld, Index x0, Index count, Index p0, Index depth, Index width,
          float* out) {
  for (Index panel = 0; panel < count; panel += width) {
    const Index filled = std::min(width, count - panel);
    if (along_x) {
      for (Index p = 0; p < depth; ++p) {
        const float* line = m + (p0 + p) * ld + x0 + panel;
        float* dst = out + p * width;
        for (Index x = 0; x < filled; ++x) dst[x] = line[x];
        for (Index x = filled; x < width; ++x) dst[x] = 0;
      }
    } else {
      const float* lines[kMr];
      for (Index x = 0; x < filled; ++x) lines[x] = m + (x0 + panel + x) * ld + p0;
      copy_transposed(lines, filled, width, depth, out, width);
    }
    out += depth * width;
  }
}

// C block ← β C + tile, for the valid rows × cols of the tile (column-major, leading
// dimension kMr). β = 0 never reads C.
void store_tile(const float* tile, Index rows, Index cols, float beta, float* c, Index ldc) {
  for (Index j = 0; j < cols; ++j) {
    float* column = c + j * ldc;
    const float* t = tile + j * kMr;
    if (beta == 0.0f)
      for (Index i = 0; i < rows; ++i) column[i] = t[i];
    else if (beta == 1.0f)
      for (Index i = 0; i < rows; ++i) column[i] += t[i];
    else
      for (Index i = 0; i < rows; ++i) column[i] = beta * column[i] + t[i];
  }
}

// C tile (rows × cols ≤ kMr × kNr) ← β C + Σ_p a_p b_pᵀ over depth, from one panel of each.
#if NFIELD_GEMM_AVX2
void micro_kernel(Index depth, const float* a, const float* b, Index rows, Index cols, float beta, float* c,
                  Index ldc) {
  __m256 c00 = _mm256_setzero_ps(), c10 = c00, c01 = c00, c11 = c00, c02 = c00, c12 = c00;
  __m256 c03 = c00, c13 = c00, c04 = c00, c14 = c00, c05 = c00, c15 = c00;
  for (Index p = 0; p < depth; ++p, a += kMr, b += kNr) {
    const __m256 a0 = _mm256_loadu_ps(a), a1 = _mm256_loadu_ps(a + 8);
    __m256 bb = _mm256_broadcast_ss(b);
    c00 = _mm256_fmadd_ps(a0, bb, c00), c10 = _mm256_fmadd_ps(a1, bb, c10);
    bb = _mm256_broadcast_ss(b + 1);
    c01 = _mm256_fmadd_ps(a0, bb, c01), c11 = _mm256_fmadd_ps(a1, bb, c11);
    bb = _mm256_broadcast_ss(b + 2);
    c02 = _mm256_fmadd_ps(a0, bb, c02), c12 = _mm256_fmadd_ps(a1, bb, c12);
    bb = _mm256_broadcast_ss(b + 3);
    c03 = _mm256_fmadd_ps(a0, bb, c03), c13 = _mm256_fmadd_ps(a1, bb, c13);
    bb = _mm256_broadcast_ss(b + 4);
    c04 = _mm256_fmadd_ps(a0, bb, c04), c14 = _mm256_fmadd_ps(a1, bb, c14);
    bb = _mm256_broadcast_ss(b + 5);
    c05 = _mm256_fmadd_ps(a0, bb, c05), c15 = _mm256_fmadd_ps(a1, bb, c15);
  }
  const __m256 sums[2 * kNr] = {c00, c10, c01, c11, c02, c12, c03, c13, c04, c14, c05, c15};
  if (rows == kMr && cols == kNr) {
    const __m256 scale = _mm256_set1_ps(beta);
    for (Index j = 0; j < kNr; ++j)
      for (Index h = 0; h < 2; ++h) {
        float* out = c + j * ldc + 8 * h;
        const __m256 sum = sums[2 * j + h];
        if (beta == 0.0f)
          _mm256_storeu_ps(out, sum);
        else if (beta == 1.0f)
          _mm256_storeu_ps(out, _mm256_add_ps(_mm256_loadu_ps(out), sum));
        else
          _mm256_storeu_ps(out, _mm256_fmadd_ps(scale, _mm256_loadu_ps(out), sum));
      }
    return;
  }
  alignas(32) float tile[kMr * kNr];
  for (Index i = 0; i < 2 * kNr; ++i) _mm256_store_ps(tile + 8 * i, sums[i]);
  store_tile(tile, rows, cols, beta, c, ldc);
}
#else
void micro_kernel(Index depth, const float* a, const float* b, Index rows, Index cols, float beta, float* c,
                  Index ldc) {
  float tile[kNr * kMr] = {};
  for (Index p = 0; p < depth; ++p, a += kMr, b += kNr)
    for (Index j = 0; j < kNr; ++j)
      for (Index i = 0; i < kMr; ++i) tile[j * kMr + i] += a[i] * b[j];
  store_tile(tile, rows, cols, beta, c, ldc);
}
#endif

}  // namespace

void small_gemm(GemmOp op_a, GemmOp op_b, Index m, Index n, Index k, const float* a, Index lda, const float* b,
                Index ldb, float beta, float* c, Index ldc) {
  if (m <= 0 || n <= 0) return;
  if (k <= 0) {
    for (Index j = 0; j < n; ++j)
      for (Index i = 0; i < m; ++i) c[i + j * ldc] = beta == 0.0f ? 0.0f : beta * c[i + j * ldc];
    return;
  }
  thread_local const PackBuffer packed_a(kMc * kKc), packed_b(kKc * kNc + 8);  // + the transposes' spill
  for (Index jc = 0; jc < n; jc += kNc) {
    const Index nc = std::min(kNc, n - jc);
    for (Index pc = 0; pc < k; pc += kKc) {
      const Index kc = std::min(kKc, k - pc);
      const float block_beta = pc == 0 ? beta : 1.0f;
      pack(op_b == GemmOp::kTranspose, b, ldb, jc, nc, pc, kc, kNr, packed_b.data());
      for (Index ic = 0; ic < m; ic += kMc) {
        const Index mc = std::min(kMc, m - ic);
        pack(op_a == GemmOp::kNone, a, lda, ic, mc, pc, kc, kMr, packed_a.data());
        for (Index ir = 0; ir < mc; ir += kMr) {
          const float* a_panel = packed_a.data() + (ir / kMr) * kc * kMr;
          for (Index jr = 0; jr < nc; jr += kNr) {
            micro_kernel(kc, a_panel, packed_b.data() + (jr / kNr) * kc * kNr, std::min(kMr, mc - ir),
                         std::min(kNr, nc - jr), block_beta, c + (ic + ir) + (jc + jr) * ldc, ldc);
          }
        }
      }
    }
  }
}

const char* small_gemm_kernel_name() {
#if NFIELD_GEMM_AVX2
  return "avx2-fma 16x6";
#else
  return "portable 16x6";
#endif
}

}  // namespace nfield::autodiff
