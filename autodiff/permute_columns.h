// SPDX-License-Identifier: MIT
//
// A module that reorders the columns of its input: out[:, j] = in[:, order[j]], order a
// permutation of 0 … width−1. Linear, so every stream is reordered alike and the adjoint
// puts each column back: in̄[:, order[j]] = out̄[:, j]. With autodiff::OnColumns (which reads
// contiguous columns) it brings columns that one module reads together: a radiance field's
// input [x, d, σ²] becomes [x, σ², d] for an encoding of (x, σ²) (fields/radiance_network.cc).
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "autodiff/module.h"

namespace nfield::autodiff {

template <typename Scalar>
class PermuteColumns final : public Module<Scalar> {
 public:
  explicit PermuteColumns(std::vector<Eigen::Index> order) : order_(std::move(order)) {
    std::vector<Eigen::Index> sorted = order_;
    std::sort(sorted.begin(), sorted.end());
    for (size_t j = 0; j < sorted.size(); ++j)
      if (sorted[j] != static_cast<Eigen::Index>(j))
        throw std::logic_error("PermuteColumns: the order must be a permutation of 0 … width−1");
  }

  std::string name() const override { return "permute columns"; }
  Eigen::Index input_width() const override { return static_cast<Eigen::Index>(order_.size()); }
  Eigen::Index output_width() const override { return input_width(); }

  void forward(const StreamLayout&, const Scalar*, const Streams<Scalar>& in, Streams<Scalar>& out,
               SavedTensors<Scalar>* saved) const override {
    out.resize(in.points, in.count, in.width());
    for (size_t j = 0; j < order_.size(); ++j) out.data.col(static_cast<Eigen::Index>(j)) = in.data.col(order_[j]);
    if (saved) saved->clear();
  }

  void backward(const StreamLayout&, const Scalar*, const Streams<Scalar>& in, const SavedTensors<Scalar>&,
                Streams<Scalar>& out_adjoint, Scalar*, Streams<Scalar>* in_adjoint) const override {
    if (!in_adjoint) return;
    in_adjoint->resize(in.points, in.count, in.width());
    for (size_t j = 0; j < order_.size(); ++j)
      in_adjoint->data.col(order_[j]) = out_adjoint.data.col(static_cast<Eigen::Index>(j));
  }

 private:
  std::vector<Eigen::Index> order_;
};

}  // namespace nfield::autodiff
