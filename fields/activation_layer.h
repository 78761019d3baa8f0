// SPDX-License-Identifier: MIT
//
// A module applying an elementwise activation to every unit of every stream. A recording
// forward pass keeps the derivative tables σ⁽⁰⁾ … σ⁽ʳ⁺¹⁾ (r = the layout's forward order),
// so the reverse pass evaluates no transcendental function again.
#pragma once

#include <memory>

#include "autodiff/module.h"
#include "fields/activations.h"

namespace nfield::fields {

template <typename Scalar>
class ActivationLayer final : public autodiff::Module<Scalar> {
 public:
  ActivationLayer(ActivationSpec spec, Eigen::Index width)
      : spec_(std::move(spec)), width_(width), function_(make_activation<Scalar>(spec_)) {}

  std::string name() const override { return spec_.name; }
  const ActivationSpec& spec() const { return spec_; }
  Eigen::Index input_width() const override { return width_; }
  Eigen::Index output_width() const override { return width_; }

  void forward(const autodiff::StreamLayout& layout, const Scalar*,
               const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
               autodiff::SavedTensors<Scalar>* saved) const override {
    const int order = layout.forward_order();
    if (saved) {
      function_->derivatives(in.values(), order + 1, *saved);
      autodiff::elementwise_forward(layout, *saved, in, out);
    } else {
      thread_local std::vector<autodiff::Matrix<Scalar>> tables;
      function_->derivatives(in.values(), order, tables);
      autodiff::elementwise_forward(layout, tables, in, out);
    }
  }

  void backward(const autodiff::StreamLayout& layout, const Scalar*,
                const autodiff::Streams<Scalar>& in, const autodiff::SavedTensors<Scalar>& saved,
                autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                autodiff::Streams<Scalar>* in_adjoint) const override {
    if (in_adjoint) autodiff::elementwise_backward(layout, saved, in, out_adjoint, *in_adjoint);
  }

 private:
  ActivationSpec spec_;
  Eigen::Index width_;
  std::unique_ptr<autodiff::ElementwiseFunction<Scalar>> function_;
};

}  // namespace nfield::fields
