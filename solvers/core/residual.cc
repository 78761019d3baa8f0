// SPDX-License-Identifier: MIT
#include "solvers/core/residual.h"

#include <cmath>
#include <stdexcept>

namespace nfield::solvers {

LinearResidual::LinearResidual(std::vector<Term> terms, Eigen::MatrixXd source)
    : terms_(std::move(terms)), source_(std::move(source)) {
  for (const Term& t : terms_)
    if (t.coefficient.size() != 1 && t.coefficient.size() != source_.rows())
      throw std::invalid_argument("LinearResidual: a coefficient has " +
                                  std::to_string(t.coefficient.size()) + " values for " +
                                  std::to_string(source_.rows()) + " points");
}

void LinearResidual::evaluate(Eigen::Index first, const StreamLayout&, const Streams<double>& out,
                              Eigen::MatrixXd& r) const {
  const Eigen::Index n = out.points;
  r = -source_.middleRows(first, n);
  for (const Term& t : terms_) {
    if (t.coefficient.size() == 1)
      r.col(t.component) += t.coefficient(0) * out.stream(t.stream).col(t.channel);
    else
      r.col(t.component).array() +=
          t.coefficient.segment(first, n).array() * out.stream(t.stream).col(t.channel).array();
  }
}

void LinearResidual::backward(Eigen::Index first, const StreamLayout&, const Streams<double>& out,
                              const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const {
  const Eigen::Index n = out.points;
  for (const Term& t : terms_) {
    if (t.coefficient.size() == 1)
      adjoint.stream(t.stream).col(t.channel) += t.coefficient(0) * r_bar.col(t.component);
    else
      adjoint.stream(t.stream).col(t.channel).array() +=
          t.coefficient.segment(first, n).array() * r_bar.col(t.component).array();
  }
}

ScaleTargetResidual::ScaleTargetResidual(std::vector<std::unique_ptr<Residual>> scales, int output_scale)
    : scales_(std::move(scales)), output_scale_(output_scale) {
  if (output_scale_ < 0 || output_scale_ >= static_cast<int>(scales_.size()))
    throw std::invalid_argument("ScaleTargetResidual: the output scale is not one of the scales");
}

const Residual& ScaleTargetResidual::at_scale(int scale) const {
  if (scale < 0 || scale >= static_cast<int>(scales_.size()))
    throw std::invalid_argument("ScaleTargetResidual: scale " + std::to_string(scale) + " of " +
                                std::to_string(scales_.size()));
  return *scales_[static_cast<size_t>(scale)];
}

template <typename Scalar>
double ResidualLoss<Scalar>::evaluate_with(const Residual& residual, Eigen::Index first, const StreamLayout& layout,
                                           const Streams<Scalar>& out, Streams<Scalar>& adjoint) const {
  thread_local Streams<double> out_d, adjoint_d;
  thread_local Eigen::MatrixXd r;
  out_d.points = out.points;
  out_d.count = out.count;
  out_d.data = out.data.template cast<double>();
  first += offset_;
  residual.evaluate(first, layout, out_d, r);
  adjoint_d.points = out.points;
  adjoint_d.count = out.count;
  adjoint_d.data.setZero(out.data.rows(), out.data.cols());
  const auto gather_extra = [&](const Eigen::MatrixXd& r_bar) {
    if (!extra_ || residual.extra_parameters() == 0) return;
    Eigen::MatrixXd jacobian;
    residual.extra_jacobian(first, layout, out_d, jacobian);
    // Rows of the Jacobian are point-major (n·C + c); r̄ is n × C.
    const Eigen::MatrixXd r_bar_rows = r_bar.transpose();
    extra_->add(first, jacobian.transpose() * Eigen::Map<const Eigen::VectorXd>(r_bar_rows.data(), r_bar_rows.size()));
  };
  if (point_weights_) {
    const auto a = point_weights_->segment(first, out.points).array();
    const Eigen::MatrixXd r_bar = (2.0 * scale_) * (r.array().colwise() * a).matrix();
    residual.backward(first, layout, out_d, r_bar, adjoint_d);
    gather_extra(r_bar);
    adjoint.data += adjoint_d.data.template cast<Scalar>();
    return scale_ * (r.rowwise().squaredNorm().array() * a).sum();
  }
  const Eigen::MatrixXd r_bar = (2.0 * scale_) * r;
  residual.backward(first, layout, out_d, r_bar, adjoint_d);
  gather_extra(r_bar);
  adjoint.data += adjoint_d.data.template cast<Scalar>();
  return scale_ * r.squaredNorm();
}

namespace {
template <typename Scalar>
void to_double(const Streams<Scalar>& from, Streams<double>& to) {
  to.points = from.points;
  to.count = from.count;
  to.data = from.data.template cast<double>();
}
}  // namespace

template <typename Scalar>
ScaledResidual<Scalar>::ScaledResidual(const Residual& residual, double weight,
                                       Eigen::Index total_points, Eigen::Index offset)
    : residual_(residual), scale_(std::sqrt(weight / static_cast<double>(total_points))),
      offset_(offset) {}

template <typename Scalar>
void ScaledResidual<Scalar>::evaluate(Eigen::Index first, const StreamLayout& layout,
                                      const Streams<Scalar>& out,
                                      autodiff::Matrix<Scalar>& r) const {
  thread_local Streams<double> out_d;
  thread_local Eigen::MatrixXd r_d;
  to_double(out, out_d);
  residual_.evaluate(first + offset_, layout, out_d, r_d);
  r = (scale_ * r_d).template cast<Scalar>();
}

template <typename Scalar>
void ScaledResidual<Scalar>::backward(Eigen::Index first, const StreamLayout& layout,
                                      const Streams<Scalar>& out,
                                      const autodiff::Matrix<Scalar>& r_bar,
                                      Streams<Scalar>& adjoint) const {
  thread_local Streams<double> out_d, adjoint_d;
  to_double(out, out_d);
  adjoint_d.points = out.points;
  adjoint_d.count = out.count;
  adjoint_d.data.setZero(out.data.rows(), out.data.cols());
  const Eigen::MatrixXd r_bar_d = scale_ * r_bar.template cast<double>();
  residual_.backward(first + offset_, layout, out_d, r_bar_d, adjoint_d);
  adjoint.data += adjoint_d.data.template cast<Scalar>();
}

template <typename Scalar>
void ScaledResidual<Scalar>::extra_jacobian(Eigen::Index first, const StreamLayout& layout,
                                            const Streams<Scalar>& out,
                                            autodiff::Matrix<Scalar>& jacobian) const {
  thread_local Streams<double> out_d;
  to_double(out, out_d);
  Eigen::MatrixXd j;
  residual_.extra_jacobian(first + offset_, layout, out_d, j);
  jacobian = (scale_ * j).template cast<Scalar>();
}

template class ScaledResidual<float>;
template class ScaledResidual<double>;
template class ResidualLoss<float>;
template class ResidualLoss<double>;

}  // namespace nfield::solvers
