// SPDX-License-Identifier: MIT
//
// A module maps input streams to output streams (a linear layer, an activation, an
// encoding) and knows its reverse pass. Parameters are not owned by modules: a field keeps
// one flat vector and hands each module a pointer to its slice, so optimizers see one vector
// and can evaluate at any point without copies.
#pragma once

#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "autodiff/streams.h"

namespace nfield::autodiff {

// What a recording forward pass keeps for the reverse pass, besides the module's input.
template <typename Scalar>
using SavedTensors = std::vector<Matrix<Scalar>>;

// Rows of a row-major Jacobian (points × parameters) with any row stride: the destination
// of Module::backward_per_point, a view into Sequential::residuals_and_jacobian's output.
template <typename Scalar>
using JacobianRows =
    Eigen::Map<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>, 0,
               Eigen::OuterStride<>>;

template <typename Scalar>
class Module {
 public:
  virtual ~Module() = default;

  virtual std::string name() const = 0;
  virtual Eigen::Index input_width() const = 0;
  virtual Eigen::Index output_width() const = 0;
  virtual Eigen::Index parameter_count() const { return 0; }

  // Draws this module's initial parameters (its slice) from `rng` and returns true; or
  // returns false and leaves them to the network's owner, as a dense layer does, whose
  // initialization depends on the network around it (fields/field.h).
  virtual bool initialize(Scalar* params, std::mt19937_64& rng) const {
    (void)params;
    (void)rng;
    return false;
  }

  // Throws std::invalid_argument when the module cannot compute `layout`'s streams (a field
  // that gives the value and gradient only, fields/acorn.h). Sequential calls it before each
  // pass, outside its threads, where an exception can still reach the caller.
  virtual void check_layout(const StreamLayout& layout) const { (void)layout; }

  // out = f(in) for all streams. When `saved` is not null, keep there what backward reads.
  virtual void forward(const StreamLayout& layout, const Scalar* params,
                       const Streams<Scalar>& in, Streams<Scalar>& out,
                       SavedTensors<Scalar>* saved) const = 0;

  // From ∂L/∂out: adds ∂L/∂params into `gradient` (this module's slice) and, when
  // `in_adjoint` is not null, writes ∂L/∂in. May overwrite `out_adjoint`.
  virtual void backward(const StreamLayout& layout, const Scalar* params,
                        const Streams<Scalar>& in, const SavedTensors<Scalar>& saved,
                        Streams<Scalar>& out_adjoint, Scalar* gradient,
                        Streams<Scalar>* in_adjoint) const = 0;

  // backward for per-point Jacobians (Sequential::residuals_and_jacobian): instead of adding
  // the parameter gradient summed over points, ASSIGNS point n's own term of that sum to row
  // n of `jacobian` (in.points × parameter_count(), row-major: this module's columns of the
  // output rows, in the order of its parameter slice). With `out_adjoint` seeded per point (the rows of point n holding
  // ∂r(xₙ)/∂out), row n is then ∂r(xₙ)/∂θ. The input adjoint is the same as backward's.
  // Modules without parameters need not override it; those with parameters that do, say
  // so in has_per_point_gradients.
  virtual bool has_per_point_gradients() const { return parameter_count() == 0; }
  virtual void backward_per_point(const StreamLayout& layout, const Scalar* params,
                                  const Streams<Scalar>& in, const SavedTensors<Scalar>& saved,
                                  Streams<Scalar>& out_adjoint, JacobianRows<Scalar> jacobian,
                                  Streams<Scalar>* in_adjoint) const {
    if (parameter_count() > 0)
      throw std::logic_error("module '" + name() + "' has no per-point parameter gradients");
    (void)jacobian;
    backward(layout, params, in, saved, out_adjoint, nullptr, in_adjoint);
  }
};

}  // namespace nfield::autodiff
