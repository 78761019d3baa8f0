// SPDX-License-Identifier: MIT
#include "integrators/scene_box.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace nfield::integrators {

void SceneBox::validate() const {
  for (int k = 0; k < 3; ++k)
    if (!(std::isfinite(lower[k]) && std::isfinite(upper[k]) && lower[k] < upper[k])) {
      std::ostringstream out;
      out << "scene_box: lower[" << k << "] = " << lower[k] << ", upper[" << k
          << "] = " << upper[k] << ": both must be finite with lower < upper";
      throw std::invalid_argument(out.str());
    }
}

std::pair<double, double> SceneBox::intersect(const Eigen::Vector3d& origin,
                                              const Eigen::Vector3d& direction) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double enter = -kInf, exit = kInf;
  for (int k = 0; k < 3; ++k) {
    if (direction[k] == 0) {
      if (origin[k] < lower[k] || origin[k] > upper[k]) return {kInf, -kInf};
      continue;
    }
    const double inv = 1.0 / direction[k];
    double t0 = (lower[k] - origin[k]) * inv, t1 = (upper[k] - origin[k]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    exit = std::min(exit, t1);
  }
  return {enter, exit};
}

template <typename Scalar>
void clip_to_box(Rays<Scalar>& rays, const SceneBox& box, double min_near) {
  box.validate();
#pragma omp parallel for schedule(static) if (rays.size() > 4096)
  for (Eigen::Index n = 0; n < rays.size(); ++n) {
    const auto [enter, exit] = box.intersect(rays.origins.row(n).transpose().template cast<double>(),
                                             rays.directions.row(n).transpose().template cast<double>());
    const double near = std::max({static_cast<double>(rays.near(n)), enter, min_near});
    const double far = std::min(static_cast<double>(rays.far(n)), exit);
    if (near < far) {
      rays.near(n) = static_cast<Scalar>(near);
      rays.far(n) = static_cast<Scalar>(far);
    } else {
      rays.near(n) = rays.far(n) = Scalar(0);
    }
  }
}

template void clip_to_box(Rays<float>&, const SceneBox&, double);
template void clip_to_box(Rays<double>&, const SceneBox&, double);

}  // namespace nfield::integrators
