// SPDX-License-Identifier: MIT
#include "solvers/training/dense_algebra.h"

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

// The Fortran interfaces of BLAS and LAPACK (every implementation has them; no header needed).
// Character arguments carry hidden lengths at the end (gfortran's convention; C
// implementations such as OpenBLAS ignore them).
extern "C" {
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* a, const int* lda, const double* beta, double* c, const int* ldc,
            std::size_t, std::size_t);
void dgemv_(const char* trans, const int* m, const int* n, const double* alpha, const double* a,
            const int* lda, const double* x, const int* incx, const double* beta, double* y,
            const int* incy, std::size_t);
void dsymv_(const char* uplo, const int* n, const double* alpha, const double* a, const int* lda,
            const double* x, const int* incx, const double* beta, double* y, const int* incy,
            std::size_t);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* a, const int* lda, double* b,
            const int* ldb, std::size_t, std::size_t, std::size_t, std::size_t);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda,
             double* b, const int* ldb, int* info, std::size_t);
}

namespace nfield::solvers::dense {
namespace {

// BLAS counts in int (LP64, as Debian builds it).
int blas_int(Eigen::Index n) {
  if (n > std::numeric_limits<int>::max())
    throw std::length_error("dense algebra: dimension " + std::to_string(n) +
                            " exceeds BLAS's int");
  return static_cast<int>(n);
}

}  // namespace

BlasThreads::BlasThreads(int threads, Eigen::Index order) : saved_(omp_get_max_threads()) {
  if (order < kParallelOrder) threads = 1;
  if (threads > 0) omp_set_num_threads(threads);
}

BlasThreads::~BlasThreads() { omp_set_num_threads(saved_); }

void add_gram(Eigen::MatrixXd& a, const double* rows, Eigen::Index m) {
  if (m == 0) return;
  const int n = blas_int(a.rows()), k = blas_int(m);
  const double one = 1;
  dsyrk_("U", "N", &n, &k, &one, rows, &n, &one, a.data(), &n, 1, 1);
}

void add_transposed_product(Eigen::VectorXd& g, const double* rows, Eigen::Index m,
                            const double* f) {
  if (m == 0) return;
  const int n = blas_int(g.size()), k = blas_int(m), inc = 1;
  const double one = 1;
  dgemv_("N", &n, &k, &one, rows, &n, f, &inc, &one, g.data(), &inc, 1);
}

Eigen::VectorXd symmetric_product(const Eigen::MatrixXd& a, const Eigen::VectorXd& x) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(x.size());
  if (x.size() == 0) return y;
  const int n = blas_int(x.size()), inc = 1;
  const double one = 1, zero = 0;
  dsymv_("U", &n, &one, a.data(), &n, x.data(), &inc, &zero, y.data(), &inc, 1);
  return y;
}

bool cholesky(Eigen::MatrixXd& m, int block) {
  const int n = blas_int(m.rows());
  const double one = 1, minus_one = -1;
  for (int k = 0; k < n; k += block) {
    const int b = std::min(block, n - k), rest = n - k - b;
    double* diagonal = m.data() + k + static_cast<Eigen::Index>(k) * n;
    int info = 0;
    {
      const BlasThreads single(1);  // a small block: threads would only wait on each other
      dpotrf_("U", &b, diagonal, &n, &info, 1);
    }
    if (info != 0) return false;
    if (rest == 0) break;
    double* panel = diagonal + static_cast<Eigen::Index>(b) * n;  // rows k…k+b, columns k+b…
    dtrsm_("L", "U", "T", "N", &b, &rest, &one, diagonal, &n, panel, &n, 1, 1, 1, 1);
    dsyrk_("U", "T", &rest, &b, &minus_one, panel, &n, &one, panel + b, &n, 1, 1);
  }
  return true;
}

bool cholesky_solve(Eigen::MatrixXd& m, Eigen::VectorXd& b) {
  if (b.size() == 0) return true;
  const int n = blas_int(m.rows()), one = 1;
  int info = 0;
  if (!cholesky(m, 256)) return false;
  dpotrs_("U", &n, &one, m.data(), &n, b.data(), &n, &info, 1);
  return info == 0;
}

}  // namespace nfield::solvers::dense
