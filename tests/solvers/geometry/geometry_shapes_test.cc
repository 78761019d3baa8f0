// SPDX-License-Identifier: MIT
//
// solvers/geometry: every primitive's inside test, boundary points and normals against closed
// forms, placed (rotated, scaled, translated) and combined shapes likewise; volumes and
// boundary measures against exact values within 4 Monte Carlo standard errors (a chance
// failure has probability 6·10⁻⁵ per check; the seeds are fixed); uniform boundary sampling by
// a chi-square test over arc length (threshold: the 99.9 % quantile).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "solvers/geometry/geometry.h"
#include "solvers/geometry/polygon.h"
#include "solvers/geometry/primitives.h"

namespace nfield::solvers::geometry {
namespace {
constexpr double kPi = std::numbers::pi;

ShapeTree leaf(std::unique_ptr<Primitive> p, std::string name = "") {
  return ShapeTree::primitive(std::move(name), std::move(p));
}
std::vector<ShapeTree> list(ShapeTree a, ShapeTree b) {
  std::vector<ShapeTree> v;
  v.push_back(std::move(a));
  v.push_back(std::move(b));
  return v;
}

Eigen::MatrixXd l_shape_vertices() {  // (−1, 1)² ∖ [0, 1) × (−1, 0], given clockwise
  Eigen::MatrixXd v(6, 2);
  v << -1, 1, 1, 1, 1, 0, 0, 0, 0, -1, -1, -1;
  return v;
}

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}

// A primitive with its closed forms: the signed distance (negative inside) or another function
// that is 0 exactly on the boundary, and the outward normal at a boundary point.
struct Case {
  std::string name;
  std::function<std::unique_ptr<Primitive>()> make;
  std::function<double(const Vec3&)> level;  // < 0 inside, 0 on the boundary
  std::function<Vec3(const Vec3&)> normal;
  double volume, boundary;  // boundary NaN: computed by the test
  // Within 10⁻² of where the R-functions' operands vanish together (a polygon's vertices, the
  // capsule's tube–cap seams), where ψ is 0 but its normalisation degrades (R0's corners).
  std::function<bool(const Vec3&)> near_corner = [](const Vec3&) { return false; };
};

std::vector<Case> cases() {
  std::vector<Case> c;
  const Vec3 dc(0.2, -0.1, 0);
  c.push_back({"disk", [=] { return std::make_unique<Ball>(2, dc, 0.7); },
               [=](const Vec3& x) { return (x - dc).norm() - 0.7; }, [=](const Vec3& x) { return Vec3((x - dc) / 0.7); },
               kPi * 0.49, 2 * kPi * 0.7});
  const Vec3 bc(0.1, 0.2, -0.3);
  c.push_back({"ball", [=] { return std::make_unique<Ball>(3, bc, 0.6); },
               [=](const Vec3& x) { return (x - bc).norm() - 0.6; }, [=](const Vec3& x) { return Vec3((x - bc) / 0.6); },
               4.0 / 3 * kPi * 0.216, 4 * kPi * 0.36});
  const Vec3 ea(1.2, 0.5, 1), ea3(1.0, 0.6, 0.4);
  c.push_back({"ellipse", [=] { return std::make_unique<Ellipsoid>(2, Vec3::Zero(), ea); },
               [=](const Vec3& x) { return std::pow(x(0) / ea(0), 2) + std::pow(x(1) / ea(1), 2) - 1; },
               [=](const Vec3& x) { return Vec3(Vec3(x(0) / (ea(0) * ea(0)), x(1) / (ea(1) * ea(1)), 0).normalized()); },
               kPi * 0.6, std::nan("")});
  c.push_back({"ellipsoid", [=] { return std::make_unique<Ellipsoid>(3, Vec3::Zero(), ea3); },
               [=](const Vec3& x) { return x.cwiseQuotient(ea3).squaredNorm() - 1; },
               [=](const Vec3& x) { return Vec3(x.cwiseQuotient(ea3.cwiseProduct(ea3)).normalized()); },
               4.0 / 3 * kPi * 0.24, std::nan("")});
  const auto box_level = [](const Vec3& lo, const Vec3& hi, int dim) {
    return [=](const Vec3& x) {
      double inside = -1e300, outside = 0;
      for (int a = 0; a < dim; ++a) {
        const double q = std::max(lo(a) - x(a), x(a) - hi(a));
        inside = std::max(inside, q);
        outside += std::pow(std::max(q, 0.0), 2);
      }
      return inside > 0 ? std::sqrt(outside) : inside;
    };
  };
  const auto box_normal = [](const Vec3& lo, const Vec3& hi, int dim) {
    return [=](const Vec3& x) {
      Vec3 n = Vec3::Zero();
      for (int a = 0; a < dim; ++a) {
        if (std::abs(x(a) - lo(a)) < 1e-12) n(a) = -1;
        if (std::abs(x(a) - hi(a)) < 1e-12) n(a) = 1;
      }
      return n;
    };
  };
  const Vec3 lo2(-1, 0, 0), hi2(2, 0.5, 0), lo3(-1, -0.5, 0), hi3(0.5, 0.5, 2);
  c.push_back({"box2", [=] { return std::make_unique<Box>(2, lo2, hi2); }, box_level(lo2, hi2, 2), box_normal(lo2, hi2, 2),
               1.5, 7});
  c.push_back({"box3", [=] { return std::make_unique<Box>(3, lo3, hi3); }, box_level(lo3, hi3, 3), box_normal(lo3, hi3, 3),
               3, 2 * (1.5 + 3 + 2)});
  const Vec3 cc(0, 0, 1);
  c.push_back({"cylinder", [=] { return std::make_unique<Cylinder>(cc, 0.5, 2); },
               [=](const Vec3& x) {
                 const double r = (x - cc).head<2>().norm() - 0.5, z = std::abs(x(2) - cc(2)) - 1;
                 return std::max(r, z) > 0 ? std::hypot(std::max(r, 0.0), std::max(z, 0.0)) : std::max(r, z);
               },
               [=](const Vec3& x) {
                 if (std::abs(std::abs(x(2) - cc(2)) - 1) < 1e-12) return Vec3(0, 0, x(2) > cc(2) ? 1 : -1);
                 return Vec3(Vec3(x(0), x(1), 0).normalized());
               },
               kPi * 0.25 * 2, 2 * kPi * 0.5 * 2 + 2 * kPi * 0.25});
  for (int dim : {2, 3}) {
    const Vec3 a(-0.5, 0, 0), b = dim == 2 ? Vec3(0.5, 0.3, 0) : Vec3(0.5, 0.3, -0.2);
    const double r = 0.25, l = (b - a).norm();
    c.push_back({"capsule" + std::to_string(dim), [=] { return std::make_unique<Capsule>(dim, a, b, r); },
                 [=](const Vec3& x) { return segment_distance(x, a, b) - r; },
                 [=](const Vec3& x) {
                   const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
                   return Vec3((x - (a + t * (b - a))).normalized());
                 },
                 dim == 2 ? 2 * r * l + kPi * r * r : kPi * r * r * l + 4.0 / 3 * kPi * r * r * r,
                 dim == 2 ? 2 * l + 2 * kPi * r : 2 * kPi * r * l + 4 * kPi * r * r,
                 [=](const Vec3& x) {
                   const double s = (x - a).dot(b - a) / l;
                   return std::abs(s) < 1e-2 || std::abs(s - l) < 1e-2;
                 }});
  }
  c.push_back({"polygon", [] { return std::make_unique<Polygon>(l_shape_vertices()); },
               [](const Vec3& x) {
                 const Eigen::MatrixXd v = l_shape_vertices();
                 double d = 1e300;
                 for (int i = 0; i < 6; ++i)
                   d = std::min(d, segment_distance(x, Vec3(v(i, 0), v(i, 1), 0), Vec3(v((i + 1) % 6, 0), v((i + 1) % 6, 1), 0)));
                 const bool in = std::abs(x(0)) <= 1 && std::abs(x(1)) <= 1 && !(x(0) > 0 && x(1) < 0);
                 return in ? -d : d;
               },
               [](const Vec3& x) {
                 const Eigen::MatrixXd v = l_shape_vertices();  // clockwise: outward = edge turned left
                 int best = 0;
                 double d = 1e300;
                 for (int i = 0; i < 6; ++i) {
                   const double e = segment_distance(x, Vec3(v(i, 0), v(i, 1), 0), Vec3(v((i + 1) % 6, 0), v((i + 1) % 6, 1), 0));
                   if (e < d) d = e, best = i;
                 }
                 const Eigen::Vector2d t = (v.row((best + 1) % 6) - v.row(best)).normalized();
                 return Vec3(-t(1), t(0), 0);
               },
               3, 8, [](const Vec3& x) {
                 const Eigen::MatrixXd v = l_shape_vertices();
                 for (int i = 0; i < 6; ++i)
                   if (std::hypot(x(0) - v(i, 0), x(1) - v(i, 1)) < 1e-2) return true;
                 return false;
               }});
  return c;
}

Vec3 row3(const Eigen::MatrixXd& m, Eigen::Index r) {
  Vec3 x = Vec3::Zero();
  x.head(m.cols()) = m.row(r).transpose();
  return x;
}

// Central differences of ψ's value (for the gradient) and gradient (for the Hessian).
void expect_derivatives(const std::function<Scalar2(const Vec3&)>& f, const Vec3& x, int dim, const std::string& what) {
  const Scalar2 s = f(x);
  const double h = 1e-5;
  for (int a = 0; a < dim; ++a) {
    Vec3 e = Vec3::Zero();
    e(a) = h;
    const Scalar2 p = f(x + e), m = f(x - e);
    const double g = (p.v - m.v) / (2 * h);
    EXPECT_NEAR(s.g(a), g, 1e-6 * (1 + std::abs(g))) << what << " ∂" << a << " at " << x.transpose();
    for (int b = 0; b < dim; ++b) {
      const double hab = (p.g(b) - m.g(b)) / (2 * h);
      EXPECT_NEAR(s.h(a, b), hab, 2e-5 * (1 + std::abs(hab))) << what << " ∂" << a << "∂" << b << " at " << x.transpose();
    }
  }
}

TEST(GeometryPrimitives, InsideTestsMatchClosedForms) {
  for (const Case& c : cases()) {
    Geometry g(leaf(c.make()));
    const Bounds b = g.bounds();
    Random rng(3);
    int checked = 0, inside = 0;
    for (int k = 0; k < 20000; ++k) {
      Vec3 x = Vec3::Zero();
      for (int a = 0; a < g.dim(); ++a) {
        const double pad = 0.1 * (b.upper(a) - b.lower(a));
        x(a) = b.lower(a) - pad + (b.upper(a) - b.lower(a) + 2 * pad) * uniform01(rng);
      }
      if (std::abs(c.level(x)) < 1e-9) continue;
      ASSERT_EQ(g.contains(x), c.level(x) < 0) << c.name << " at " << x.transpose();
      ++checked;
      inside += c.level(x) < 0;
    }
    EXPECT_GT(inside, 1000) << c.name;
    EXPECT_GT(checked - inside, 1000) << c.name;
  }
}

TEST(GeometryPrimitives, BoundaryPointsNormalsAndDistanceNormalisation) {
  for (const Case& c : cases()) {
    Geometry g(leaf(c.make()));
    Random rng(5);
    const BoundarySample s = g.sample_boundary(rng, 2000);
    for (Eigen::Index r = 0; r < s.points.rows(); ++r) {
      const Vec3 p = row3(s.points, r), n = row3(s.normals, r);
      ASSERT_NEAR(c.level(p), 0, 1e-12) << c.name << " at " << p.transpose();
      ASSERT_NEAR(n.dot(c.normal(p)), 1, 1e-9) << c.name << " at " << p.transpose();
      EXPECT_EQ(s.parts(r), 0);
      const double eps = 1e-8;
      EXPECT_TRUE(g.contains(p - eps * n)) << c.name;
      EXPECT_FALSE(g.contains(p + eps * n)) << c.name;
      // ψ = 0 on ∂Ω, and ψ(p − εn) = ε (1 + O(ε/δ)), δ the distance to a corner (R-equivalence
      // at a polygon's vertex): normalised to first order, positive inside.
      EXPECT_NEAR(g.distance(p).v, 0, 1e-9) << c.name;
      if (!c.near_corner(p))
        EXPECT_NEAR(g.distance(p - eps * n).v / eps, 1, 1e-4) << c.name << " at " << p.transpose();
    }
  }
}

TEST(GeometryPrimitives, VolumesAndBoundaryMeasuresAgainstExactValues) {
  for (const Case& c : cases()) {
    Geometry g(leaf(c.make()));
    const Measure v = g.volume();
    EXPECT_TRUE(v.exact) << c.name;
    EXPECT_NEAR(v.value, c.volume, 1e-12 * c.volume) << c.name;
    // The same through the Monte Carlo path: the shape cut by a box that holds it.
    const Bounds b = g.bounds();
    const Vec3 pad = Vec3::Constant(0.5);
    std::vector<ShapeTree> ops = list(leaf(c.make(), "p"), leaf(std::make_unique<Box>(g.dim(), b.lower - pad, b.upper + pad)));
    Geometry cut(ShapeTree::combine(Combine::kIntersection, std::move(ops)));
    const Measure mc = cut.volume(1 << 17, 11);
    EXPECT_FALSE(mc.exact);
    EXPECT_NEAR(mc.value, c.volume, 4 * mc.std_error) << c.name;
    const Measure mb = cut.boundary_measure(cut.select({"p"}), 1 << 17, 13);
    double exact_boundary = c.boundary;
    if (std::isnan(exact_boundary) && g.dim() == 2) {  // the ellipse's perimeter by quadrature
      exact_boundary = 0;
      const int m = 200000;
      for (int k = 0; k < m; ++k) {
        const double t = 2 * kPi * (k + 0.5) / m;
        exact_boundary += std::hypot(1.2 * std::sin(t), 0.5 * std::cos(t)) * 2 * kPi / m;
      }
    }
    if (std::isnan(exact_boundary)) continue;  // the ellipsoid: no closed form
    EXPECT_NEAR(mb.value, exact_boundary, 4 * mb.std_error + 1e-12) << c.name;
    if (!std::isnan(c.boundary)) EXPECT_NEAR(g.boundary_measure().value, c.boundary, 1e-12 * c.boundary) << c.name;
  }
}

TEST(GeometryPrimitives, DistanceDerivativesMatchCentralDifferences) {
  for (const Case& c : cases()) {
    Geometry g(leaf(c.make()));
    Random rng(7);
    const Eigen::MatrixXd x = g.sample_interior(rng, 40);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      const Vec3 p = row3(x, r);
      if (g.distance(p).v < 1e-2) continue;  // R0 corners lie on the boundary
      expect_derivatives([&](const Vec3& q) { return g.distance(q); }, p, g.dim(), c.name);
    }
  }
}

// The ellipse keeps proposals with w < 1; the L-shape and the capsule pick among pieces.
TEST(GeometryPrimitives, BoundaryPointsUniformInArcLength) {
  const auto chi_square = [](const std::vector<int>& counts, double n) {
    double chi = 0;
    for (int k : counts) chi += std::pow(k - n / counts.size(), 2) / (n / counts.size());
    return chi;
  };
  constexpr int kBins = 20, kPoints = 40000;
  constexpr double kQuantile = 43.82;  // χ² with 19 degrees of freedom, 99.9 %
  {
    Geometry g(leaf(std::make_unique<Ellipsoid>(2, Vec3::Zero(), Vec3(1.2, 0.5, 1))));
    std::vector<double> arc(100001, 0.0);
    for (size_t k = 1; k < arc.size(); ++k) {
      const double t = 2 * kPi * (k - 0.5) / 100000;
      arc[k] = arc[k - 1] + std::hypot(1.2 * std::sin(t), 0.5 * std::cos(t)) * 2 * kPi / 100000;
    }
    Random rng(17);
    const BoundarySample s = g.sample_boundary(rng, kPoints);
    std::vector<int> counts(kBins, 0);
    for (Eigen::Index r = 0; r < kPoints; ++r) {
      double t = std::atan2(s.points(r, 1) / 0.5, s.points(r, 0) / 1.2);
      if (t < 0) t += 2 * kPi;
      const double length = arc[static_cast<size_t>(t / (2 * kPi) * 100000)];
      ++counts[std::min(kBins - 1, static_cast<int>(length / arc.back() * kBins))];
    }
    EXPECT_LT(chi_square(counts, kPoints), kQuantile) << "ellipse";
  }
  {
    Geometry g(leaf(std::make_unique<Polygon>(l_shape_vertices())));
    const Eigen::MatrixXd v = l_shape_vertices().colwise().reverse();  // counter-clockwise
    Random rng(19);
    const BoundarySample s = g.sample_boundary(rng, kPoints);
    std::vector<int> counts(kBins, 0);
    for (Eigen::Index r = 0; r < kPoints; ++r) {
      const Vec3 p = row3(s.points, r);
      double before = 0, length = -1;
      for (int i = 0; i < 6 && length < 0; ++i) {
        const Vec3 a(v(i, 0), v(i, 1), 0), b(v((i + 1) % 6, 0), v((i + 1) % 6, 1), 0);
        if (segment_distance(p, a, b) < 1e-12) length = before + (p - a).norm();
        before += (b - a).norm();
      }
      ASSERT_GE(length, 0);
      ++counts[std::min(kBins - 1, static_cast<int>(length / 8 * kBins))];
    }
    EXPECT_LT(chi_square(counts, kPoints), kQuantile) << "L-shape";
  }
  {
    // The ball's surface: z is uniform on [−r, r] (Archimedes).
    Geometry g(leaf(std::make_unique<Ball>(3, Vec3::Zero(), 1.0)));
    Random rng(23);
    const BoundarySample s = g.sample_boundary(rng, kPoints);
    std::vector<int> counts(kBins, 0);
    for (Eigen::Index r = 0; r < kPoints; ++r) ++counts[std::min(kBins - 1, static_cast<int>((s.points(r, 2) + 1) / 2 * kBins))];
    EXPECT_LT(chi_square(counts, kPoints), kQuantile) << "sphere";
  }
}

TEST(GeometryPlacement, RotatedScaledTranslatedBox) {
  Similarity m;
  m.scale = 2;
  m.rotation = Similarity::rotation_2d(30);
  m.translation = Vec3(1, -1, 0);
  Geometry g(leaf(std::make_unique<Box>(2, Vec3(0, 0, 0), Vec3(1, 2, 0))).place(m));
  EXPECT_NEAR(g.volume().value, 8, 1e-12);
  EXPECT_NEAR(g.boundary_measure().value, 12, 1e-12);
  Random rng(29);
  for (int k = 0; k < 5000; ++k) {
    const Vec3 x(-4 + 8 * uniform01(rng), -3 + 8 * uniform01(rng), 0);
    const Vec3 local = m.rotation.transpose() * (x - m.translation) / 2;
    EXPECT_EQ(g.contains(x), local(0) >= 0 && local(0) <= 1 && local(1) >= 0 && local(1) <= 2);
  }
  const BoundarySample s = g.sample_boundary(rng, 1000);
  const double c = std::cos(kPi / 6), sn = std::sin(kPi / 6);
  for (Eigen::Index r = 0; r < s.points.rows(); ++r) {
    const Vec3 n = row3(s.normals, r), local = m.rotation.transpose() * (row3(s.points, r) - m.translation) / 2;
    // The normal is a rotated axis: ±(cos 30°, sin 30°) or ±(−sin 30°, cos 30°), by the face.
    const Vec3 expected = std::abs(local(0)) < 1e-12 ? Vec3(-c, -sn, 0)
                          : std::abs(local(0) - 1) < 1e-12 ? Vec3(c, sn, 0)
                          : std::abs(local(1)) < 1e-12 ? Vec3(sn, -c, 0)
                                                       : Vec3(-sn, c, 0);
    EXPECT_NEAR((n - expected).norm(), 0, 1e-12);
  }
  // ψ in world coordinates stays normalised (× s) and its derivatives exact.
  const Vec3 centre = m.apply(Vec3(0.5, 1, 0));
  EXPECT_NEAR(g.distance(centre).v, 2 * (0.25 + 0.5 - std::sqrt(0.25 * 0.25 + 0.25)), 1e-12);
  expect_derivatives([&](const Vec3& q) { return g.distance(q); }, centre + Vec3(0.1, 0.2, 0), 2, "placed box");
}

// A square plate with four holes: difference(square, union(disks)).
Geometry plate() {
  std::vector<ShapeTree> holes;
  int k = 1;
  for (double x : {-0.5, 0.5})
    for (double y : {-0.5, 0.5}) holes.push_back(leaf(std::make_unique<Ball>(2, Vec3(x, y, 0), 0.2), "hole" + std::to_string(k++)));
  return Geometry(ShapeTree::combine(
      Combine::kDifference, list(leaf(std::make_unique<Box>(2, Vec3(-1, -1, 0), Vec3(1, 1, 0)), "outer"),
                                 ShapeTree::combine(Combine::kUnion, std::move(holes)))));
}

TEST(GeometryCombined, PlateWithHoles) {
  const Geometry g = plate();
  ASSERT_EQ(g.part_count(), 5);
  EXPECT_EQ(g.part("HOLE3"), 3);
  const Measure v = g.volume(1 << 17);
  EXPECT_NEAR(v.value, 4 - 4 * kPi * 0.04, 4 * v.std_error);
  EXPECT_LT(v.std_error, 5e-3);
  const Measure b = g.boundary_measure({}, 1 << 17);
  EXPECT_NEAR(b.value, 8 + 4 * 2 * kPi * 0.2, 4 * b.std_error);
  Random rng(31);
  const Eigen::MatrixXd x = g.sample_interior(rng, 4000);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Vec3 p = row3(x, r);
    ASSERT_TRUE(std::abs(p(0)) <= 1 && std::abs(p(1)) <= 1);
    for (double cx : {-0.5, 0.5})
      for (double cy : {-0.5, 0.5}) ASSERT_GT(std::hypot(p(0) - cx, p(1) - cy), 0.2);
  }
  // Points per part ∝ its length: 8 for the square, 0.4π per hole (χ², 4 dof, 99.9 %: 18.47).
  const int n = 40000;
  const BoundarySample s = g.sample_boundary(rng, n);
  std::vector<int> counts(5, 0);
  for (Eigen::Index r = 0; r < n; ++r) {
    const Vec3 p = row3(s.points, r), nn = row3(s.normals, r);
    ++counts[static_cast<size_t>(s.parts(r))];
    if (s.parts(r) > 0) {  // a hole: the normal points into it (out of the plate)
      const Vec3 c(s.parts(r) <= 2 ? -0.5 : 0.5, s.parts(r) % 2 == 1 ? -0.5 : 0.5, 0);
      ASSERT_NEAR((p - c).norm(), 0.2, 1e-12);
      ASSERT_NEAR(nn.dot((c - p) / 0.2), 1, 1e-12);
    }
  }
  const double total = 8 + 4 * 0.4 * kPi;
  double chi = 0;
  for (int k = 0; k < 5; ++k) {
    const double expected = n * (k == 0 ? 8 : 0.4 * kPi) / total;
    chi += std::pow(counts[static_cast<size_t>(k)] - expected, 2) / expected;
  }
  EXPECT_LT(chi, 18.47);
}

TEST(GeometryCombined, UnionAndIntersectionOfTwoDisks) {
  const auto disks = [] {
    return list(leaf(std::make_unique<Ball>(2, Vec3(-0.5, 0, 0), 1.0), "left"),
                leaf(std::make_unique<Ball>(2, Vec3(0.5, 0, 0), 1.0), "right"));
  };
  const double lens = 2 * kPi / 3 - std::sqrt(3.0) / 2;
  Geometry u(ShapeTree::combine(Combine::kUnion, disks()));
  Geometry i(ShapeTree::combine(Combine::kIntersection, disks()));
  const Measure vu = u.volume(1 << 17), vi = i.volume(1 << 17);
  EXPECT_NEAR(vu.value, 2 * kPi - lens, 4 * vu.std_error);
  EXPECT_NEAR(vi.value, lens, 4 * vi.std_error);
  const Measure bu = u.boundary_measure({}, 1 << 17), bi = i.boundary_measure({}, 1 << 17);
  EXPECT_NEAR(bu.value, 8 * kPi / 3, 4 * bu.std_error);
  EXPECT_NEAR(bi.value, 4 * kPi / 3, 4 * bi.std_error);
  Random rng(37);
  const BoundarySample su = u.sample_boundary(rng, 3000), si = i.sample_boundary(rng, 3000);
  for (Eigen::Index r = 0; r < 3000; ++r) {
    const Vec3 p = row3(su.points, r), q = row3(si.points, r);
    // Union: each point outside the other disk; intersection: inside it.
    const Vec3 other_u(su.parts(r) == 0 ? 0.5 : -0.5, 0, 0), other_i(si.parts(r) == 0 ? 0.5 : -0.5, 0, 0);
    ASSERT_GE((p - other_u).norm(), 1 - 1e-12);
    ASSERT_LE((q - other_i).norm(), 1 + 1e-12);
    // ψ of the combined domain vanishes there, and is normalised.
    EXPECT_NEAR(u.distance(p).v, 0, 1e-12);
    EXPECT_NEAR(i.distance(q).v, 0, 1e-12);
  }
}

TEST(GeometryCombined, BoxWithABoreIn3D) {
  std::vector<ShapeTree> ops = list(leaf(std::make_unique<Box>(3, Vec3(-1, -1, -1), Vec3(1, 1, 1)), "block"),
                                    leaf(std::make_unique<Cylinder>(Vec3::Zero(), 0.3, 3), "bore"));
  Geometry g(ShapeTree::combine(Combine::kDifference, std::move(ops)));
  const Measure v = g.volume(1 << 17);
  EXPECT_NEAR(v.value, 8 - 0.18 * kPi, 4 * v.std_error);
  const Measure b = g.boundary_measure({}, 1 << 17);
  EXPECT_NEAR(b.value, 24 - 0.18 * kPi + 1.2 * kPi, 4 * b.std_error);
  // Only the bore's side survives, its normals pointing at the axis.
  Random rng(41);
  const BoundarySample s = g.sample_boundary(rng, 2000, g.select({"bore"}));
  for (Eigen::Index r = 0; r < s.points.rows(); ++r) {
    const Vec3 p = row3(s.points, r);
    ASSERT_EQ(s.parts(r), 1);
    ASSERT_LE(std::abs(p(2)), 1 + 1e-12);
    ASSERT_NEAR(row3(s.normals, r).dot(-Vec3(p(0), p(1), 0) / 0.3), 1, 1e-12);
  }
}

// The boundary quadrature: Σ w = |∂Ω| and, by the divergence theorem, Σ w (x·n)/d = |Ω|.
// x·n is linear on faces and edges and a trigonometric polynomial of degree 1 on circles and
// spheres (in the azimuth; the sphere's z = 1 − 2u is linear), so the midpoint rules are exact
// to rounding there; on the 2-D capsule's half circles (not periodic) the rule is O(h²); the
// ellipse(oid)'s weighted rule is smooth, spectral in 2-D.
struct QuadratureSums {
  double measure = 0, divergence = 0;
};
QuadratureSums quadrature_sums(const Geometry& g, const Selection& s, Eigen::Index n) {
  const BoundaryQuadrature q = g.boundary_quadrature(s, n);
  QuadratureSums sums;
  for (Eigen::Index i = 0; i < q.weights.size(); ++i) {
    sums.measure += q.weights(i);
    sums.divergence += q.weights(i) * q.points.row(i).dot(q.normals.row(i)) / g.dim();
  }
  return sums;
}

TEST(GeometryQuadrature, EveryPrimitiveIntegratesItsMeasureAndVolume) {
  for (const Case& c : cases()) {
    // Placed, so the map's scale and rotation enter the weights and normals.
    Similarity map;
    map.scale = 1.3;
    map.rotation = c.make()->dim() == 2 ? Similarity::rotation_2d(25) : Similarity::rotation_3d(Vec3(10, 20, 30));
    map.translation = Vec3(0.3, -0.2, c.make()->dim() == 3 ? 0.1 : 0);
    Geometry g(leaf(c.make()).place(map));
    const double v = c.volume * std::pow(1.3, g.dim());
    const QuadratureSums sums = quadrature_sums(g, {}, 1 << 14);
    const bool smooth_only = c.name == "ellipse" || c.name == "ellipsoid";
    const double tolerance = c.name == "ellipsoid" ? 1e-4 : c.name == "capsule2" ? 1e-7 : 1e-10;
    EXPECT_NEAR(sums.divergence, v, tolerance * v) << c.name;
    if (!smooth_only) EXPECT_NEAR(sums.measure, c.boundary * std::pow(1.3, g.dim() - 1), 1e-10 * c.boundary) << c.name;
  }
}

TEST(GeometryQuadrature, PartsOfACombinedDomain) {
  const Geometry g = plate();
  const QuadratureSums all = quadrature_sums(g, {}, 1 << 14);
  EXPECT_NEAR(all.measure, 8 + 4 * 2 * kPi * 0.2, 1e-10);
  EXPECT_NEAR(all.divergence, 4 - 4 * kPi * 0.04, 1e-10);
  // One hole: its length, and its normals (into the hole) sum to 0 round the closed curve.
  const BoundaryQuadrature hole = g.boundary_quadrature(g.select({"hole3"}), 1000);
  ASSERT_GT(hole.weights.size(), 900);
  EXPECT_NEAR(hole.weights.sum(), 0.4 * kPi, 1e-12);
  EXPECT_NEAR((hole.normals.transpose() * hole.weights).norm(), 0, 1e-12);
  EXPECT_TRUE((hole.parts.array() == 3).all());
  // A trimmed boundary (the union of two disks): the cut is resolved to one cell, so the
  // error is O(1/n) and falls as n grows.
  Geometry u(ShapeTree::combine(Combine::kUnion, list(leaf(std::make_unique<Ball>(2, Vec3(-0.5, 0, 0), 1.0)),
                                                      leaf(std::make_unique<Ball>(2, Vec3(0.5, 0, 0), 1.0)))));
  const double area = 2 * kPi - (2 * kPi / 3 - std::sqrt(3.0) / 2);
  // Bound: four cuts, each off by at most one cell (4π/n of arc) times the largest integrand,
  // 1 + |x·n|/2 ≤ 1.75.
  double previous = 1;
  for (Eigen::Index n : {1 << 10, 1 << 13, 1 << 16}) {
    const QuadratureSums sums = quadrature_sums(u, {}, n);
    const double error = std::abs(sums.divergence - area) + std::abs(sums.measure - 8 * kPi / 3);
    EXPECT_LT(error, 4 * (4 * kPi / static_cast<double>(n)) * 1.75) << n;
    EXPECT_LT(error, previous / 4) << n;  // n grows 8×
    previous = error;
  }
}

TEST(GeometryParts, SelectionsGetOnlyTheirOwnPoints) {
  const Geometry g = plate();
  Random rng(43);
  const BoundarySample holes = g.sample_boundary(rng, 2000, g.select({"hole1", "hole4"}));
  for (Eigen::Index r = 0; r < holes.points.rows(); ++r) ASSERT_TRUE(holes.parts(r) == 1 || holes.parts(r) == 4);
  const BoundarySample left = g.sample_boundary(rng, 2000, g.select({"boundary"}, "x < -0.99"));
  for (Eigen::Index r = 0; r < left.points.rows(); ++r) {
    ASSERT_EQ(left.parts(r), 0);
    ASSERT_LT(left.points(r, 0), -0.99);
  }
  EXPECT_NEAR(g.boundary_measure(g.select({"outer"}, "x < -0.99")).value, 2.0 + 2 * 0.01, 0.05);
  try {
    g.select({"hole9"});
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown part 'hole9' (parts: outer, hole1, hole2, hole3, hole4"), std::string::npos)
        << e.what();
  }
}

// φ vanishing on the holes only: 0 there, positive inside and on the outer square, normalised,
// and with derivatives that match central differences.
TEST(GeometryDistance, SelectedPartsOfACombinedDomain) {
  const Geometry g = plate();
  const Selection holes = g.select({"hole1", "hole2", "hole3", "hole4"});
  Random rng(47);
  const BoundarySample on = g.sample_boundary(rng, 500, holes);
  for (Eigen::Index r = 0; r < on.points.rows(); ++r) {
    const Vec3 p = row3(on.points, r), n = row3(on.normals, r);
    EXPECT_NEAR(g.distance(p, holes).v, 0, 1e-10);
    EXPECT_NEAR(g.distance(p - 1e-6 * n, holes).v / 1e-6, 1, 1e-3);
  }
  const BoundarySample outer = g.sample_boundary(rng, 500, g.select({"outer"}));
  for (Eigen::Index r = 0; r < outer.points.rows(); ++r) EXPECT_GT(g.distance(row3(outer.points, r), holes).v, 1e-3);
  const Eigen::MatrixXd x = g.sample_interior(rng, 60);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Vec3 p = row3(x, r);
    EXPECT_GT(g.distance(p, holes).v, 0);
    if (g.distance(p).v < 1e-2) continue;
    expect_derivatives([&](const Vec3& q) { return g.distance(q, holes); }, p, 2, "holes");
    expect_derivatives([&](const Vec3& q) { return g.distance(q); }, p, 2, "plate");
  }
  // The union of two disks with φ = 0 on the right one's surviving arc only: trimmed.
  Geometry u(ShapeTree::combine(Combine::kUnion, list(leaf(std::make_unique<Ball>(2, Vec3(-0.5, 0, 0), 1.0), "left"),
                                                      leaf(std::make_unique<Ball>(2, Vec3(0.5, 0, 0), 1.0), "right"))));
  const Selection right = u.select({"right"});
  // The right circle's arc inside the left disk is no boundary: φ > 0 there.
  EXPECT_GT(u.distance(Vec3(0.5 + std::cos(2.5), std::sin(2.5), 0), right).v, 1e-2);
  EXPECT_NEAR(u.distance(Vec3(1.5, 0, 0), right).v, 0, 1e-12);
  const Eigen::MatrixXd y = u.sample_interior(rng, 40);
  for (Eigen::Index r = 0; r < y.rows(); ++r) {
    const Vec3 p = row3(y, r);
    EXPECT_GT(u.distance(p, right).v, 0);
    if (u.distance(p).v < 1e-2) continue;
    expect_derivatives([&](const Vec3& q) { return u.distance(q, right); }, p, 2, "trimmed arc");
  }
}

// With a sobol sequence attached, rejection consumes a varying number of sequence points but
// stays a function of the seed: two engines with one seed draw the same points.
TEST(GeometrySampling, QuasiRandomPointsAreReproducibleAndInside) {
  const Geometry g = plate();
  Eigen::MatrixXd first, again;
  BoundarySample b1, b2;
  for (Eigen::MatrixXd* out : {&first, &again}) {
    Random rng(53);
    UnitSequence sobol("sobol", 53);
    AttachSequence attach(rng, &sobol);
    *out = g.sample_interior(rng, 1000);
    (out == &first ? b1 : b2) = g.sample_boundary(rng, 500);
  }
  EXPECT_EQ(first, again);
  EXPECT_EQ(b1.points, b2.points);
  EXPECT_TRUE(g.contains_rows(first).all());
  // Even coverage: the share of points in the left half is within 1 % of its area share.
  const double left = (first.col(0).array() < 0).cast<double>().mean();
  EXPECT_NEAR(left, 0.5, 0.01);
}

TEST(GeometryRefusals, BadShapes) {
  EXPECT_THROW(Ball(2, Vec3::Zero(), 0), std::invalid_argument);
  EXPECT_THROW(Box(2, Vec3::Zero(), Vec3(1, 0, 0)), std::invalid_argument);
  Eigen::MatrixXd two(2, 2);
  two << 0, 0, 1, 0;
  EXPECT_THROW(Polygon{two}, std::invalid_argument);
  Eigen::MatrixXd bowtie(4, 2);
  bowtie << 0, 0, 1, 1, 1, 0, 0, 1;
  try {
    Polygon p(bowtie);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("edges 0 (vertices 0–1) and 2 (vertices 2–3) cross"), std::string::npos) << e.what();
  }
  // Shapes of two dimensions, two parts of one name.
  EXPECT_THROW(Geometry(ShapeTree::combine(Combine::kUnion, list(leaf(std::make_unique<Ball>(2, Vec3::Zero(), 1.0)),
                                                                 leaf(std::make_unique<Ball>(3, Vec3::Zero(), 1.0))))),
               std::invalid_argument);
  EXPECT_THROW(Geometry(ShapeTree::combine(Combine::kUnion, list(leaf(std::make_unique<Ball>(2, Vec3::Zero(), 1.0), "a"),
                                                                 leaf(std::make_unique<Ball>(2, Vec3::Zero(), 2.0), "A")))),
               std::invalid_argument);
  // A difference that removes everything: sampling says so.
  Geometry empty(ShapeTree::combine(Combine::kDifference, list(leaf(std::make_unique<Ball>(2, Vec3::Zero(), 1.0)),
                                                                leaf(std::make_unique<Ball>(2, Vec3::Zero(), 2.0)))));
  EXPECT_EQ(empty.volume(1 << 12).value, 0);
  Random rng(1);
  EXPECT_THROW(empty.sample_interior(rng, 10), std::runtime_error);
}

}  // namespace
}  // namespace nfield::solvers::geometry
