// SPDX-License-Identifier: MIT
//
// How a shape read from a file (a cloud, a mesh) is placed in a problem's box: the centre of
// its bounding box goes to the box's centre and its longest side to (1 − margin) of the box's
// shortest side, x_box = (x − c) s + c_box. The sdf and occupancy problems fit their shapes
// this way (`normalize`, `margin`) and write their surfaces back in the file's coordinates.
#pragma once

#include <Eigen/Core>

namespace nfield::solvers {

struct ShapePlacement {
  Eigen::Vector3d center = Eigen::Vector3d::Zero(), domain_center = Eigen::Vector3d::Zero();
  double scale = 1;  // s; 1 (and centres 0): the identity

  // The placement of `points` (rows x y z) in [lower, upper] with `margin` ∈ [0, 1) left free.
  static ShapePlacement fit(const Eigen::MatrixXd& points, const Eigen::Vector3d& lower, const Eigen::Vector3d& upper,
                            double margin) {
    ShapePlacement p;
    const Eigen::Vector3d lo = points.colwise().minCoeff(), hi = points.colwise().maxCoeff();
    p.center = 0.5 * (lo + hi);
    p.domain_center = 0.5 * (lower + upper);
    const double half = 0.5 * (hi - lo).maxCoeff();
    const double room = 0.5 * (upper - lower).minCoeff();
    p.scale = half > 0 ? (1 - margin) * room / half : 1.0;
    return p;
  }
  // Whether every row of `points` lies in [lower, upper] (a shape kept where it is).
  static bool within(const Eigen::MatrixXd& points, const Eigen::Vector3d& lower, const Eigen::Vector3d& upper) {
    return ((points.rowwise() - lower.transpose()).array() >= 0).all() &&
           ((points.rowwise() - upper.transpose()).array() <= 0).all();
  }
  Eigen::MatrixXd to_domain(const Eigen::MatrixXd& x) const {
    return ((x.rowwise() - center.transpose()) * scale).rowwise() + domain_center.transpose();
  }
  Eigen::MatrixXd to_original(const Eigen::MatrixXd& x) const {
    return ((x.rowwise() - domain_center.transpose()) / scale).rowwise() + center.transpose();
  }
};

}  // namespace nfield::solvers
