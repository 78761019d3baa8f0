// SPDX-License-Identifier: MIT
//
// The smooth signed distance of a mesh (solvers/geometry/spline_distance.h): the quintic
// weights (a partition of unity whose derivatives sum to 0), the spline reproducing a linear
// function exactly, its value near the exact distance of a sphere mesh, its zero level near
// the surface, and its gradient and Hessian against central differences, also through a
// Geometry whose mesh is scaled and rotated; the config key `distance: smooth`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "io/config.h"
#include "solvers/geometry/geometry.h"
#include "solvers/geometry/geometry_config.h"
#include "solvers/geometry/mesh_shape.h"
#include "solvers/geometry/spline_distance.h"

namespace nfield::solvers::geometry {
namespace {

const std::filesystem::path kMeshes = std::filesystem::path(NFIELD_SOURCE_DIR) / "data" / "meshes";

TEST(SplineDistance, QuinticWeightsArePartitionOfUnity) {
  for (double t : {0.0, 0.1, 0.5, 0.77, 0.999}) {
    const QuinticWeights w = quintic_weights(t);
    double s = 0, s1 = 0, s2 = 0, first_moment = 0;
    for (int k = 0; k < 6; ++k) {
      s += w.w[k], s1 += w.d1[k], s2 += w.d2[k];
      first_moment += w.w[k] * (k - 2);  // Σ B(u − i) i = u for u = t (nodes −2 … 3)
    }
    EXPECT_NEAR(s, 1, 1e-14);
    EXPECT_NEAR(s1, 0, 1e-13);
    EXPECT_NEAR(s2, 0, 1e-12);
    EXPECT_NEAR(first_moment, t, 1e-14);
    // the derivative against a central difference in t
    const double e = 1e-6;
    const QuinticWeights a = quintic_weights(std::min(t + e, 0.9999999)), b = quintic_weights(std::max(t - e, 0.0));
    const double step = std::min(t + e, 0.9999999) - std::max(t - e, 0.0);
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(w.d1[k], (a.w[k] - b.w[k]) / step, 1e-6);
      EXPECT_NEAR(w.d2[k], (a.d1[k] - b.d1[k]) / step, 1e-5);
    }
  }
}

TEST(SplineDistance, ReproducesLinearFunctions) {
  // The prefiltered spline of a linear function is that function (the filter leaves linear
  // samples alone, the spline reproduces them): value, gradient and a zero Hessian.
  const Vec3 a(0.3, -0.7, 0.2);
  Bounds box{Vec3(-1, -0.5, 0), Vec3(1, 0.5, 0.8)};
  const SplineDistance s(box, 8, [&](const Eigen::MatrixXd& p) { return Eigen::VectorXd(p * a + Eigen::VectorXd::Constant(p.rows(), 0.1)); });
  for (const Vec3& x : {Vec3(0, 0, 0.4), Vec3(-0.93, 0.41, 0.05), Vec3(0.7, -0.2, 0.77)}) {
    const Scalar2 v = s(x);
    EXPECT_NEAR(v.v, a.dot(x) + 0.1, 1e-12);
    EXPECT_LT((v.g - a).norm(), 1e-11);
    EXPECT_LT(v.h.norm(), 1e-9);
  }
}

TEST(SplineDistance, SphereMeshDistanceAndDerivatives) {
  std::unique_ptr<MeshShape> mesh = read_mesh_shape(kMeshes / "sphere.ply");
  const std::unique_ptr<MeshShape> exact = read_mesh_shape(kMeshes / "sphere.ply");
  const double r = mesh->bounds().upper(0);
  mesh->use_spline_distance(32);
  const double h = mesh->spline_distance()->spacing();
  // Near the exact distance inside, the zero level near the surface (the vertices).
  const Eigen::MatrixXd& v = mesh->mesh().vertices;
  double worst_vertex = 0;
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    worst_vertex = std::max(worst_vertex, std::abs(mesh->distance(variables(v.row(i).transpose())).v));
  // The vertices are the polyhedron's corners, where the spline rounds the distance's kink.
  std::printf("sphere mesh, 32 cells (h = %.4f): largest |phi| at a vertex %.2e\n", h, worst_vertex);
  EXPECT_LT(worst_vertex, 0.15 * h);
  Geometry g(ShapeTree::primitive("surface", std::move(mesh)));
  Random rng(3);
  const Eigen::MatrixXd x = g.sample_interior(rng, 40);
  for (Eigen::Index k = 0; k < x.rows(); ++k) {
    const Vec3 p = x.row(k).transpose();
    const Scalar2 d = g.distance(p);
    // Near the exact distance of the polyhedron away from its centre (the medial axis).
    if (p.norm() > 0.5 * r) EXPECT_NEAR(d.v, exact->distance(variables(p)).v, 0.1 * h) << p.transpose();
    EXPECT_GT(d.v, 0);
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e(a) = 1e-5;
      const Scalar2 plus = g.distance(p + e), minus = g.distance(p - e);
      EXPECT_NEAR(d.g(a), (plus.v - minus.v) / 2e-5, 1e-6);
      for (int b = 0; b < 3; ++b) EXPECT_NEAR(d.h(a, b), (plus.g(b) - minus.g(b)) / 2e-5, 1e-4 / h);
    }
  }
}

// The bunny's spline at 24 cells: the zero level near every vertex, φ
// positive at interior points (also in the ears, a few cells thick).
TEST(SplineDistance, BunnyZeroLevelNearTheVertices) {
  std::unique_ptr<MeshShape> mesh = read_mesh_shape(kMeshes / "bunny00.ply");
  mesh->use_spline_distance(24);
  const double h = mesh->spline_distance()->spacing();
  const Eigen::MatrixXd& v = mesh->mesh().vertices;
  double worst = 0, sum_sq = 0;
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const double d = mesh->distance(variables(v.row(i).transpose())).v;
    worst = std::max(worst, std::abs(d));
    sum_sq += d * d;
  }
  std::printf("bunny, 24 cells (h = %.4f): |phi| at the %d vertices: largest %.2e, rms %.2e\n", h,
              static_cast<int>(v.rows()), worst, std::sqrt(sum_sq / static_cast<double>(v.rows())));
  EXPECT_LT(worst, h);
  Geometry g(ShapeTree::primitive("surface", std::move(mesh)));
  Random rng(11);
  const Eigen::MatrixXd x = g.sample_interior(rng, 2000);
  int negative = 0;
  for (Eigen::Index k = 0; k < x.rows(); ++k) negative += g.distance(Vec3(x.row(k).transpose())).v <= 0;
  std::printf("bunny: phi <= 0 at %d of 2000 interior points\n", negative);
  // Measured 26 (1.3 %): the points between the mesh and the zero level, which lies up to
  // 0.36 h off it (rms 0.11 h) where the spline rounds the scan's creases and the ears' tips.
  EXPECT_LT(negative, 60);
}

TEST(SplineDistance, PlacedMeshThroughConfig) {
  // A scaled, rotated, translated mesh: ψ_world(x) = s ψ(local(x)); derivatives by differences.
  const io::ConfigNode root = io::parse_config(
      "geometry: {shape: mesh, file: sphere.ply, distance: smooth, distance_cells: 24, scale: 0.5, "
      "rotate: [20, 30, 40], translate: [0.1, 0.2, 0.3]}\n",
      "test.yaml");
  const Geometry g = read_geometry(root.child("geometry"), kMeshes);
  const Vec3 p(0.15, 0.22, 0.27);
  ASSERT_TRUE(g.contains(p));
  const Scalar2 d = g.distance(p);
  for (int a = 0; a < 3; ++a) {
    Vec3 e = Vec3::Zero();
    e(a) = 1e-5;
    const Scalar2 plus = g.distance(p + e), minus = g.distance(p - e);
    EXPECT_NEAR(d.g(a), (plus.v - minus.v) / 2e-5, 1e-6);
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(d.h(a, b), (plus.g(b) - minus.g(b)) / 2e-5, 1e-3);
  }
  for (const char* bad : {"geometry: {shape: mesh, file: sphere.ply, distance_cells: 24}\n",
                          "geometry: {shape: mesh, file: sphere.ply, distance: smooth, distance_cells: 2}\n",
                          "geometry: {shape: mesh, file: sphere.ply, distance: smoothest}\n"}) {
    try {
      (void)read_geometry(io::parse_config(bad, "t.yaml").child("geometry"), kMeshes);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("t.yaml:1:"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace nfield::solvers::geometry
