// SPDX-License-Identifier: MIT
#include "fields/encodings.h"

#include <numbers>
#include <stdexcept>

#include "autodiff/elementwise.h"
#include "fields/activations.h"

namespace nfield::fields {

template <typename Scalar>
FeatureEncoding<Scalar>::FeatureEncoding(const Eigen::MatrixXd& weights,
                                         const Eigen::VectorXd& offsets,
                                         std::unique_ptr<autodiff::ElementwiseFunction<Scalar>> function,
                                         bool include_input, const Eigen::VectorXd& scales)
    : weights_(weights.cast<Scalar>()),
      offsets_(offsets.transpose().cast<Scalar>()),
      scales_(scales.transpose().cast<Scalar>()),
      function_(std::move(function)),
      include_input_(include_input) {
  if (offsets.size() != weights.rows())
    throw std::logic_error("FeatureEncoding: one offset per row of the weights expected");
  if (scales.size() != 0 && scales.size() != weights.rows())
    throw std::logic_error("FeatureEncoding: one scale per row of the weights expected");
}

// saved = [z streams (one matrix), derivative tables …]
template <typename Scalar>
void FeatureEncoding<Scalar>::forward(const autodiff::StreamLayout& layout, const Scalar*,
                                      const autodiff::Streams<Scalar>& in,
                                      autodiff::Streams<Scalar>& out,
                                      autodiff::SavedTensors<Scalar>* saved) const {
  const Eigen::Index d = include_input_ ? in.width() : 0;
  if (!features_on_) {
    out.resize(in.points, in.count, d + weights_.rows());
    if (d > 0) out.data.leftCols(d) = in.data;
    out.data.rightCols(weights_.rows()).setZero();
    if (saved) saved->clear();
    return;
  }
  thread_local autodiff::Streams<Scalar> z, y;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  z.resize(in.points, in.count, weights_.rows());
  z.data.noalias() = in.data * weights_.transpose();
  z.values().rowwise() += offsets_.row(0);
  const int order = layout.forward_order() + (saved ? 1 : 0);
  function_->derivatives(z.values(), order, tables);
  autodiff::elementwise_forward(layout, tables, z, y);
  out.resize(in.points, in.count, d + y.width());
  if (d > 0) out.data.leftCols(d) = in.data;
  out.data.rightCols(y.width()) = y.data;
  // Every stream is linear in the feature, so the scale multiplies each stream alike.
  if (scales_.size() > 0) out.data.rightCols(y.width()).array().rowwise() *= scales_.row(0).array();
  if (saved) {
    saved->resize(1 + tables.size());
    (*saved)[0] = z.data;
    for (size_t m = 0; m < tables.size(); ++m) (*saved)[1 + m] = tables[m];
  }
}

template <typename Scalar>
void FeatureEncoding<Scalar>::backward(const autodiff::StreamLayout& layout, const Scalar*,
                                       const autodiff::Streams<Scalar>& in,
                                       const autodiff::SavedTensors<Scalar>& saved,
                                       autodiff::Streams<Scalar>& out_adjoint, Scalar*,
                                       autodiff::Streams<Scalar>* in_adjoint) const {
  if (!in_adjoint) return;
  const Eigen::Index d = include_input_ ? in.width() : 0;
  if (!features_on_) {
    in_adjoint->resize(in.points, in.count, in.width());
    if (d > 0)
      in_adjoint->data = out_adjoint.data.leftCols(d);
    else
      in_adjoint->data.setZero();
    return;
  }
  thread_local autodiff::Streams<Scalar> z, y_adjoint, z_adjoint;
  thread_local std::vector<autodiff::Matrix<Scalar>> tables;
  z.points = in.points;
  z.count = in.count;
  z.data = saved[0];
  tables.assign(saved.begin() + 1, saved.end());
  y_adjoint.resize(in.points, in.count, weights_.rows());
  y_adjoint.data = out_adjoint.data.rightCols(weights_.rows());
  if (scales_.size() > 0) y_adjoint.data.array().rowwise() *= scales_.row(0).array();
  autodiff::elementwise_backward(layout, tables, z, y_adjoint, z_adjoint);
  in_adjoint->resize(in.points, in.count, in.width());
  in_adjoint->data.noalias() = z_adjoint.data * weights_;
  if (d > 0) in_adjoint->data += out_adjoint.data.leftCols(d);
}

template class FeatureEncoding<float>;
template class FeatureEncoding<double>;

template <typename Scalar>
std::unique_ptr<autodiff::Module<Scalar>> make_sinusoids(const Eigen::MatrixXd& b, bool include_input,
                                                         const Eigen::VectorXd& scales) {
  const Eigen::Index m = b.rows();
  Eigen::MatrixXd doubled(2 * m, b.cols());
  doubled << b, b;
  Eigen::VectorXd phase(2 * m);
  phase << Eigen::VectorXd::Zero(m), Eigen::VectorXd::Constant(m, std::numbers::pi / 2);
  Eigen::VectorXd doubled_scales;
  if (scales.size() > 0) {
    doubled_scales.resize(2 * m);
    doubled_scales << scales, scales;
  }
  return std::make_unique<FeatureEncoding<Scalar>>(
      doubled, phase, make_activation<Scalar>({"sine", 1.0}), include_input, doubled_scales);
}

template std::unique_ptr<autodiff::Module<float>> make_sinusoids<float>(const Eigen::MatrixXd&, bool,
                                                                        const Eigen::VectorXd&);
template std::unique_ptr<autodiff::Module<double>> make_sinusoids<double>(const Eigen::MatrixXd&, bool,
                                                                          const Eigen::VectorXd&);

}  // namespace nfield::fields
