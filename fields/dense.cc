// SPDX-License-Identifier: MIT
#include "fields/dense.h"

namespace nfield::fields {

using autodiff::Matrix;
using autodiff::Vector;

template <typename Scalar>
void Dense<Scalar>::forward(const autodiff::StreamLayout&, const Scalar* params,
                            const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
                            autodiff::SavedTensors<Scalar>*) const {
  const Eigen::Map<const Matrix<Scalar>> weight(params, out_, in_);
  const Eigen::Map<const Vector<Scalar>> bias(params + out_ * in_, out_);
  out.resize(in.points, in.count, out_);
  out.data.noalias() = in.data * weight.transpose();
  out.stream(0).rowwise() += bias.transpose();
}

template <typename Scalar>
void Dense<Scalar>::backward(const autodiff::StreamLayout&, const Scalar* params,
                             const autodiff::Streams<Scalar>& in,
                             const autodiff::SavedTensors<Scalar>&,
                             autodiff::Streams<Scalar>& out_adjoint, Scalar* gradient,
                             autodiff::Streams<Scalar>* in_adjoint) const {
  const Eigen::Map<const Matrix<Scalar>> weight(params, out_, in_);
  Eigen::Map<Matrix<Scalar>> weight_bar(gradient, out_, in_);
  Eigen::Map<Vector<Scalar>> bias_bar(gradient + out_ * in_, out_);
  weight_bar.noalias() += out_adjoint.data.transpose() * in.data;
  bias_bar += out_adjoint.stream(0).colwise().sum().transpose();
  if (in_adjoint) {
    in_adjoint->resize(in.points, in.count, in_);
    in_adjoint->data.noalias() = out_adjoint.data * weight;
  }
}

template <typename Scalar>
void Dense<Scalar>::backward_per_point(const autodiff::StreamLayout&, const Scalar* params,
                                       const autodiff::Streams<Scalar>& in,
                                       const autodiff::SavedTensors<Scalar>&,
                                       autodiff::Streams<Scalar>& out_adjoint,
                                       Eigen::Ref<Matrix<Scalar>> jacobian,
                                       autodiff::Streams<Scalar>* in_adjoint) const {
  for (Eigen::Index j = 0; j < in_; ++j) {
    auto w_j = jacobian.middleCols(j * out_, out_).array();
    w_j = out_adjoint.stream(0).array().colwise() * in.stream(0).col(j).array();
    for (int s = 1; s < in.count; ++s)
      w_j += out_adjoint.stream(s).array().colwise() * in.stream(s).col(j).array();
  }
  jacobian.rightCols(out_) = out_adjoint.stream(0);
  if (in_adjoint) {
    const Eigen::Map<const Matrix<Scalar>> weight(params, out_, in_);
    in_adjoint->resize(in.points, in.count, in_);
    in_adjoint->data.noalias() = out_adjoint.data * weight;
  }
}

template class Dense<float>;
template class Dense<double>;

}  // namespace nfield::fields
