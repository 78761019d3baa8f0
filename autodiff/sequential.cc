// SPDX-License-Identifier: MIT
#include "autodiff/sequential.h"

#include <omp.h>

#include <algorithm>
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


template <typename Scalar>
Sequential<Scalar>::Sequential(SequentialOptions options) {
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
std::vector<std::unique_ptr<Module<Scalar>>> Sequential<Scalar>::release_modules() {
  std::vector<std::unique_ptr<Module<Scalar>>> modules = std::move(modules_);
  modules_.clear();
  offsets_.clear();
  parameter_count_ = 0;
  workspaces_.clear();
  return modules;
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
                                       const Batch<Scalar>& batch, Eigen::Index first,
                                       Eigen::Index rows, Workspace& ws, bool record) const {
  if (batch.tangents) {
    const Eigen::Ref<const Matrix<Scalar>> tangents = batch.tangents->middleRows(first, rows);
    seed_input_streams<Scalar>(layout, batch.points.middleRows(first, rows), ws.activations[0],
                               &tangents);
  } else {
    seed_input_streams<Scalar>(layout, batch.points.middleRows(first, rows), ws.activations[0]);
  }
  for (size_t l = 0; l < modules_.size(); ++l)
    modules_[l]->forward(layout, params + offsets_[l], ws.activations[l], ws.activations[l + 1],
                         record ? &ws.saved[l] : nullptr);
}

template <typename Scalar>
std::vector<Eigen::Index> Sequential<Scalar>::block_starts(
    Eigen::Index n, std::span<const Eigen::Index> groups) const {
  const Eigen::Index block = options_.block_points;
  std::vector<Eigen::Index> starts;
  if (groups.empty()) {
    for (Eigen::Index first = 0; first < n; first += block) starts.push_back(first);
    starts.push_back(n);
    return starts;
  }
  if (groups.front() != 0 || groups.back() != n)
    throw std::invalid_argument("Batch.groups: offsets must run from 0 to the point count " +
                                std::to_string(n) + ", got " + std::to_string(groups.front()) +
                                " … " + std::to_string(groups.back()));
  for (size_t k = 1; k < groups.size(); ++k)
    if (groups[k] < groups[k - 1])
      throw std::invalid_argument("Batch.groups: offsets must not decrease (offset " +
                                  std::to_string(k) + " is " + std::to_string(groups[k]) +
                                  ", before it " + std::to_string(groups[k - 1]) + ")");
  starts.push_back(0);
  for (size_t k = 1; k + 1 < groups.size(); ++k)
    // Cut before group k when it would make the current block larger than a block.
    // (Never at N: empty groups at the end stay with the block that ends there.)
    if (groups[k + 1] - starts.back() > block && groups[k] > starts.back() && groups[k] < n)
      starts.push_back(groups[k]);
  starts.push_back(n);
  return starts;
}

namespace {
// Shapes are checked before a parallel region: an exception may not leave one.
template <typename Scalar>
void check_batch(const StreamLayout& layout, const Batch<Scalar>& batch, Eigen::Index input_width) {
  const int d = layout.input_dim();
  if (batch.points.cols() != d || (input_width > 0 && d != input_width))
    throw std::invalid_argument("Sequential: points have " + std::to_string(batch.points.cols()) +
                                " columns, the stream spec expects " + std::to_string(d) +
                                " and the network " + std::to_string(input_width));
  if (batch.tangents && (batch.tangents->rows() != batch.points.rows() ||
                         batch.tangents->cols() != d * layout.tangents()))
    throw std::invalid_argument("Sequential: per-point tangents are " +
                                std::to_string(batch.tangents->rows()) + " x " +
                                std::to_string(batch.tangents->cols()) + ", expected " +
                                std::to_string(batch.points.rows()) + " x " +
                                std::to_string(d * layout.tangents()) +
                                " (points x input_dim * tangents)");
}

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

// The blocks already split the work over the threads: each block's matrix products must
// run on its own thread. Eigen would otherwise open a nested team inside a team of one
// thread (threads = 1), which slows a step several times over (docs/experiments.md). The thread count set here belongs to the
// calling thread's task inside the parallel region (OpenMP's nthreads-var is a per-task
// setting), so nothing outside the region changes and concurrent passes do not race.
void single_threaded_products_in_this_task() { omp_set_num_threads(1); }
}  // namespace

template <typename Scalar>
void Sequential<Scalar>::evaluate(const Scalar* params, const StreamLayout& layout,
                                  const Batch<Scalar>& batch, Streams<Scalar>& out) const {
  if (modules_.empty()) throw std::logic_error("Sequential::evaluate: no modules");
  check_batch(layout, batch, input_width());
  for (const auto& m : modules_) m->check_layout(layout);
  const Eigen::Index n = batch.points.rows();
  const std::vector<Eigen::Index> starts = block_starts(n, batch.groups);
  const auto blocks = static_cast<Eigen::Index>(starts.size()) - 1;
  const int threads = thread_count(options_.threads);
  out.resize(n, layout.count(), output_width());
  prepare_workspaces(threads);
#pragma omp parallel num_threads(threads)
  {
    single_threaded_products_in_this_task();
    Workspace& ws = workspace(omp_get_thread_num());
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index first = starts[b], rows = starts[b + 1] - first;
      if (rows == 0) continue;
      forward_block(params, layout, batch, first, rows, ws, false);
      const Streams<Scalar>& result = ws.activations[modules_.size()];
      for (int s = 0; s < layout.count(); ++s)
        out.stream(s).middleRows(first, rows) = result.stream(s);
    }
  }
}

template <typename Scalar>
double Sequential<Scalar>::value_and_gradient(const Scalar* params, const StreamLayout& layout,
                                              const Batch<Scalar>& batch,
                                              const StreamLoss<Scalar>& loss,
                                              Scalar* gradient) const {
  if (modules_.empty()) throw std::logic_error("Sequential::value_and_gradient: no modules");
  check_batch(layout, batch, input_width());
  for (const auto& m : modules_) m->check_layout(layout);
  const std::vector<Eigen::Index> starts = block_starts(batch.points.rows(), batch.groups);
  const auto blocks = static_cast<Eigen::Index>(starts.size()) - 1;
  const int threads = thread_count(options_.threads);
  const size_t depth = modules_.size();
  prepare_workspaces(threads);
  for (auto& w : workspaces_) {
    w->gradient.setZero(parameter_count_);
    w->loss = 0;
  }
#pragma omp parallel num_threads(threads)
  {
    single_threaded_products_in_this_task();
    Workspace& ws = workspace(omp_get_thread_num());
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index first = starts[b], rows = starts[b + 1] - first;
      forward_block(params, layout, batch, first, rows, ws, true);
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
                                                const Batch<Scalar>& batch,
                                                const StreamResidual<Scalar>& residual,
                                                Scalar* residuals, Scalar* jacobian) const {
  if (modules_.empty()) throw std::logic_error("Sequential::residuals_and_jacobian: no modules");
  check_batch(layout, batch, input_width());
  for (const auto& m : modules_) m->check_layout(layout);
  const Eigen::Index n = batch.points.rows(), block = options_.block_points, p = parameter_count_;
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
  prepare_workspaces(threads);
#pragma omp parallel num_threads(threads)
  {
    single_threaded_products_in_this_task();
    Workspace& ws = workspace(omp_get_thread_num());
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      const Eigen::Index first = b * block, rows = std::min(block, n - first);
      forward_block(params, layout, batch, first, rows, ws, record);
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

std::pair<size_t, size_t> groups_in_block(std::span<const Eigen::Index> groups, Eigen::Index first,
                                          Eigen::Index rows) {
  const Eigen::Index n = groups.empty() ? 0 : groups.back();
  const auto begin = std::lower_bound(groups.begin(), groups.end() - 1, first);
  const auto end = first + rows == n ? groups.end() - 1
                                     : std::lower_bound(begin, groups.end() - 1, first + rows);
  return {static_cast<size_t>(begin - groups.begin()), static_cast<size_t>(end - groups.begin())};
}

template class Sequential<float>;
template class Sequential<double>;

}  // namespace nfield::autodiff
