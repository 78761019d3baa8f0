// SPDX-License-Identifier: MIT
//
// The dense algebra of the own Levenberg–Marquardt step (solvers/training/levenberg_marquardt.h),
// on the system's BLAS and LAPACK (Debian: OpenBLAS built with OpenMP, libopenblas-openmp-dev;
// any reference BLAS/LAPACK links too, only slower). These are the products that dominate an
// LM iteration on a network: for an m × P Jacobian, JᵀJ costs m·P² multiply-adds (syrk, which
// fills one triangle: half of a general product), the Cholesky factor P³/3 and Jᵀf only m·P.
//
// Layout. The network's Jacobian (autodiff::Sequential::residuals_and_jacobian) is row-major
// m × P; read column-major it is Jᵀ, P × m with leading dimension P. So JᵀJ = (Jᵀ)(Jᵀ)ᵀ is
// syrk with trans = 'N' on those bytes as they are, and Jᵀf is gemv with trans = 'N': no
// copy, no transpose. Symmetric matrices are P × P column-major Eigen matrices of which only
// the upper triangle is read and written.
//
// Threads. OpenBLAS's OpenMP build runs each call on omp_get_max_threads() threads of the
// calling thread (one inside a parallel region). BlasThreads sets that count for a scope, so
// the products use the training's thread count (training.threads) and no more.
#pragma once

#include <Eigen/Core>

namespace nfield::solvers::dense {

// Sets the calling thread's OpenMP thread count (and with it BLAS's) for its lifetime;
// `threads` <= 0 leaves it as it is. Given the order P of the products, one thread below
// kParallelOrder: there the threads' synchronisation costs more than it saves (figures:
// docs/experiments.md).
class BlasThreads {
 public:
  static constexpr Eigen::Index kParallelOrder = 384;
  explicit BlasThreads(int threads, Eigen::Index order = kParallelOrder);
  ~BlasThreads();
  BlasThreads(const BlasThreads&) = delete;
  BlasThreads& operator=(const BlasThreads&) = delete;

 private:
  int saved_;
};

// A += Jᵀ J (upper triangle) for the m rows of J, stored row-major m × P at `rows`
// (dsyrk, beta = 1).
void add_gram(Eigen::MatrixXd& a, const double* rows, Eigen::Index m);
// g += Jᵀ f for the same rows and their m residuals f (dgemv).
void add_transposed_product(Eigen::VectorXd& g, const double* rows, Eigen::Index m,
                            const double* f);
// y = A x with A symmetric, its upper triangle stored (dsymv).
Eigen::VectorXd symmetric_product(const Eigen::MatrixXd& a, const Eigen::VectorXd& x);
// M = UᵀU for symmetric positive definite M (upper triangle, overwritten by U), blocked by
// columns of `block`: each diagonal block by potrf on one thread, then the panel right of it
// by trsm and the trailing matrix by a syrk of rank `block`, on all threads. (OpenBLAS's own
// threaded potrf synchronises its threads so often that it is slower on two threads than on
// one, docs/experiments.md; its syrk and trsm do not.) False when M is not
// positive definite to working precision (a pivot <= 0).
bool cholesky(Eigen::MatrixXd& m, int block = 256);
// Solves M x = b that way (then potrs): M is overwritten by its factor, b by x (undefined
// when false is returned).
bool cholesky_solve(Eigen::MatrixXd& m, Eigen::VectorXd& b);

}  // namespace nfield::solvers::dense
