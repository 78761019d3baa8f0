// SPDX-License-Identifier: MIT
//
// A module applied to some columns of its input, the others passed through unchanged:
//
//   out = [ in[:, 0:b) | inner(in[:, b:b+w)) | in[:, b+w:) ]      w = inner.input_width()
//
// This is how a field chain becomes a small graph without a graph type: an input that
// enters a later layer (a radiance field's view direction) is carried past the layers before
// it in extra columns, and a layer that makes two heads (density and a feature vector) is
// one Dense whose outputs are both. The identity on the carried columns holds in every
// stream, so their adjoints pass back unchanged. Costs two copies of the inner module's
// input and output per pass, small beside a matrix product over the same streams.
#pragma once

#include <memory>

#include "autodiff/module.h"

namespace nfield::autodiff {

template <typename Scalar>
class OnColumns final : public Module<Scalar> {
 public:
  // inner reads columns [begin, begin + inner.input_width()) of an input `width` wide.
  OnColumns(std::unique_ptr<Module<Scalar>> inner, Eigen::Index begin, Eigen::Index width);

  const Module<Scalar>& inner() const { return *inner_; }
  Module<Scalar>& inner() { return *inner_; }
  Eigen::Index begin() const { return begin_; }

  std::string name() const override { return inner_->name() + " (on columns)"; }
  Eigen::Index input_width() const override { return width_; }
  Eigen::Index output_width() const override {
    return width_ - inner_->input_width() + inner_->output_width();
  }
  Eigen::Index parameter_count() const override { return inner_->parameter_count(); }

  void forward(const StreamLayout& layout, const Scalar* params, const Streams<Scalar>& in,
               Streams<Scalar>& out, SavedTensors<Scalar>* saved) const override;
  void backward(const StreamLayout& layout, const Scalar* params, const Streams<Scalar>& in,
                const SavedTensors<Scalar>& saved, Streams<Scalar>& out_adjoint,
                Scalar* gradient, Streams<Scalar>* in_adjoint) const override;
  bool has_per_point_gradients() const override { return inner_->has_per_point_gradients(); }
  void backward_per_point(const StreamLayout& layout, const Scalar* params,
                          const Streams<Scalar>& in, const SavedTensors<Scalar>& saved,
                          Streams<Scalar>& out_adjoint, JacobianRows<Scalar> jacobian,
                          Streams<Scalar>* in_adjoint) const override;

 private:
  // The inner module's input columns, and out_adjoint's columns of its output.
  void slice_input(const Streams<Scalar>& in, Streams<Scalar>& inner_in) const;
  void slice_output_adjoint(const Streams<Scalar>& out_adjoint, Streams<Scalar>& inner_adjoint) const;
  // ∂L/∂in from the inner module's input adjoint and the carried columns' adjoints.
  void join_input_adjoint(const Streams<Scalar>& out_adjoint, const Streams<Scalar>& inner_in_adjoint,
                          Streams<Scalar>& in_adjoint) const;

  std::unique_ptr<Module<Scalar>> inner_;
  Eigen::Index begin_, width_;
};

}  // namespace nfield::autodiff
