// SPDX-License-Identifier: MIT
//
// `domain.geometry` (solvers/geometry/geometry_config.h): a plate with holes, placements and a
// mesh read from a config; every refused input is one ConfigError at FILE:LINE:COL and key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <ostream>
#include <string>

#include "io/config.h"
#include "solvers/core/domain.h"
#include "solvers/geometry/geometry_config.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers::geometry {
namespace {

Geometry read(const std::string& text, const std::filesystem::path& dir = ".") {
  const io::ConfigNode root = io::parse_config(text, "geo.yaml");
  Geometry g = read_geometry(root.child("geometry"), dir);
  root.reject_unknown_keys_recursive();
  return g;
}

TEST(GeometryConfig, PlateWithHolesAndPlacements) {
  const Geometry g = read(R"(geometry:
  shape: difference
  shapes:
    - {shape: box, name: outer, lower: [-1, -1], upper: [1, 1]}
    - shape: union
      shapes:
        - {shape: disk, name: left, center: [-0.5, 0], radius: 0.2}
        - {shape: ellipse, name: right, center: [0, 0], semi_axes: [0.2, 0.1], rotate: 90, translate: [0.5, 0]}
        - {shape: polygon, name: notch, vertices: [[-0.1, 0.8], [0.1, 0.8], [0, 0.9]], scale: 2}
)");
  ASSERT_EQ(g.part_count(), 4);
  EXPECT_EQ(g.part_name(3), "notch");
  EXPECT_FALSE(g.contains(Vec3(-0.5, 0.1, 0)));
  EXPECT_FALSE(g.contains(Vec3(0.5, 0.15, 0)));  // the rotated ellipse reaches y = ±0.2
  EXPECT_TRUE(g.contains(Vec3(0.5, -0.25, 0)));
  EXPECT_FALSE(g.contains(Vec3(0, 1.7, 0)));      // outside the square
  // The notch, scaled by 2 about the origin, is the triangle (−0.2, 1.6), (0.2, 1.6), (0, 1.8):
  // outside the square, so it removes nothing.
  const Measure v = g.volume(1 << 17);
  EXPECT_NEAR(v.value, 4 - std::numbers::pi * (0.04 + 0.02), 4 * v.std_error);
  const io::ConfigNode cond = io::parse_config("on: [left, RIGHT]\nwhere: 'y > 0'\n", "c.yaml");
  const Selection s = read_selection(cond, g);
  EXPECT_EQ(s.parts, (std::vector<int>{1, 2}));
  ASSERT_TRUE(s.where);
}

TEST(GeometryConfig, MeshAndThreeDimensionalShapes) {
  const auto dir = std::filesystem::path(NFIELD_SOURCE_DIR) / "data";
  const Geometry g = read(R"(geometry:
  shape: intersection
  shapes:
    - {shape: mesh, name: sphere, file: meshes/sphere.ply, scale: 2}
    - {shape: cylinder, name: can, center: [0, 0, 0], radius: 0.5, height: 4, rotate: [90, 0, 0]}
    - {shape: capsule, from: [0, -3, 0], to: [0, 3, 0], radius: 0.6}
)", dir);
  EXPECT_EQ(g.dim(), 3);
  EXPECT_EQ(g.part_name(2), "capsule3");
  EXPECT_TRUE(g.contains(Vec3(0, 0.5, 0)));
  EXPECT_FALSE(g.contains(Vec3(0, 0, 0.55)));  // the can's axis is y after the rotation
}

struct Refusal {
  std::string name, yaml, where, says;
  friend void PrintTo(const Refusal& r, std::ostream* os) { *os << r.name; }
};

class GeometryConfigRefusal : public ::testing::TestWithParam<Refusal> {};

TEST_P(GeometryConfigRefusal, IsALocatedError) {
  const Refusal& r = GetParam();
  const auto dir = testutil::scratch_dir("solvers");
  std::ofstream(dir / "open.off") << "OFF\n7 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n5 5 5\n6 5 5\n5 6 5\n"
                                     "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 4 5 6\n";
  std::ofstream(dir / "bad.ply") << "no ply\n";
  std::ofstream(dir / "two.txt") << "0 0\n1 0\n";
  std::ofstream(dir / "words.txt") << "0 0\n1 zero\n0 1\n";
  try {
    const Geometry g = read(r.yaml, dir);
    const io::ConfigNode cond = io::parse_config("on: hole\n", "c.yaml");
    read_selection(cond, g);
    FAIL() << r.name << ": no error";
  } catch (const io::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(r.where, 0), 0u) << r.name << ": " << what;
    EXPECT_NE(what.find(r.says), std::string::npos) << r.name << ": " << what;
    EXPECT_GT(e.line(), 0) << r.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Inputs, GeometryConfigRefusal,
    ::testing::Values(
        Refusal{"EmptyDifference",
                "geometry:\n  shape: difference\n  shapes:\n    - {shape: disk, center: [0, 0], radius: 1}\n"
                "    - {shape: box, lower: [-2, -2], upper: [2, 2]}\n",
                "geo.yaml:2:3: geometry: ", "the domain is empty"},
        Refusal{"DisjointIntersection",
                "geometry:\n  shape: intersection\n  shapes:\n    - {shape: disk, center: [0, 0], radius: 1}\n"
                "    - {shape: disk, center: [3, 0], radius: 1}\n",
                "geo.yaml:2:3: geometry: ", "the domain is empty"},
        Refusal{"ZeroRadius", "geometry: {shape: disk, center: [0, 0], radius: 0}\n", "geo.yaml:1:49: geometry.radius:",
                "positive"},
        Refusal{"NegativeBox", "geometry: {shape: box, lower: [0, 0], upper: [1, -1]}\n",
                "geo.yaml:1:46: geometry.upper:", "upper[1] must be greater than lower[1]"},
        Refusal{"ZeroHeight", "geometry: {shape: cylinder, center: [0, 0, 0], radius: 1, height: 0}\n",
                "geo.yaml:1:", "geometry.height"},
        Refusal{"NegativeScale", "geometry: {shape: disk, center: [0, 0], radius: 1, scale: -2}\n", "geo.yaml:1:",
                "geometry.scale"},
        Refusal{"NegativeSemiAxis", "geometry: {shape: ellipse, center: [0, 0], semi_axes: [1, -1]}\n",
                "geo.yaml:1:", "geometry.semi_axes: expected positive semi-axes"},
        Refusal{"UnknownPart", "geometry: {shape: disk, name: plate, center: [0, 0], radius: 1}\n", "c.yaml:1:5: on:",
                "unknown part 'hole' (parts: plate; or boundary)"},
        Refusal{"TwoVertices", "geometry:\n  shape: polygon\n  vertices: [[0, 0], [1, 0]]\n",
                "geo.yaml:3:13: geometry.vertices:", "at least 3 vertices, got 2"},
        Refusal{"TwoVerticesInAFile", "geometry: {shape: polygon, file: two.txt}\n", "geo.yaml:1:34: geometry.file:",
                "at least 3 vertices, got 2"},
        Refusal{"WordsInAFile", "geometry: {shape: polygon, file: words.txt}\n", "geo.yaml:1:34: geometry.file:",
                "words.txt:2: expected two numbers"},
        Refusal{"CrossingEdges", "geometry:\n  shape: polygon\n  vertices: [[0, 0], [1, 1], [1, 0], [0, 1]]\n",
                "geo.yaml:3:13: geometry.vertices:", "edges 0 (vertices 0–1) and 2 (vertices 2–3) cross"},
        Refusal{"MissingMesh", "geometry: {shape: mesh, file: nowhere.stl}\n", "geo.yaml:1:31: geometry.file:",
                "no such file"},
        Refusal{"UnreadableMesh", "geometry: {shape: mesh, file: bad.ply}\n", "geo.yaml:1:31: geometry.file:",
                "not a PLY file"},
        Refusal{"OpenMesh", "geometry: {shape: mesh, file: open.off}\n", "geo.yaml:1:31: geometry.file:",
                "not closed: 3 boundary edge(s)"},
        Refusal{"MixedDimensions",
                "geometry:\n  shape: union\n  shapes:\n    - {shape: disk, center: [0, 0], radius: 1}\n"
                "    - {shape: ball, center: [0, 0, 0], radius: 1}\n",
                "geo.yaml:5:7: geometry.shapes[1]:", "a 3-D ball in a 2-D geometry"},
        Refusal{"DuplicateName",
                "geometry:\n  shape: union\n  shapes:\n    - {shape: disk, name: a, center: [0, 0], radius: 1}\n"
                "    - {shape: disk, name: A, center: [1, 0], radius: 1}\n",
                "geo.yaml:5:27: geometry.shapes[1].name:", "a part named 'A' exists already"},
        Refusal{"OneOperand", "geometry:\n  shape: union\n  shapes:\n    - {shape: disk, center: [0, 0], radius: 1}\n",
                "geo.yaml:4:5: geometry.shapes:", "at least two shapes"},
        Refusal{"UnknownShape", "geometry: {shape: torus}\n", "geo.yaml:1:", "expected one of box, disk"},
        Refusal{"UnknownKey", "geometry: {shape: disk, center: [0, 0], radius: 1, radus: 2}\n", "geo.yaml:1:",
                "unknown key 'radus'"},
        Refusal{"EmptyName", "geometry: {shape: disk, name: \"\", center: [0, 0], radius: 1}\n",
                "geo.yaml:1:31: geometry.name:", "expected a part name of letters, digits and '_'"},
        Refusal{"NameNotAnIdentifier", "geometry: {shape: disk, name: \"sin(x\", center: [0, 0], radius: 1}\n",
                "geo.yaml:1:31: geometry.name:", "expected a part name of letters, digits and '_'"},
        // The hole lies inside the larger disk of the union: none of its boundary survives.
        Refusal{"CoveredPart",
                "geometry:\n  shape: union\n  shapes:\n    - {shape: disk, name: big, center: [0, 0], radius: 2}\n"
                "    - {shape: disk, name: hole, center: [0, 0], radius: 1}\n",
                "c.yaml:1:5: on:", "the selected boundary is empty"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return info.param.name; });

TEST(GeometryConfig, BadWhereExpressionIsLocated) {
  const Geometry g = read("geometry: {shape: disk, name: hole, center: [0, 0], radius: 1}\n");
  const io::ConfigNode cond = io::parse_config("on: hole\nwhere: 'x < q'\n", "c.yaml");
  try {
    read_selection(cond, g);
    FAIL();
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("c.yaml:2:", 0), 0u) << e.what();
    EXPECT_EQ(e.key_path(), "where");
  }
}

}  // namespace
}  // namespace nfield::solvers::geometry

namespace nfield::solvers {
namespace {

TEST(GeometryDomain, ADomainHoldsAGeometry) {
  const io::ConfigNode root = io::parse_config(
      "geometry:\n  shape: difference\n  shapes:\n    - {shape: box, name: outer, lower: [0, 0], upper: [2, 1]}\n"
      "    - {shape: disk, name: hole, center: [1, 0.5], radius: 0.25}\n",
      "d.yaml");
  auto g = std::make_shared<const geometry::Geometry>(geometry::read_geometry(root.child("geometry"), "."));
  const Domain d(g, std::pair{0.0, 3.0});
  EXPECT_EQ(d.input_dim(), 3);
  EXPECT_EQ(d.upper(), (std::vector<double>{2, 1}));
  Random rng(3);
  const Eigen::MatrixXd x = d.sample_interior(rng, 500);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    EXPECT_GT(std::hypot(x(r, 0) - 1, x(r, 1) - 0.5), 0.25);
    EXPECT_TRUE(x(r, 2) >= 0 && x(r, 2) < 3);
  }
  const Domain::BoundaryPoints b = d.sample_boundary(g->select({"hole"}), rng, 200);
  for (Eigen::Index r = 0; r < 200; ++r) {
    EXPECT_NEAR(std::hypot(b.points(r, 0) - 1, b.points(r, 1) - 0.5), 0.25, 1e-12);
    EXPECT_EQ(b.normals(r, 2), 0);
    EXPECT_EQ(b.parts(r), 1);
  }
  const Eigen::MatrixXd initial = d.sample_initial(rng, 50);
  EXPECT_TRUE((initial.col(2).array() == 0).all());
  const geometry::Measure m = d.space_measure();
  EXPECT_NEAR(m.value, 2 - std::numbers::pi / 16, 4 * m.std_error);
  EXPECT_THROW(d.sample_faces(d.faces(), rng, 10), std::logic_error);
  EXPECT_TRUE(Domain({0, 0}, {1, 2}).space_measure().exact);
  EXPECT_THROW(Domain({0, 0}, {1, 2}).sample_boundary({}, rng, 1), std::logic_error);
}

}  // namespace
}  // namespace nfield::solvers
