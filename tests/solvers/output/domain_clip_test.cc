// SPDX-License-Identifier: MIT
//
// A 2-D grid's triangles clipped to a geometry (solvers/output/domain_clip.h): the mesh's area
// is the domain's exact area up to O(h²) (a disk, whose error must fall ≈ 4× when h halves; a
// plate with four holes; an L-shape on a grid its edges do not follow), every point is inside,
// the crossings lie within the tolerance of ∂Ω, the triangles are counter-clockwise, and the
// mesh is conforming: an edge that only one triangle uses lies on ∂Ω.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <utility>

#include "io/config.h"
#include "solvers/geometry/geometry_config.h"
#include "solvers/output/domain_clip.h"

namespace nfield::solvers {
namespace {

geometry::Geometry read(const std::string& text) {
  const io::ConfigNode root = io::parse_config(text, "geo.yaml");
  return geometry::read_geometry(root.child("geometry"), ".");
}

struct Clipped {
  io::Grid grid;
  ClippedTriangles mesh;
  double tolerance = 0;
};

// The clip of `g` on an n × n grid over [lo, hi]².
Clipped clip(const geometry::Geometry& g, double lo, double hi, int n) {
  Clipped c;
  c.grid = io::make_grid({lo, lo}, {hi, hi}, {n, n});
  Eigen::Array<bool, Eigen::Dynamic, 1> inside(c.grid.point_count());
  for (Eigen::Index p = 0; p < inside.size(); ++p) inside(p) = g.contains(c.grid.point(p));
  c.tolerance = clip_tolerance(c.grid);
  c.mesh = clip_triangles(
      c.grid, inside, [&g](const Eigen::Vector2d& p) { return g.contains(Eigen::Vector3d(p(0), p(1), 0)); },
      c.tolerance);
  return c;
}

double signed_area(const ClippedTriangles& m, Eigen::Index t) {
  const Eigen::Vector2d a = m.points.row(m.triangles(t, 0)), b = m.points.row(m.triangles(t, 1)),
                        c = m.points.row(m.triangles(t, 2));
  return 0.5 * ((b(0) - a(0)) * (c(1) - a(1)) - (b(1) - a(1)) * (c(0) - a(0)));
}

// The mesh's area; every triangle must be counter-clockwise.
double area(const ClippedTriangles& m) {
  double sum = 0;
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t) {
    const double s = signed_area(m, t);
    EXPECT_GT(s, 0) << "triangle " << t;
    sum += s;
  }
  return sum;
}

// Every point inside; every edge used by one triangle only has both ends within `near` of ∂Ω
// (`on_boundary`), so there are no cracks inside the domain.
template <class OnBoundary>
void expect_inside_and_conforming(const geometry::Geometry& g, const Clipped& c, OnBoundary on_boundary) {
  const ClippedTriangles& m = c.mesh;
  for (Eigen::Index p = 0; p < m.points.rows(); ++p)
    ASSERT_TRUE(g.contains(Eigen::Vector3d(m.points(p, 0), m.points(p, 1), 0))) << "point " << p;
  std::map<std::pair<int, int>, int> uses;
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles(t, k), b = m.triangles(t, (k + 1) % 3);
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  int single = 0;
  for (const auto& [edge, count] : uses) {
    ASSERT_LE(count, 2);
    if (count == 2) continue;
    ++single;
    for (const int p : {edge.first, edge.second})
      ASSERT_TRUE(on_boundary(Eigen::Vector2d(m.points.row(p)))) << "edge end " << m.points.row(p);
  }
  EXPECT_GT(single, 0);
}

TEST(DomainClip, DiskAreaConvergesAtSecondOrderAndCrossingsLieOnTheCircle) {
  const geometry::Geometry g = read("geometry: {shape: disk, center: [0.05, 0.03], radius: 0.7}\n");
  const double exact = std::numbers::pi * 0.49;
  double error[2];
  for (int level = 0; level < 2; ++level) {
    const Clipped c = clip(g, -1, 1, level == 0 ? 41 : 81);
    const double h = c.grid.spacing[0];
    error[level] = std::abs(area(c.mesh) - exact);
    // Chords of an arc of radius R: each of length ≤ √2 h misses c³/(12R); summed over the
    // circumference 2πR, at most 2π (√2 h)² / 12 = 1.05 h².
    EXPECT_LT(error[level], 1.05 * h * h) << "h " << h;
    // The crossings on the circle, to the tolerance; the grid points strictly inside.
    const std::vector<Eigen::Index> crossings = c.mesh.crossings();
    ASSERT_GT(crossings.size(), 50u);
    for (const Eigen::Index p : crossings)
      EXPECT_NEAR((c.mesh.points.row(p) - Eigen::RowVector2d(0.05, 0.03)).norm(), 0.7, c.tolerance);
    expect_inside_and_conforming(g, c, [&](const Eigen::Vector2d& p) {
      return std::abs((p - Eigen::Vector2d(0.05, 0.03)).norm() - 0.7) <= c.tolerance;
    });
  }
  EXPECT_GT(error[0] / error[1], 3.0);  // second order: 4 in the limit
}

TEST(DomainClip, PlateWithFourHolesHasItsExactAreaToOrderHSquared) {
  const geometry::Geometry g = read(R"(geometry:
  shape: difference
  shapes:
    - {shape: box, lower: [-1, -1], upper: [1, 1]}
    - {shape: disk, center: [0.5, 0.5], radius: 0.2}
    - {shape: disk, center: [-0.5, 0.5], radius: 0.2}
    - {shape: disk, center: [-0.5, -0.5], radius: 0.2}
    - {shape: disk, center: [0.5, -0.5], radius: 0.2}
)");
  const Clipped c = clip(g, -1, 1, 61);
  const double h = c.grid.spacing[0];
  // The holes' chords cut into the holes: the mesh is larger than the plate by ≤ 4 · 1.05 h².
  const double exact = 4 - 4 * std::numbers::pi * 0.04, a = area(c.mesh);
  EXPECT_GT(a, exact);
  EXPECT_LT(a - exact, 4 * 1.05 * h * h);
  expect_inside_and_conforming(g, c, [&](const Eigen::Vector2d& p) {
    double d = 1 - p.cwiseAbs().maxCoeff();  // to the outer square
    for (const double sx : {-0.5, 0.5})
      for (const double sy : {-0.5, 0.5}) d = std::min(d, std::abs((p - Eigen::Vector2d(sx, sy)).norm() - 0.2));
    return d <= c.tolerance;
  });
}

TEST(DomainClip, LShapeOnAGridItsEdgesDoNotFollow) {
  const geometry::Geometry g =
      read("geometry: {shape: polygon, vertices: [[-1, -1], [0, -1], [0, 0], [1, 0], [1, 1], [-1, 1]]}\n");
  // 47 points over [−1.07, 1.03]: no grid line on an edge of the L, so every edge is cut.
  const Clipped c = clip(g, -1.07, 1.03, 47);
  const double h = c.grid.spacing[0];
  // Straight edges are followed exactly (to the tolerance); each of the six corners changes
  // the area by at most half a cell.
  EXPECT_NEAR(area(c.mesh), 3.0, 6 * 0.5 * h * h);
  expect_inside_and_conforming(g, c, [&](const Eigen::Vector2d& p) {
    const double x = p(0), y = p(1), t = c.tolerance;
    const bool outer = std::abs(std::abs(x) - 1) <= t || std::abs(std::abs(y) - 1) <= t;
    const bool notch = (std::abs(x) <= t && y <= t) || (std::abs(y) <= t && x >= -t);
    return outer || notch;
  });
}

TEST(DomainClip, RefusesA3DGridAndAMaskOfTheWrongSize) {
  const io::Grid cube = io::make_grid({0, 0, 0}, {1, 1, 1}, {3, 3, 3});
  const auto all = [](const Eigen::Vector2d&) { return true; };
  EXPECT_THROW(clip_triangles(cube, Eigen::Array<bool, Eigen::Dynamic, 1>::Ones(27), all, 1e-6),
               std::invalid_argument);
  const io::Grid square = io::make_grid({0, 0}, {1, 1}, {3, 3});
  EXPECT_THROW(clip_triangles(square, Eigen::Array<bool, Eigen::Dynamic, 1>::Ones(8), all, 1e-6),
               std::invalid_argument);
  EXPECT_THROW(clip_triangles(square, Eigen::Array<bool, Eigen::Dynamic, 1>::Ones(9), all, 0), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
