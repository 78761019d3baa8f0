// SPDX-License-Identifier: MIT
#include "fields/latent_code.h"

namespace nfield::fields {

template <typename Scalar>
bool LatentCode<Scalar>::initialize(Scalar* params, std::mt19937_64&) const {
  std::fill(params, params + size_, Scalar(0));
  return true;
}

template <typename Scalar>
void LatentCode<Scalar>::forward(const autodiff::StreamLayout&, const Scalar* params,
                                 const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
                                 autodiff::SavedTensors<Scalar>*) const {
  out.resize(in.points, in.count, width_ + size_);
  out.data.leftCols(width_) = in.data;
  out.data.rightCols(size_).setZero();
  const Eigen::Map<const Eigen::Matrix<Scalar, 1, Eigen::Dynamic>> code(params, size_);
  out.values().rightCols(size_).rowwise() = code;
}

template <typename Scalar>
void LatentCode<Scalar>::pass_adjoint(const autodiff::Streams<Scalar>& out_adjoint,
                                      autodiff::Streams<Scalar>* in_adjoint) const {
  if (!in_adjoint) return;
  in_adjoint->resize(out_adjoint.points, out_adjoint.count, width_);
  in_adjoint->data = out_adjoint.data.leftCols(width_);
}

template <typename Scalar>
void LatentCode<Scalar>::backward(const autodiff::StreamLayout&, const Scalar*, const autodiff::Streams<Scalar>&,
                                  const autodiff::SavedTensors<Scalar>&, autodiff::Streams<Scalar>& out_adjoint,
                                  Scalar* gradient, autodiff::Streams<Scalar>* in_adjoint) const {
  if (gradient) {
    Eigen::Map<Eigen::Matrix<Scalar, 1, Eigen::Dynamic>> g(gradient, size_);
    g += out_adjoint.values().rightCols(size_).colwise().sum();
  }
  pass_adjoint(out_adjoint, in_adjoint);
}

template <typename Scalar>
void LatentCode<Scalar>::backward_per_point(const autodiff::StreamLayout&, const Scalar*,
                                            const autodiff::Streams<Scalar>&, const autodiff::SavedTensors<Scalar>&,
                                            autodiff::Streams<Scalar>& out_adjoint,
                                            autodiff::JacobianRows<Scalar> jacobian,
                                            autodiff::Streams<Scalar>* in_adjoint) const {
  jacobian = out_adjoint.values().rightCols(size_);
  pass_adjoint(out_adjoint, in_adjoint);
}

template class LatentCode<float>;
template class LatentCode<double>;

}  // namespace nfield::fields
