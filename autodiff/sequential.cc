// SPDX-License-Identifier: MIT
#include "autodiff/sequential.h"

#include <malloc.h>
#include <omp.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace nfield::autodiff {

template <typename Scalar>
struct Sequential<Scalar>::Workspace {
  std::vector<Streams<Scalar>> activations;  // input of module l, then the output
  std::vector<SavedTensors<Scalar>> saved;
  Streams<Scalar> adjoint, next_adjoint;
  Vector<Scalar> gradient;
  double loss = 0;
  Matrix<Scalar> r, r_bar;  // residuals_and_jacobian: one block's r and r̄
};

namespace {
// Eigen allocates the packing buffers of every matrix product (0.1–2 MB here) on the heap,
// and glibc's defaults hand such blocks back to the kernel when they are freed (mmap above
// 128 KiB, heap trimming above 128 KiB), so every product page-faulted its buffers anew: a
// training process ran 1.7–2× slower per step (laplacian, batch 4096: 140 → 80 ms) until
// something large had moved glibc's adaptive thresholds. Keeping freed blocks below 32 MiB
// in the heap costs at most the trim threshold in retained memory.
void keep_freed_blocks_in_the_heap() {
  static std::once_flag once;
  std::call_once(once, [] {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 128 << 20);
  });
}
}  // namespace

template <typename Scalar>
Sequential<Scalar>::Sequential(SequentialOptions options) {
  keep_freed_blocks_in_the_heap();
  set_options(options);
}
template <typename Scalar>
Sequential<Scalar>::Sequential(Sequential&&) noexcept = default;
template <typename Scalar>
Sequential<Scalar>& Sequential<Scalar>::operator=(Sequential&&) noexcept = default;
template <typename Scalar>
Sequential<Scalar>::~Sequential() = default;

template <typename Scalar>
void Sequential<Scalar>::set_options(const SequentialOptions& options) {
  if (options.block_points < 1)
    throw std::invalid_argument("SequentialOptions.block_points = " +
                                std::to_string(options.block_points) + ": must be >= 1");
  if (options.threads < 0)
    throw std::invalid_argument("SequentialOptions.threads = " + std::to_string(options.threads) +
                                ": must be >= 0 (0 = all)");
  options_ = options;
}

template <typename Scalar>
void Sequential<Scalar>::add(std::unique_ptr<Module<Scalar>> module) {
  if (!modules_.empty() && module->input_width() != output_width())
    throw std::invalid_argument("Sequential::add: module '" + module->name() + "' takes width " +
                                std::to_string(module->input_width()) + ", previous output is " +
                                std::to_string(output_width()));
  offsets_.push_back(parameter_count_);
  parameter_count_ += module->parameter_count();
  modules_.push_back(std::move(module));
  workspaces_.clear();
}

template <typename Scalar>
Eigen::Index Sequential<Scalar>::input_width() const {
  return modules_.empty() ? 0 : modules_.front()->input_width();
}
template <typename Scalar>
Eigen::Index Sequential<Scalar>::output_width() const {
  return modules_.empty() ? 0 : modules_.back()->output_width();
}

template <typename Scalar>
typename Sequential<Scalar>::Workspace& Sequential<Scalar>::workspace(int thread) const {
  return *workspaces_[thread];
}

template <typename Scalar>
void Sequential<Scalar>::prepare_workspaces(int threads) const {
  if (static_cast<int>(workspaces_.size()) < threads) workspaces_.resize(threads);
  for (auto& w : workspaces_) {
    if (!w) w = std::make_unique<Workspace>();
    w->activations.resize(modules_.size() + 1);
    w->saved.resize(modules_.size());
  }
}

template <typename Scalar>
void Sequential<Scalar>::forward_block(const Scalar* params, const StreamLayout& layout,
                                       const Eigen::Ref<const Matrix<Scalar>>& x,
                                       Eigen::Index first, Eigen::Index rows, Workspace& ws,
                                       bool record) const {
  seed_input_streams<Scalar>(layout, x.middleRows(first, rows), ws.activations[0]);
  for (size_t l = 0; l < modules_.size(); ++l)
    modules_[l]->forward(layout, params + offsets_[l], ws.activations[l], ws.activations[l + 1],
                         record ? &ws.saved[l] : nullptr);
}

namespace {
int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

// The blocks already split the work over the threads: each block's matrix products must
// run on its own thread. Eigen would otherwise open a nested team of its own inside a team
// of one thread (threads = 1), which costs 3–4× per step.
class SingleThreadedEigen {
 public:
  SingleThreadedEigen() : previous_(Eigen::nbThreads()) { Eigen::setNbThreads(1); }
  ~SingleThreadedEigen() { Eigen::setNbThreads(previous_); }

 private:
  int previous_;
};
}  // namespace

template <typename Scalar>
void Sequential<Scalar>::evaluate(const Scalar* params, const StreamLayout& layout,
                                  const Eigen::Ref<const Matrix<Scalar>>& x,
                                  Streams<Scalar>& out) const {
  if (modules_.empty()) throw std::logic_error("Sequential::evaluate: no modules");
  const Eigen::Index n = x.rows(), block = options_.block_points;
  const Eigen::Index blocks = (n + block - 1) / block;
  const int threads = thread_count(options_.threads);
  out.resize(n, layout.count(), output_width());
  const SingleThreadedEigen single_threaded_products;
  prepare_workspaces(threads);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (Eigen::Index b = 0; b < blocks; ++b) {
    Workspace& ws = workspace(omp_get_thread_num());
    const Eigen::Index first = b * block, rows = std::min(block, n - first);
    // Two activations alternate: no tape is kept.
    seed_input_streams<Scalar>(layout, x.middleRows(first, rows), ws.activations[0]);
    for (size_t l = 0; l < modules_.size(); ++l) {
      modules_[l]->forward(layout, params + offsets_[l], ws.activations[0], ws.activations[1],
                           nullptr);
      std::swap(ws.activations[0], ws.activations[1]);
    }
    for (int s = 0; s < layout.count(); ++s)
      out.stream(s).middleRows(first, rows) = ws.activations[0].stream(s);
  }
}

template <typename Scalar>
double Sequential<Scalar>::value_and_gradient(const Scalar* params, const StreamLayout& layout,
                                              const Eigen::Ref<const Matrix<Scalar>>& x,
                                              const StreamLoss<Scalar>& loss,
                                              Scalar* gradient) const {
  if (modules_.empty()) throw std::logic_error("Sequential::value_and_gradient: no modules");
  const Eigen::Index n = x.rows(), block = options_.block_points;
  const Eigen::Index blocks = (n + block - 1) / block;
  const int threads = thread_count(options_.threads);
  const size_t depth = modules_.size();
  const SingleThreadedEigen single_threaded_products;
  prepare_workspaces(threads);
  for (auto& w : workspaces_) {
    w->gradient.setZero(parameter_count_);
    w->loss = 0;
  }
#pragma omp parallel num_threads(threads)
  {
    Workspace& ws = workspace(omp_get_thread_num());
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index first = b * block, rows = std::min(block, n - first);
      forward_block(params, layout, x, first, rows, ws, true);
      const Streams<Scalar>& out = ws.activations[depth];
      ws.adjoint.resize(out.points, out.count, out.width());
      ws.adjoint.data.setZero();
      ws.loss += loss.evaluate(first, layout, out, ws.adjoint);
      for (size_t l = depth; l-- > 0;) {
        modules_[l]->backward(layout, params + offsets_[l], ws.activations[l], ws.saved[l],
                              ws.adjoint, ws.gradient.data() + offsets_[l],
                              l > 0 ? &ws.next_adjoint : nullptr);
        if (l > 0) std::swap(ws.adjoint, ws.next_adjoint);
      }
    }
  }
  double total = 0;
  Eigen::Map<Vector<Scalar>> g(gradient, parameter_count_);
  for (int t = 0; t < threads; ++t) {
    g += workspaces_[t]->gradient;
    total += workspaces_[t]->loss;
  }
  return total;
}

template <typename Scalar>
void Sequential<Scalar>::residuals_and_jacobian(const Scalar* params, const StreamLayout& layout,
                                                const Eigen::Ref<const Matrix<Scalar>>& x,
                                                const StreamResidual<Scalar>& residual,
                                                Scalar* residuals, Scalar* jacobian) const {
  if (modules_.empty()) throw std::logic_error("Sequential::residuals_and_jacobian: no modules");
  const Eigen::Index n = x.rows(), block = options_.block_points, p = parameter_count_;
  const Eigen::Index blocks = (n + block - 1) / block;
  const int threads = thread_count(options_.threads);
  const int c_count = residual.components();
  const size_t depth = modules_.size();
  const bool record = jacobian != nullptr;
  if (record)  // before the parallel region: an exception may not leave it
    for (const auto& m : modules_)
      if (!m->has_per_point_gradients())
        throw std::logic_error("Sequential::residuals_and_jacobian: module '" + m->name() +
                               "' has no per-point parameter gradients");
  const SingleThreadedEigen single_threaded_products;
  prepare_workspaces(threads);
#pragma omp parallel num_threads(threads)
  {
    Workspace& ws = workspace(omp_get_thread_num());
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index first = b * block, rows = std::min(block, n - first);
      forward_block(params, layout, x, first, rows, ws, record);
      const Streams<Scalar>& out = ws.activations[depth];
      residual.evaluate(first, layout, out, ws.r);
      // r is points × C column-major; the output is point-major, i.e. rᵀ column-major.
      Eigen::Map<Matrix<Scalar>>(residuals + first * c_count, c_count, rows) = ws.r.transpose();
      if (!record) continue;
      for (int c = 0; c < c_count; ++c) {
        ws.r_bar.setZero(rows, c_count);
        ws.r_bar.col(c).setOnes();
        ws.adjoint.resize(out.points, out.count, out.width());
        ws.adjoint.data.setZero();
        residual.backward(first, layout, out, ws.r_bar, ws.adjoint);
        // This block's rows n·C + c: row stride C·P in the row-major output.
        Scalar* rows_c = jacobian + (first * c_count + c) * p;
        for (size_t l = depth; l-- > 0;) {
          modules_[l]->backward_per_point(
              layout, params + offsets_[l], ws.activations[l], ws.saved[l], ws.adjoint,
              JacobianRows<Scalar>(rows_c + offsets_[l], rows, modules_[l]->parameter_count(),
                                   Eigen::OuterStride<>(c_count * p)),
              l > 0 ? &ws.next_adjoint : nullptr);
          if (l > 0) std::swap(ws.adjoint, ws.next_adjoint);
        }
      }
    }
  }
}

template class Sequential<float>;
template class Sequential<double>;

}  // namespace nfield::autodiff
