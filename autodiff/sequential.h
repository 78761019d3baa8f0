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
// Matrix products inside a block run on the block's thread: each thread of a pass sets its
// own OpenMP thread count (a per-task setting) to one, so Eigen opens no nested team, and
// nothing process-wide is changed (two Sequentials may run on two threads at once). A
// program that calls Eigen::setNbThreads(n > 1) itself overrides this. Programs that train
// should also keep freed blocks in the heap (apps/allocator_tuning.h): the library does not
// change the allocator by itself.
#pragma once

#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "autodiff/module.h"
#include "autodiff/stream_loss.h"
#include "autodiff/stream_residual.h"

namespace nfield::autodiff {

// What a pass runs over besides the parameters: the points, and what may differ per point.
//
//   points    N × input_dim.
//   tangents  optional per-point tangent directions (autodiff/streams.h, PointTangents):
//             row n holds point n's T directions; null: the layout's shared ones.
//   groups    optional offsets 0 = g₀ ≤ g₁ ≤ … ≤ g_G = N: group k is points [g_k, g_{k+1}),
//             evaluated together by one loss (a ray's samples, the two ends of an interval).
//             Blocks are then cut between groups only, so a StreamLoss sees whole groups:
//             a block holds the groups that start in it, packed up to block_points points (a
//             larger group gets a block of its own). Empty: every point is its own group.
template <typename Scalar>
struct Batch {
  Eigen::Ref<const Matrix<Scalar>> points;
  const Matrix<Scalar>* tangents = nullptr;
  std::span<const Eigen::Index> groups = {};
};

// The groups a block of a pass over `groups` holds: [k₀, k₁) are those whose first point lies
// in [first, first + rows), and in the last block also the empty groups at the end.
std::pair<size_t, size_t> groups_in_block(std::span<const Eigen::Index> groups, Eigen::Index first,
                                          Eigen::Index rows);

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
  // Hands the modules over and leaves the chain empty (to rebuild them into another chain).
  std::vector<std::unique_ptr<Module<Scalar>>> release_modules();
  Eigen::Index input_width() const;
  Eigen::Index output_width() const;
  Eigen::Index parameter_count() const { return parameter_count_; }
  Eigen::Index parameter_offset(size_t module) const { return offsets_[module]; }
  const SequentialOptions& options() const { return options_; }
  void set_options(const SequentialOptions& options);

  // Output streams at points x (N × input_dim).
  void evaluate(const Scalar* params, const StreamLayout& layout,
                const Eigen::Ref<const Matrix<Scalar>>& x, Streams<Scalar>& out) const {
    evaluate(params, layout, Batch<Scalar>{x}, out);
  }
  void evaluate(const Scalar* params, const StreamLayout& layout, const Batch<Scalar>& batch,
                Streams<Scalar>& out) const;

  // Σ over blocks of `loss`; adds its parameter gradient into `gradient` (length
  // parameter_count(); not cleared here). Returns the loss sum.
  double value_and_gradient(const Scalar* params, const StreamLayout& layout,
                            const Eigen::Ref<const Matrix<Scalar>>& x,
                            const StreamLoss<Scalar>& loss, Scalar* gradient) const {
    return value_and_gradient(params, layout, Batch<Scalar>{x}, loss, gradient);
  }
  double value_and_gradient(const Scalar* params, const StreamLayout& layout,
                            const Batch<Scalar>& batch, const StreamLoss<Scalar>& loss,
                            Scalar* gradient) const;

  // The first point of each block and N at the end, for N points and optional group
  // offsets (see Batch). Throws std::invalid_argument for offsets that are not a partition.
  std::vector<Eigen::Index> block_starts(Eigen::Index n, std::span<const Eigen::Index> groups) const;

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
                              Scalar* jacobian) const {
    residuals_and_jacobian(params, layout, Batch<Scalar>{x}, residual, residuals, jacobian);
  }
  // The same with per-point tangents; residuals are per point, so groups are not used.
  void residuals_and_jacobian(const Scalar* params, const StreamLayout& layout,
                              const Batch<Scalar>& batch, const StreamResidual<Scalar>& residual,
                              Scalar* residuals, Scalar* jacobian) const;

 private:
  struct Workspace;
  Workspace& workspace(int thread) const;
  // Workspaces for `threads` threads, each with room for a recording pass.
  void prepare_workspaces(int threads) const;
  // Forward pass of points [first, first + rows) of x into ws.activations (input, then
  // each module's output), keeping each module's tape in ws.saved when `record`.
  void forward_block(const Scalar* params, const StreamLayout& layout, const Batch<Scalar>& batch,
                     Eigen::Index first, Eigen::Index rows, Workspace& ws, bool record) const;

  SequentialOptions options_;
  std::vector<std::unique_ptr<Module<Scalar>>> modules_;
  std::vector<Eigen::Index> offsets_;
  Eigen::Index parameter_count_ = 0;
  mutable std::vector<std::unique_ptr<Workspace>> workspaces_;
};

}  // namespace nfield::autodiff
