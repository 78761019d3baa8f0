// SPDX-License-Identifier: MIT
#include "autodiff/on_columns.h"

#include <stdexcept>
#include <string>

namespace nfield::autodiff {
namespace {
// Per-thread scratch: a pass runs one module at a time on each thread.
template <typename Scalar>
struct Scratch {
  Streams<Scalar> in, out, out_adjoint, in_adjoint;
};
template <typename Scalar>
Scratch<Scalar>& scratch() {
  thread_local Scratch<Scalar> s;
  return s;
}
}  // namespace

template <typename Scalar>
OnColumns<Scalar>::OnColumns(std::unique_ptr<Module<Scalar>> inner, Eigen::Index begin,
                             Eigen::Index width)
    : inner_(std::move(inner)), begin_(begin), width_(width) {
  if (!inner_) throw std::invalid_argument("OnColumns: no inner module");
  // One per-thread scratch serves all OnColumns; a nested one would overwrite its caller's.
  // (Nesting is never needed: columns of columns are columns of the outer input.)
  if (dynamic_cast<const OnColumns*>(inner_.get()))
    throw std::invalid_argument("OnColumns: the inner module is itself an OnColumns; give the outer "
                                "one the combined column range instead");
  if (begin < 0 || begin + inner_->input_width() > width)
    throw std::invalid_argument("OnColumns: module '" + inner_->name() + "' reads columns [" +
                                std::to_string(begin) + ", " +
                                std::to_string(begin + inner_->input_width()) +
                                ") of an input " + std::to_string(width) + " wide");
}

template <typename Scalar>
void OnColumns<Scalar>::slice_input(const Streams<Scalar>& in, Streams<Scalar>& inner_in) const {
  inner_in.resize(in.points, in.count, inner_->input_width());
  inner_in.data = in.data.middleCols(begin_, inner_->input_width());
}

template <typename Scalar>
void OnColumns<Scalar>::slice_output_adjoint(const Streams<Scalar>& out_adjoint,
                                             Streams<Scalar>& inner_adjoint) const {
  inner_adjoint.resize(out_adjoint.points, out_adjoint.count, inner_->output_width());
  inner_adjoint.data = out_adjoint.data.middleCols(begin_, inner_->output_width());
}

template <typename Scalar>
void OnColumns<Scalar>::join_input_adjoint(const Streams<Scalar>& out_adjoint,
                                           const Streams<Scalar>& inner_in_adjoint,
                                           Streams<Scalar>& in_adjoint) const {
  const Eigen::Index after = width_ - begin_ - inner_->input_width();
  in_adjoint.resize(out_adjoint.points, out_adjoint.count, width_);
  in_adjoint.data.leftCols(begin_) = out_adjoint.data.leftCols(begin_);
  in_adjoint.data.middleCols(begin_, inner_->input_width()) = inner_in_adjoint.data;
  in_adjoint.data.rightCols(after) = out_adjoint.data.rightCols(after);
}

template <typename Scalar>
void OnColumns<Scalar>::forward(const StreamLayout& layout, const Scalar* params,
                                const Streams<Scalar>& in, Streams<Scalar>& out,
                                SavedTensors<Scalar>* saved) const {
  Scratch<Scalar>& s = scratch<Scalar>();
  slice_input(in, s.in);
  inner_->forward(layout, params, s.in, s.out, saved);
  const Eigen::Index after = width_ - begin_ - inner_->input_width();
  out.resize(in.points, in.count, output_width());
  out.data.leftCols(begin_) = in.data.leftCols(begin_);
  out.data.middleCols(begin_, inner_->output_width()) = s.out.data;
  out.data.rightCols(after) = in.data.rightCols(after);
}

template <typename Scalar>
void OnColumns<Scalar>::backward(const StreamLayout& layout, const Scalar* params,
                                 const Streams<Scalar>& in, const SavedTensors<Scalar>& saved,
                                 Streams<Scalar>& out_adjoint, Scalar* gradient,
                                 Streams<Scalar>* in_adjoint) const {
  Scratch<Scalar>& s = scratch<Scalar>();
  slice_input(in, s.in);
  slice_output_adjoint(out_adjoint, s.out_adjoint);
  inner_->backward(layout, params, s.in, saved, s.out_adjoint, gradient,
                   in_adjoint ? &s.in_adjoint : nullptr);
  if (in_adjoint) join_input_adjoint(out_adjoint, s.in_adjoint, *in_adjoint);
}

template <typename Scalar>
void OnColumns<Scalar>::backward_per_point(const StreamLayout& layout, const Scalar* params,
                                           const Streams<Scalar>& in,
                                           const SavedTensors<Scalar>& saved,
                                           Streams<Scalar>& out_adjoint,
                                           JacobianRows<Scalar> jacobian,
                                           Streams<Scalar>* in_adjoint) const {
  Scratch<Scalar>& s = scratch<Scalar>();
  slice_input(in, s.in);
  slice_output_adjoint(out_adjoint, s.out_adjoint);
  inner_->backward_per_point(layout, params, s.in, saved, s.out_adjoint, jacobian,
                             in_adjoint ? &s.in_adjoint : nullptr);
  if (in_adjoint) join_input_adjoint(out_adjoint, s.in_adjoint, *in_adjoint);
}

template class OnColumns<float>;
template class OnColumns<double>;

}  // namespace nfield::autodiff
