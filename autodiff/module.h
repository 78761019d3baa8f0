// SPDX-License-Identifier: MIT
//
// A module maps input streams to output streams (a linear layer, an activation, an
// encoding) and knows its reverse pass. Parameters are not owned by modules: a field keeps
// one flat vector and hands each module a pointer to its slice, so optimizers see one vector
// and can evaluate at any point without copies.
#pragma once

#include <string>
#include <vector>

#include "autodiff/streams.h"

namespace nfield::autodiff {

// What a recording forward pass keeps for the reverse pass, besides the module's input.
template <typename Scalar>
using SavedTensors = std::vector<Matrix<Scalar>>;

template <typename Scalar>
class Module {
 public:
  virtual ~Module() = default;

  virtual std::string name() const = 0;
  virtual Eigen::Index input_width() const = 0;
  virtual Eigen::Index output_width() const = 0;
  virtual Eigen::Index parameter_count() const { return 0; }

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
};

}  // namespace nfield::autodiff
