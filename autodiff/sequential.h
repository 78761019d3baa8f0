// SPDX-License-Identifier: MIT
//
// A chain of modules evaluated over a batch of points, forward and reverse.
//
// The batch is cut into blocks of `block_points` points; the threads (OpenMP, static
// schedule) each take contiguous blocks and run forward, loss and reverse pass on one block
// at a time, keeping only that block's tape. Memory therefore grows with the block size and
// the thread count, not with the batch, and each layer's streams still go through one
// matrix product per block. Gradients are summed per thread and then in thread order, so a
// run is bit-for-bit repeatable for a given thread count.
//
// Not thread-safe: one call at a time per Sequential (it reuses its per-thread workspaces).
//
// The first Sequential of a process raises glibc's mmap and trim thresholds (mallopt) to
// 32 and 128 MiB: Eigen allocates its product buffers per call, and with the defaults each
// call page-faulted them anew (up to 2× per step).
#pragma once

#include <memory>
#include <vector>

#include "autodiff/module.h"
#include "autodiff/stream_loss.h"
#include "autodiff/stream_residual.h"

namespace nfield::autodiff {

struct SequentialOptions {
  Eigen::Index block_points = 128;  // points per block; > 0
  int threads = 0;                  // 0: omp_get_max_threads()
};

template <typename Scalar>
class Sequential {
 public:
  explicit Sequential(SequentialOptions options = {});
  Sequential(Sequential&&) noexcept;
  Sequential& operator=(Sequential&&) noexcept;
  ~Sequential();

  // Appends a module; its input width must match the last output width.
  void add(std::unique_ptr<Module<Scalar>> module);

  const std::vector<std::unique_ptr<Module<Scalar>>>& modules() const { return modules_; }
  Eigen::Index input_width() const;
  Eigen::Index output_width() const;
  Eigen::Index parameter_count() const { return parameter_count_; }
  Eigen::Index parameter_offset(size_t module) const { return offsets_[module]; }
  const SequentialOptions& options() const { return options_; }
  void set_options(const SequentialOptions& options);

  // Output streams at points x (N × input_dim).
  void evaluate(const Scalar* params, const StreamLayout& layout,
                const Eigen::Ref<const Matrix<Scalar>>& x, Streams<Scalar>& out) const;

  // Σ over points of `loss`; adds its parameter gradient into `gradient` (length
  // parameter_count(); not cleared here). Returns the loss sum.
  double value_and_gradient(const Scalar* params, const StreamLayout& layout,
                            const Eigen::Ref<const Matrix<Scalar>>& x,
                            const StreamLoss<Scalar>& loss, Scalar* gradient) const;

  // Per-point residuals r(xₙ) ∈ R^C (C = residual.components()) and, unless `jacobian` is
  // null, their Jacobian J = ∂r/∂θ, in Ceres' layout for one residual block:
  //
  //   residuals  N·C values, point-major: r_c(xₙ) at n·C + c
  //   jacobian   (N·C) × parameter_count(), row-major: row n·C + c is ∂r_c(xₙ)/∂θ
  //
  // Jᵀr is then half the gradient of Σₙ ‖r(xₙ)‖². Points are independent, so one reverse
  // pass per component c yields the rows of every point at once: seed the output adjoint
  // with residual.backward for r̄ = e_c at all points (point n's rows then hold
  // ∂r_c(xₙ)/∂outₙ), reverse through the modules, and let each module with parameters
  // write point n's gradient term into row n (Module::backward_per_point) instead of
  // summing over points. Per block this costs one forward pass, C reverse passes and
  // writing the block's rows; blocks run in parallel as in value_and_gradient, each
  // writing its own rows, so the result does not depend on the thread count.
  void residuals_and_jacobian(const Scalar* params, const StreamLayout& layout,
                              const Eigen::Ref<const Matrix<Scalar>>& x,
                              const StreamResidual<Scalar>& residual, Scalar* residuals,
                              Scalar* jacobian) const;

 private:
  struct Workspace;
  Workspace& workspace(int thread) const;
  // Workspaces for `threads` threads, each with room for a recording pass.
  void prepare_workspaces(int threads) const;
  // Forward pass of points [first, first + rows) of x into ws.activations (input, then
  // each module's output), keeping each module's tape in ws.saved when `record`.
  void forward_block(const Scalar* params, const StreamLayout& layout,
                     const Eigen::Ref<const Matrix<Scalar>>& x, Eigen::Index first,
                     Eigen::Index rows, Workspace& ws, bool record) const;

  SequentialOptions options_;
  std::vector<std::unique_ptr<Module<Scalar>>> modules_;
  std::vector<Eigen::Index> offsets_;
  Eigen::Index parameter_count_ = 0;
  mutable std::vector<std::unique_ptr<Workspace>> workspaces_;
};

}  // namespace nfield::autodiff
