// SPDX-License-Identifier: MIT
#include "solvers/conditions/periodic.h"

#include "autodiff/sequential.h"

namespace nfield::solvers {

void PeriodicResidual::evaluate(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                                Eigen::MatrixXd& r) const {
  const auto [k0, k1] = autodiff::groups_in_block(groups_, first, out.points);
  const auto value = out.stream(layout.value());
  const auto slope = out.stream(layout.tangent(0));
  r.resize(static_cast<Eigen::Index>(k1 - k0), components());
  for (size_t k = k0; k < k1; ++k) {
    const Eigen::Index p = groups_[k] - first, row = static_cast<Eigen::Index>(k - k0);
    for (size_t j = 0; j < outputs_.size(); ++j) {
      const int c = outputs_[j];
      r(row, static_cast<Eigen::Index>(2 * j)) = value(p, c) - value(p + 1, c);
      r(row, static_cast<Eigen::Index>(2 * j + 1)) = slope(p, c) - slope(p + 1, c);
    }
  }
}

void PeriodicResidual::backward(Eigen::Index first, const StreamLayout& layout, const Streams<double>& out,
                                const Eigen::MatrixXd& r_bar, Streams<double>& adjoint) const {
  const auto [k0, k1] = autodiff::groups_in_block(groups_, first, out.points);
  auto value = adjoint.stream(layout.value());
  auto slope = adjoint.stream(layout.tangent(0));
  for (size_t k = k0; k < k1; ++k) {
    const Eigen::Index p = groups_[k] - first, row = static_cast<Eigen::Index>(k - k0);
    for (size_t j = 0; j < outputs_.size(); ++j) {
      const int c = outputs_[j];
      const double v = r_bar(row, static_cast<Eigen::Index>(2 * j));
      const double s = r_bar(row, static_cast<Eigen::Index>(2 * j + 1));
      value(p, c) += v;
      value(p + 1, c) -= v;
      slope(p, c) += s;
      slope(p + 1, c) -= s;
    }
  }
}

autodiff::StreamSpec periodic_spec(const Domain& domain, int axis) {
  autodiff::StreamSpec spec = autodiff::StreamSpec::values(domain.input_dim());
  spec.tangents = Eigen::MatrixXd::Zero(domain.input_dim(), 1);
  spec.tangents(axis, 0) = 1.0;
  return spec;
}

TermPoints periodic_points(const Domain& domain, const Face& lower, Random& rng, Eigen::Index n) {
  const Eigen::MatrixXd p = domain.sample_face(lower, rng, n);
  TermPoints points;
  points.x.resize(2 * n, p.cols());
  for (Eigen::Index k = 0; k < n; ++k) {
    points.x.row(2 * k) = p.row(k);
    points.x.row(2 * k + 1) = p.row(k);
    points.x(2 * k + 1, lower.axis) = domain.upper()[static_cast<size_t>(lower.axis)];
  }
  points.groups.resize(static_cast<size_t>(n) + 1);
  for (Eigen::Index k = 0; k <= n; ++k) points.groups[static_cast<size_t>(k)] = 2 * k;
  return points;
}

}  // namespace nfield::solvers
