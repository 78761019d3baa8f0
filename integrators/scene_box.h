// SPDX-License-Identifier: MIT
//
// The axis-aligned box that holds a scene, and where rays enter and leave it.
//
// Slab test: along axis k the ray o + t d is inside the slab [lo_k, hi_k] for t between
// (lo_k − o_k)/d_k and (hi_k − o_k)/d_k; the box is the intersection of the three slabs, so
// t_enter = max over k of the smaller bound and t_exit = min over k of the larger one, and the
// ray meets the box iff t_enter ≤ t_exit. Pitfall: with d_k = 0 the two bounds are ±∞ when
// o_k is strictly inside the slab but 0·∞ = NaN when o_k lies on a face; an axis with d_k = 0
// is therefore decided by o_k alone (inside: no constraint, outside: a miss).
#pragma once

#include <Eigen/Core>
#include <utility>

#include "integrators/rays.h"

namespace nfield::integrators {

struct SceneBox {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(-1.0);
  Eigen::Vector3d upper = Eigen::Vector3d::Constant(1.0);

  // Throws std::invalid_argument naming the field, its value and the rule (finite,
  // lower < upper on every axis).
  void validate() const;

  Eigen::Vector3d size() const { return upper - lower; }
  // Closed box: points on a face are inside.
  bool contains(const Eigen::Vector3d& x) const {
    return (x.array() >= lower.array()).all() && (x.array() <= upper.array()).all();
  }

  // (t_enter, t_exit) of the whole line o + t d, t ∈ ℝ (d need not be unit); t_enter > t_exit
  // when the line misses the box.
  std::pair<double, double> intersect(const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& direction) const;
};

// Clips every ray's [near, far] to the box: near = max(near, t_enter, min_near) and
// far = min(far, t_exit). A ray that misses the box (or whose interval ends up empty) gets
// near = far = 0 (empty).
template <typename Scalar>
void clip_to_box(Rays<Scalar>& rays, const SceneBox& box, double min_near = 0.0);

}  // namespace nfield::integrators
