// SPDX-License-Identifier: MIT
//
// Periodicity between the opposite faces of one space axis a (a `type: periodic` condition,
// solvers/conditions/condition_list.h): the points come in groups of two, p on the lower
// face and p' = p + (upperₐ − lowerₐ) eₐ on the upper one, and per group and tied output c
//
//     r = (u_c(p) − u_c(p'),  ∂ₐu_c(p) − ∂ₐu_c(p'))         (two components per output)
//
// from the value stream and one tangent stream along eₐ. Matching ∂ₐu (rather than ∂u/∂n,
// whose sign flips between the faces) is what makes the periodic extension C¹; the
// derivatives along the face agree once the values do.
#pragma once

#include <memory>
#include <vector>

#include "solvers/core/residual.h"

namespace nfield::solvers {

class PeriodicResidual final : public Residual {
 public:
  // `groups`: offsets 0, 2, 4, …, rows of the points; `outputs`: the channels tied.
  PeriodicResidual(std::vector<Eigen::Index> groups, std::vector<int> outputs)
      : groups_(std::move(groups)), outputs_(std::move(outputs)) {}

  int components() const override { return 2 * static_cast<int>(outputs_.size()); }
  void evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                Eigen::MatrixXd& r) const override;
  void backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const override;

 private:
  std::vector<Eigen::Index> groups_;
  std::vector<int> outputs_;
};

// The loss term's parts: the spec (values and the tangent eₐ) and its points, n pairs on
// `lower` and its opposite face (2n rows, groups of two).
autodiff::StreamSpec periodic_spec(const Domain& domain, int axis);
TermPoints periodic_points(const Domain& domain, const Face& lower, Random& rng, Eigen::Index n);

}  // namespace nfield::solvers
