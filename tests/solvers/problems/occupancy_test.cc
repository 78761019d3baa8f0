// SPDX-License-Identifier: MIT
//
// The occupancy problem (solvers/problems/occupancy.cc): its residual is the square root of
// the binary cross-entropy with the mesh's inside test as labels, its derivative matches
// central differences (also where softplus saturates), a small SIREN and a small ACORN fit a
// sphere's inside, and bad keys are refused where they are.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "io/vtk_polydata.h"
#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"
#include "tests/testing/sphere_mesh.h"

namespace nfield::solvers {
namespace {

std::filesystem::path test_dir() { return testutil::test_folder("occupancy"); }

std::filesystem::path write_config(const std::string& name, const std::string& text) {
  const std::filesystem::path path = test_dir() / (name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

// The sphere |x| = 0.5 (a closed mesh), in the domain's coordinates.
std::filesystem::path sphere_file() {
  const std::filesystem::path path = test_dir() / "sphere.ply";
  io::write_ply(path, testutil::sphere_mesh(0.5));
  return path;
}

std::string sphere_config(const std::string& equation_extra, const std::string& rest = "") {
  return "problem: occupancy\nequation:\n  mesh: " + sphere_file().string() + "\n  normalize: false\n" +
         equation_extra + (rest.empty() ? "training: {batch: {interior: 64}}\n" : rest);
}

double softplus(double t) { return std::max(t, 0.0) + std::log1p(std::exp(-std::abs(t))); }

// r at the points of `x` for field values u, and dr/du from the residual's backward pass.
struct Evaluated {
  Eigen::VectorXd r, dr;
};
Evaluated evaluate(const LossTerm& term, const Eigen::MatrixXd& x, const Eigen::VectorXd& u) {
  const auto residual = term.residual(TermPoints(x));
  const autodiff::StreamLayout layout(term.spec);
  autodiff::Streams<double> out, adjoint;
  out.resize(x.rows(), layout.count(), 1);
  out.data.setZero();
  out.stream(0).col(0) = u;
  adjoint = out;
  adjoint.data.setZero();
  Eigen::MatrixXd r(x.rows(), 1);
  residual->evaluate(0, layout, out, r);
  residual->backward(0, layout, out, Eigen::MatrixXd::Ones(x.rows(), 1), adjoint);
  return {r.col(0), adjoint.stream(0).col(0)};
}

TEST(Occupancy, ResidualIsTheRootOfTheCrossEntropyWithInsideLabels) {
  for (const std::string loss : {"bce", "squares"}) {
    SCOPED_TRACE(loss);
    const RunSetup setup = load_run(write_config("residual", sphere_config("  loss: " + loss + "\n")), {});
    const LossTerm term = setup.problem->loss_terms().at(0);
    EXPECT_EQ(term.name, "occupancy");
    Random sampler(4);
    const Eigen::MatrixXd x = term.sample(sampler, 400);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> normal(0.0, 3.0);
    Eigen::VectorXd u(x.rows());
    for (Eigen::Index p = 0; p < u.size(); ++p) u(p) = normal(rng);
    const Evaluated e = evaluate(term, x, u);
    const double h = 1e-6;
    const Evaluated plus = evaluate(term, x, u.array() + h), minus = evaluate(term, x, u.array() - h);
    int inside = 0;
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      const double y = x.row(p).norm() < 0.5 ? 1.0 : 0.0;  // the mesh is a polyhedron: skip its skin
      if (std::abs(x.row(p).norm() - 0.5) < 2e-3) continue;
      inside += static_cast<int>(y);
      if (loss == "bce")
        EXPECT_NEAR(e.r(p) * e.r(p), softplus((1 - 2 * y) * u(p)), 1e-12) << p;
      else
        EXPECT_NEAR(e.r(p), u(p) - y, 1e-12) << p;
      const double fd = (plus.r(p) - minus.r(p)) / (2 * h);
      EXPECT_NEAR(e.dr(p), fd, 1e-6 * (1 + std::abs(fd))) << p;
    }
    // Half the draws lie within a few σ of the sphere: some inside, some outside.
    EXPECT_GT(inside, 40);
    EXPECT_LT(inside, 360);
  }
  // Far on the right side the cross-entropy underflows to 0: r and its derivative stay finite.
  const RunSetup setup = load_run(write_config("saturated", sphere_config("")), {});
  const LossTerm term = setup.problem->loss_terms().at(0);
  const Eigen::MatrixXd x = (Eigen::MatrixXd(2, 3) << 0, 0, 0, 0.9, 0.9, 0.9).finished();
  const Evaluated far = evaluate(term, x, Eigen::Vector2d(1e3, -1e3));
  EXPECT_TRUE(far.r.allFinite());
  EXPECT_TRUE(far.dr.allFinite());
  EXPECT_LT(far.r.cwiseAbs().maxCoeff(), 1e-100);
  // On the wrong side it grows like √|u|.
  const Evaluated wrong = evaluate(term, x, Eigen::Vector2d(-1e3, 1e3));
  EXPECT_NEAR(wrong.r(0), std::sqrt(1e3), 1e-9);
  EXPECT_NEAR(wrong.dr(0), -0.5 / std::sqrt(1e3), 1e-12);
}

// A sphere of radius 0.5: the fitted inside against the mesh's on a 48³ grid, and the
// decision surface at the sphere.
void expect_sphere_fit(const std::string& name, const std::string& field, int steps, double min_iou) {
  const std::filesystem::path out = test_dir() / (name + "_out");
  std::filesystem::remove_all(out);
  const std::string rest = field + "training:\n  seed: 1\n  threads: 2\n  batch: {interior: 2048}\n  stages:\n"
                           "    - {optimizer: adam, steps: " + std::to_string(steps) +
                           ", lr: 3.0e-3, schedule: cosine, lr_final: 1.0e-4}\noutput: {grid: [8, 8, 8], png: false}\n";
  RunSetup setup = load_run(write_config(name, sphere_config("  iou_resolution: 48\n", rest)), {}, out);
  ASSERT_EQ(execute_run(setup), 0);
  std::ifstream file(out / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(file);
  std::printf("%s: iou %.4f accuracy %.4f chamfer/diagonal %.2e pieces %g\n", name.c_str(),
              metrics["iou"].get<double>(), metrics["occupancy_accuracy"].get<double>(),
              metrics["chamfer_mean_per_diagonal"].get<double>(), metrics["surface_components"].get<double>());
  EXPECT_GT(metrics["iou"].get<double>(), min_iou);
  EXPECT_GT(metrics["occupancy_accuracy"].get<double>(), 0.97);
  EXPECT_EQ(metrics["iou_resolution"].get<double>(), 48);
  EXPECT_LT(metrics["chamfer_mean_per_diagonal"].get<double>(), 0.01);
  const io::PolyData surface = io::read_vtp(out / "surface.vtp");
  ASSERT_GT(surface.triangles.rows(), 100);
  const Eigen::ArrayXd radii = surface.points.rowwise().norm().array();
  EXPECT_NEAR(radii.mean(), 0.5, 0.02);
  std::filesystem::remove_all(out);
}

TEST(Occupancy, SirenFitsASphere) {
  expect_sphere_fit("siren", "field: {type: siren, hidden: [32, 32], first_omega: 3, hidden_omega: 3}\n", 300, 0.95);
}

TEST(Occupancy, AcornFitsASphere) {
  expect_sphere_fit("acorn",
                    "field: {type: acorn, hidden: [16], features: 4, grid: 5, encoder_hidden: [32], "
                    "encoder_octaves: 3, initial_level: 1, max_level: 3, max_blocks: 64, allocate_every: 50}\n",
                    300, 0.9);
}

TEST(Occupancy, ConfigErrorsAreLocated) {
  using testutil::expect_located_error;
  const std::string mesh = sphere_file().string();
  expect_located_error(write_config("near", sphere_config("  near_surface: 1.5\n")),
                       {5, 17, "equation.near_surface", "share in [0, 1]"});
  expect_located_error(write_config("sigma", sphere_config("  surface_sigma: 0\n")),
                       {5, 18, "equation.surface_sigma", ""});
  expect_located_error(write_config("resolution", sphere_config("  iou_resolution: 4\n")),
                       {5, 19, "equation.iou_resolution", ""});
  expect_located_error(write_config("loss", sphere_config("  loss: hinge\n")), {5, 9, "equation.loss", "bce"});
  expect_located_error(write_config("unknown", sphere_config("  sharpness: 2\n")), {5, 3, "equation.sharpness", ""});
  expect_located_error(write_config("missing", "problem: occupancy\nequation:\n  mesh: none.ply\n"),
                       {3, 9, "equation.mesh", "none.ply"});
  // A mesh with a hole (one triangle dropped): its inside is not defined.
  io::TriangleMesh open = testutil::sphere_mesh(0.5);
  open.triangles.conservativeResize(open.triangles.rows() - 1, 3);
  io::write_ply(test_dir() / "open.ply", open);
  expect_located_error(write_config("open", "problem: occupancy\nequation:\n  mesh: open.ply\n"),
                       {3, 9, "equation.mesh", "open.ply"});
  expect_located_error(write_config("two_d", "problem: occupancy\ndomain: {lower: [0, 0], upper: [1, 1]}\n"
                                             "equation: {mesh: " + mesh + "}\n"),
                       {2, 17, "domain.lower", "3D"});
}

}  // namespace
}  // namespace nfield::solvers
