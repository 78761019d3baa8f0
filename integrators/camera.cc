// SPDX-License-Identifier: MIT
#include "integrators/camera.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nfield::integrators {
namespace {

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

Intrinsics Intrinsics::from_horizontal_fov(double angle_x, int width, int height) {
  if (!(angle_x > 0 && angle_x < std::numbers::pi))
    throw std::invalid_argument("camera_angle_x = " + number(angle_x) +
                                ": must be in (0, pi) radians");
  Intrinsics k;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * angle_x);
  k.cx = 0.5 * width;
  k.cy = 0.5 * height;
  k.width = width;
  k.height = height;
  k.validate();
  return k;
}

void Intrinsics::validate() const {
  const auto positive = [](const char* name, double v) {
    if (!(std::isfinite(v) && v > 0))
      throw std::invalid_argument(std::string("intrinsics.") + name + " = " + number(v) +
                                  ": must be finite and > 0");
  };
  positive("fx", fx);
  positive("fy", fy);
  for (auto [name, v] : {std::pair{"cx", cx}, std::pair{"cy", cy}})
    if (!std::isfinite(v))
      throw std::invalid_argument(std::string("intrinsics.") + name + " = " + number(v) +
                                  ": must be finite");
  for (auto [name, v] : {std::pair{"width", width}, std::pair{"height", height}})
    if (v < 1)
      throw std::invalid_argument(std::string("intrinsics.") + name + " = " +
                                  std::to_string(v) + ": must be >= 1");
}

Eigen::Vector3d Camera::direction(double u, double v) const {
  const Eigen::Vector3d d_cam((u - intrinsics.cx) / intrinsics.fx,
                              -(v - intrinsics.cy) / intrinsics.fy, -1.0);
  return camera_to_world.block<3, 3>(0, 0) * d_cam;
}

template <typename Scalar>
void set_ray(const Camera& camera, double u, double v, Rays<Scalar>& rays, Eigen::Index row) {
  const Eigen::Vector3d d = camera.direction(u, v);
  // R is a rotation, so ‖R d_cam‖ = ‖d_cam‖ and the camera depth of o + t·d/‖d‖ is t/‖d‖.
  const double norm = d.norm();
  rays.origins.row(row) = camera.centre().transpose().cast<Scalar>();
  rays.directions.row(row) = (d / norm).transpose().cast<Scalar>();
  rays.depth_scale(row) = static_cast<Scalar>(1.0 / norm);
  // A pixel is 1/fx by 1/fy at camera depth 1, i.e. at distance ‖d_cam‖ along the ray: its
  // width at unit distance is 1/(√(fx·fy)·‖d_cam‖) (the geometric mean of the two sides).
  const double width = 1.0 / (std::sqrt(camera.intrinsics.fx * camera.intrinsics.fy) * norm);
  rays.radius(row) = static_cast<Scalar>(2.0 / std::sqrt(12.0) * width);
}

template <typename Scalar>
Rays<Scalar> image_rays(const Camera& camera) {
  camera.intrinsics.validate();
  const int w = camera.intrinsics.width, h = camera.intrinsics.height;
  Rays<Scalar> rays;
  rays.resize(Eigen::Index{w} * h);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) set_ray(camera, c + 0.5, r + 0.5, rays, Eigen::Index{r} * w + c);
  return rays;
}

template Rays<float> image_rays(const Camera&);
template Rays<double> image_rays(const Camera&);
template void set_ray(const Camera&, double, double, Rays<float>&, Eigen::Index);
template void set_ray(const Camera&, double, double, Rays<double>&, Eigen::Index);

}  // namespace nfield::integrators
