// SPDX-License-Identifier: MIT
//
// A batch of rays r(t) = o + t d, the unit of work of every integrator in this layer.
//
// Layout: ray n is row n of each member (structure of arrays, so a batch's origins and
// directions go to a network as N × 3 matrices without a copy).
//
//   origins      N × 3   o, world space
//   directions   N × 3   d, unit length, so t is a world-space distance along the ray
//   depth_scale  N       cos of the angle between d and the camera's optical axis (−z): a
//                        point at distance t lies at camera depth z = t · depth_scale. Depth
//                        maps in the camera's sense (z-buffer) come from expected distances
//                        through this factor; it is 1/‖d_cam‖ for the unnormalized camera-space
//                        direction d_cam = ((u − cx)/fx, −(v − cy)/fy, −1).
//   near, far    N       the part of the ray to integrate, t ∈ [near, far]; empty when
//                        far ≤ near (a ray that misses the scene box). Samplers give such a ray
//                        no samples, and the renderer gives it the background.
//   radius       N       the ray as a cone (mip-NeRF, Barron et al. 2021): its radius at distance
//                        t is radius · t. A camera ray's is 2/√12 times its pixel's width at unit
//                        distance, so that the cone's cross-section has the variance of the
//                        pixel's square (a disc of radius ρ has ρ²/4 per axis, a square of side
//                        w has w²/12). 0: a ray of no width. Only the frustum Gaussians read
//                        it (cone_frustums.h), which refuse rays without it (empty).
//
// Scalar is float for training (the default for radiance fields) or double for tests.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <type_traits>

#include "autodiff/streams.h"

namespace nfield::integrators {

using autodiff::Matrix;
using autodiff::Vector;

// Views of a network's outputs and adjoints (columns and blocks without a copy). Scalar sits in
// a non-deduced context, so a call deduces it from the rays or samples and converts the Eigen
// expression passed here.
template <typename Scalar>
using ConstVectorRef = Eigen::Ref<const Vector<std::type_identity_t<Scalar>>>;
template <typename Scalar>
using ConstMatrixRef = Eigen::Ref<const Matrix<std::type_identity_t<Scalar>>>;
template <typename Scalar>
using VectorRef = Eigen::Ref<Vector<std::type_identity_t<Scalar>>>;
template <typename Scalar>
using MatrixRef = Eigen::Ref<Matrix<std::type_identity_t<Scalar>>>;

template <typename Scalar>
struct Rays {
  Matrix<Scalar> origins;
  Matrix<Scalar> directions;
  Vector<Scalar> depth_scale;
  Vector<Scalar> near;
  Vector<Scalar> far;
  Vector<Scalar> radius;

  Eigen::Index size() const { return origins.rows(); }

  // Room for n rays: near = 0, far = +∞ (a sampler asks for a finite far), depth_scale = 1,
  // radius = 0.
  void resize(Eigen::Index n) {
    origins.resize(n, 3);
    directions.resize(n, 3);
    depth_scale.setOnes(n);
    near.setZero(n);
    far.setConstant(n, std::numeric_limits<Scalar>::infinity());
    radius.setZero(n);
  }

  // The same rays in another scalar type.
  template <typename Other>
  Rays<Other> cast() const {
    return {origins.template cast<Other>(), directions.template cast<Other>(),
            depth_scale.template cast<Other>(), near.template cast<Other>(),
            far.template cast<Other>(), radius.template cast<Other>()};
  }

  // Rays `rows` of these (an index list or an Eigen sequence). Rays filled member by member
  // without resize may leave `radius` empty; their subset's is empty too.
  template <typename Rows>
  Rays subset(const Rows& rows) const {
    return {origins(rows, Eigen::all), directions(rows, Eigen::all), depth_scale(rows), near(rows),
            far(rows), radius.size() == 0 ? Vector<Scalar>() : Vector<Scalar>(radius(rows))};
  }
};

// Every ray integrates over the same [near, far] (NeRF-synthetic scenes: [2, 6]).
template <typename Scalar>
void set_bounds(Rays<Scalar>& rays, double near, double far) {
  rays.near.setConstant(rays.size(), static_cast<Scalar>(near));
  rays.far.setConstant(rays.size(), static_cast<Scalar>(far));
}

}  // namespace nfield::integrators
