// SPDX-License-Identifier: MIT
//
// Outputs on the domain (solvers/output/domain_output.h): a 2-D geometry's domain.vtu opens
// with VTK's reader, holds only points inside, carries u, grad_u, the residual, exact_u and
// error_u with the field's values at every point (the grid's and the crossings of the clip),
// reaches the boundary (points on both circles) and covers the domain's area up to O(h²);
// a time series gets one file per frame and a .pvd; a 3-D geometry's boundary.vtp lies on
// the boundary and carries u at its vertices.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "fields/field.h"
#include "io/pvd.h"
#include "io/vtk_polydata.h"
#include "io/vtk_unstructured.h"
#include "solvers/output/domain_output.h"
#include "solvers/output/grid_output.h"
#include "solvers/run/run.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

// An untrained field's evaluator (the outputs are checked against its own values).
struct Evaluated {
  explicit Evaluated(RunSetup& setup) : field(setup.field) {}
  fields::Field<double> field;
  StreamEvaluator evaluator() {
    return [this](const StreamLayout& layout, const Eigen::MatrixXd& x) {
      Streams<double> out;
      field.evaluate(layout, x, out);
      return out;
    };
  }
};

const char* const kAnnulus = R"yaml(problem: poisson
domain:
  geometry:
    shape: difference
    shapes:
      - {shape: disk, center: [0, 0], radius: 1, name: rim}
      - {shape: disk, center: [0.2, 0], radius: 0.4, name: hole}
equation: {source: "0", exact: "exp(x)*sin(y)"}
conditions:
  - {on: boundary, type: dirichlet, value: "exp(x)*sin(y)"}
field: {type: siren, hidden: [8], first_omega: 2}
training: {seed: 0, threads: 1, stages: [{optimizer: adam, steps: 1}]}
output: {grid: [61, 61], png: false}
)yaml";

TEST(DomainOutput, TwoDimensionalDomainAsTrianglesInside) {
  const auto config = testutil::write_config("domain_output", kAnnulus);
  RunSetup setup = load_run(config, {});
  setup.output.dir = config.parent_path() / "out";
  std::filesystem::create_directories(setup.output.dir);
  Evaluated e(setup);
  write_grid_outputs(*setup.problem, e.evaluator(), setup.output);
  const io::TriangleGrid vtu = io::read_vtu(setup.output.dir / "domain.vtu");
  ASSERT_GT(vtu.points.rows(), 100);
  const Domain& d = setup.problem->domain();
  EXPECT_TRUE(d.contains_rows(vtu.points.leftCols(2)).all());
  for (const char* name : {"u", "grad_u", "residual", "exact_u", "error_u"}) {
    ASSERT_TRUE(vtu.arrays.count(name)) << name;
    EXPECT_EQ(vtu.arrays.at(name).rows(), vtu.points.rows()) << name;
    EXPECT_TRUE(vtu.arrays.at(name).allFinite()) << name;
  }
  EXPECT_FALSE(vtu.arrays.count("inside"));
  // u is the field's value at each point, the error u − u*.
  const Eigen::MatrixXd u = e.field.values(vtu.points.leftCols(2));
  EXPECT_LT((vtu.arrays.at("u") - u).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd exact = setup.problem->exact(vtu.points.leftCols(2));
  EXPECT_LT((vtu.arrays.at("error_u") - (u - exact)).cwiseAbs().maxCoeff(), 1e-12);
  // The clip reaches both circles: many points on each, to its tolerance (domain_clip.h).
  const double h = 2.0 / 60, tolerance = 1e-6 * h;
  int on_rim = 0, on_hole = 0;
  for (Eigen::Index p = 0; p < vtu.points.rows(); ++p) {
    const Eigen::Vector2d x = vtu.points.row(p).head<2>().transpose();
    on_rim += std::abs(x.norm() - 1) <= tolerance ? 1 : 0;
    on_hole += std::abs((x - Eigen::Vector2d(0.2, 0)).norm() - 0.4) <= tolerance ? 1 : 0;
  }
  EXPECT_GT(on_rim, 150);  // the rim crosses some 2 · 2π / h ≈ 380 grid edges
  EXPECT_GT(on_hole, 60);
  // Area: the annulus's up to the chords' O(h²): at most 2π (√2 h)² / 12 per circle.
  double area = 0;
  for (Eigen::Index t = 0; t < vtu.triangles.rows(); ++t) {
    const Eigen::Vector3d a = vtu.points.row(vtu.triangles(t, 0)), b = vtu.points.row(vtu.triangles(t, 1)),
                          c = vtu.points.row(vtu.triangles(t, 2));
    const double signed_area = 0.5 * ((b(0) - a(0)) * (c(1) - a(1)) - (b(1) - a(1)) * (c(0) - a(0)));
    EXPECT_GT(signed_area, 0);  // counter-clockwise
    area += signed_area;
  }
  const double exact_area = std::numbers::pi * (1 - 0.16);
  EXPECT_NEAR(area, exact_area, 2 * 1.05 * h * h);
}

TEST(DomainOutput, TimeSeriesGetsOneFilePerFrameAndAPvd) {
  const std::filesystem::path config = std::filesystem::path(NFIELD_SOURCE_DIR) / "configs" / "heat_disk.yaml";
  RunSetup setup = load_run(config, {"training.threads=1", "output.grid=[15, 15]", "output.frames=3", "output.png=false"});
  setup.output.dir = testutil::scratch_dir("domain_output");
  Evaluated e(setup);
  write_grid_outputs(*setup.problem, with_ansatz(e.evaluator(), setup.problem->ansatz()), setup.output);
  const io::PvdCollection pvd = io::PvdCollection::read(setup.output.dir / "domain.pvd");
  ASSERT_EQ(pvd.entries().size(), 3u);
  EXPECT_DOUBLE_EQ(pvd.entries().back().time, 0.5);
  for (const auto& entry : pvd.entries()) {
    const io::TriangleGrid vtu = io::read_vtu(setup.output.dir / entry.file);
    EXPECT_GT(vtu.triangles.rows(), 50);
    EXPECT_TRUE(vtu.arrays.count("error_u"));
  }
}

TEST(DomainOutput, ThreeDimensionalBoundarySurfaceCarriesU) {
  const char* const ball = R"yaml(problem: poisson
domain: {geometry: {shape: ball, center: [0.1, 0, 0], radius: 0.8, name: shell}}
equation: {source: "0", exact: "x + 2*y - z"}
conditions:
  - {on: shell, type: dirichlet, value: "x + 2*y - z"}
field: {type: siren, hidden: [8], first_omega: 2}
training: {seed: 0, threads: 1, stages: [{optimizer: adam, steps: 1}]}
output: {grid: [25, 25, 25], png: false}
)yaml";
  const auto config = testutil::write_config("domain_output", ball);
  RunSetup setup = load_run(config, {});
  setup.output.dir = config.parent_path() / "out";
  std::filesystem::create_directories(setup.output.dir);
  Evaluated e(setup);
  write_grid_outputs(*setup.problem, e.evaluator(), setup.output);
  const io::PolyData vtp = io::read_vtp(setup.output.dir / "boundary.vtp");
  ASSERT_GT(vtp.triangles.rows(), 200);
  const double h = 1.6 / 24;
  for (Eigen::Index p = 0; p < vtp.points.rows(); ++p)
    EXPECT_NEAR((vtp.points.row(p) - Eigen::RowVector3d(0.1, 0, 0)).norm(), 0.8, 0.1 * h);  // O(h²) of a sphere
  ASSERT_TRUE(vtp.arrays.count("u"));
  ASSERT_TRUE(vtp.arrays.count("error_u"));
  EXPECT_LT((vtp.arrays.at("u") - e.field.values(vtp.points)).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
}  // namespace nfield::solvers
