// SPDX-License-Identifier: MIT
#include "fields/dense.h"

#include <type_traits>

#include "autodiff/small_gemm.h"

namespace nfield::fields {

using autodiff::GemmOp;
using autodiff::Matrix;
using autodiff::Vector;

namespace {

// C ← β C + op(A) op(B), β = 0 or 1: float through the small-network kernel
// (autodiff/small_gemm.h) at the shapes where it pays, otherwise and in double through Eigen.
template <typename Scalar, typename A, typename B, typename C>
void product(GemmOp op_a, GemmOp op_b, const A& a, const B& b, Scalar beta, C& c) {
  const Eigen::Index k = op_a == GemmOp::kNone ? a.cols() : a.rows();
  if constexpr (std::is_same_v<Scalar, float>) {
    if (autodiff::small_gemm_pays(c.rows(), c.cols(), k))
      return autodiff::small_gemm(op_a, op_b, c.rows(), c.cols(), k, a.data(), a.outerStride(), b.data(),
                                  b.outerStride(), beta, c.data(), c.outerStride());
  }
  const auto assign = [&](const auto& ab) {
    if (beta == Scalar(0)) c.noalias() = ab;
    else c.noalias() += ab;
  };
  if (op_a == GemmOp::kTranspose) assign(a.transpose() * b);
  else if (op_b == GemmOp::kTranspose) assign(a * b.transpose());
  else assign(a * b);
}

}  // namespace

template <typename Scalar>
void Dense<Scalar>::forward(const autodiff::StreamLayout&, const Scalar* params,
                            const autodiff::Streams<Scalar>& in, autodiff::Streams<Scalar>& out,
                            autodiff::SavedTensors<Scalar>*) const {
  const Eigen::Map<const Matrix<Scalar>> weight(params, out_, in_);
  const Eigen::Map<const Vector<Scalar>> bias(params + out_ * in_, out_);
  out.resize(in.points, in.count, out_);
  product<Scalar>(GemmOp::kNone, GemmOp::kTranspose, in.data, weight, 0, out.data);
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
  product<Scalar>(GemmOp::kTranspose, GemmOp::kNone, out_adjoint.data, in.data, 1, weight_bar);
  bias_bar += out_adjoint.values().colwise().sum().transpose();
  if (in_adjoint) {
    in_adjoint->resize(in.points, in.count, in_);
    product<Scalar>(GemmOp::kNone, GemmOp::kNone, out_adjoint.data, weight, 0, in_adjoint->data);
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
    product<Scalar>(GemmOp::kNone, GemmOp::kNone, out_adjoint.data, weight, 0, in_adjoint->data);
  }
}

template class Dense<float>;
template class Dense<double>;

}  // namespace nfield::fields
