// SPDX-License-Identifier: MIT
//
// Pinhole cameras and the rays through their pixels.
//
// Conventions (those of NeRF's transforms.json, i.e. OpenGL/Blender):
//
//   camera axes      +x right, +y up, the camera looks along −z
//   camera_to_world  4 × 4, [R t; 0 1]: columns 0–2 of R are the camera's axes in world
//                    coordinates, t is the camera centre
//   pixel (r, c)     row r from the top, column c from the left; its centre sits at the
//                    continuous image coordinates (u, v) = (c + 0.5, r + 0.5), u to the
//                    right and v downwards, so (0, 0) is the top-left corner of the image
//   intrinsics       (u, v) = (cx + fx·x/(−z), cy − fy·y/(−z)) for a camera-space point
//                    (x, y, z); the minus on y because v grows downwards while y grows up
//
// So the ray through (u, v) has the camera-space direction d_cam = ((u − cx)/fx,
// −(v − cy)/fy, −1), world direction R·d_cam, origin t. Rays are stored with ‖d‖ = 1 and the
// factor 1/‖d_cam‖ kept as depth_scale (rays.h).
//
// Pitfall: the image centre of an even-sized image is a pixel corner (cx = w/2 lies between
// columns w/2 − 1 and w/2), not a pixel centre; no pixel's ray passes through the principal
// point exactly.
#pragma once

#include <Eigen/Core>

#include "integrators/rays.h"

namespace nfield::integrators {

struct Intrinsics {
  double fx = 0, fy = 0;  // focal lengths in pixels; > 0
  double cx = 0, cy = 0;  // principal point in continuous image coordinates; finite
  int width = 0, height = 0;  // pixels; ≥ 1

  // NeRF-synthetic: fx = fy = 0.5·width / tan(0.5·angle_x), principal point at the centre.
  static Intrinsics from_horizontal_fov(double angle_x, int width, int height);

  // Throws std::invalid_argument naming the field, its value and the rule.
  void validate() const;
};

struct Camera {
  Intrinsics intrinsics;
  Eigen::Matrix4d camera_to_world = Eigen::Matrix4d::Identity();

  Eigen::Vector3d centre() const { return camera_to_world.block<3, 1>(0, 3); }
  // The world-space direction through continuous image coordinates (u, v), not normalized:
  // its camera-space z is −1.
  Eigen::Vector3d direction(double u, double v) const;
};

// The rays through the centres of all pixels of the image, ray r·width + c for pixel (r, c)
// (the pixel order of io::Image). near = 0 and far = +∞ (set them with set_bounds or
// clip_to_box).
template <typename Scalar>
Rays<Scalar> image_rays(const Camera& camera);

// Writes the ray through continuous image coordinates (u, v) into row `row` of `rays`
// (direction normalized, depth_scale = 1/‖d_cam‖, the cone radius of its pixel, rays.h);
// near and far are left as they are.
template <typename Scalar>
void set_ray(const Camera& camera, double u, double v, Rays<Scalar>& rays, Eigen::Index row);

}  // namespace nfield::integrators
