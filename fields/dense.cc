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
  out.values().rowwise() += bias.transpose();
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
  bias_bar += out_adjoint.values().colwise().sum().transpose();
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
                                       autodiff::JacobianRows<Scalar> jacobian,
                                       autodiff::Streams<Scalar>* in_adjoint) const {
  // Transposed, column s·N + n holds z̄_{s,n} (a_{s,n}): one contiguous vector per point and
  // stream.
  thread_local Matrix<Scalar> z_bar, a;
  z_bar = out_adjoint.data.transpose();
  a = in.data.transpose();
  const Eigen::Index n_points = in.points;
  for (Eigen::Index n = 0; n < n_points; ++n) {
    Eigen::Map<Matrix<Scalar>> w(&jacobian(n, 0), out_, in_);
    w.noalias() = z_bar.col(n) * a.col(n).transpose();
    for (int s = 1; s < in.count; ++s)
      w.noalias() += z_bar.col(s * n_points + n) * a.col(s * n_points + n).transpose();
    Eigen::Map<Vector<Scalar>>(&jacobian(n, out_ * in_), out_) = z_bar.col(n);
  }
  if (in_adjoint) {
    const Eigen::Map<const Matrix<Scalar>> weight(params, out_, in_);
    in_adjoint->resize(in.points, in.count, in_);
    in_adjoint->data.noalias() = out_adjoint.data * weight;
  }
}

template class Dense<float>;
template class Dense<double>;

}  // namespace nfield::fields
