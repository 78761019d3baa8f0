// SPDX-License-Identifier: MIT
//
// reference.file of `problem: pde` (solvers/problems/pde_reference.h): the same points and
// values as a CSV, a COMSOL-style whitespace table and an HDF5 dataset give the same
// per-output and overall errors as reference.exact at those points; the COMSOL layout with
// one column per output and time; column names from the config; metrics.json of a run;
// several files each with some of the outputs (the list form, `outputs`); every refused file
// located at its key with the table's message; and `solution: allen_cahn` (the ETDRK4
// solution at the config's coefficients) with its refused keys.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>

#include <nlohmann/json.hpp>

#include "io/hdf5_file.h"
#include "solvers/problems/allen_cahn_reference.h"
#include "solvers/problems/pde_reference.h"
#include "solvers/run/run.h"
#include "tests/testing/config_errors.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

namespace fs = std::filesystem;

const char* kHead = R"yaml(problem: pde
domain: {lower: [0, 0], upper: [1, 2]}
outputs: [u, v]
equation:
  residuals: ["lap(u)", "lap(v) - 2"]
reference:
)yaml";

// u* = sin(πx) y, v* = x + y².
Eigen::MatrixXd exact_values(const Eigen::MatrixXd& p) {
  Eigen::MatrixXd out(p.rows(), 2);
  for (Eigen::Index n = 0; n < p.rows(); ++n) {
    out(n, 0) = std::sin(std::numbers::pi * p(n, 0)) * p(n, 1);
    out(n, 1) = p(n, 0) + p(n, 1) * p(n, 1);
  }
  return out;
}

// A field off the exact one by different amounts per output.
Eigen::MatrixXd field_values(const Eigen::MatrixXd& p) {
  Eigen::MatrixXd out = exact_values(p);
  out.col(0).array() += 0.01 * p.col(0).array();
  out.col(1).array() -= 0.2 * p.col(1).array().square();
  return out;
}

// A 7 × 5 grid over the box, boundary included.
Eigen::MatrixXd grid_points() {
  Eigen::MatrixXd p(35, 2);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 7; ++i) p.row(j * 7 + i) << i / 6.0, 2.0 * j / 4.0;
  return p;
}

fs::path folder(const std::string& name) {
  const fs::path dir = testutil::scratch_dir("pde_reference") / name;
  fs::create_directories(dir);
  return dir;
}

void write_text(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// Rows "x<sep>y<sep>u<sep>v", full precision.
std::string rows(const Eigen::MatrixXd& p, const Eigen::MatrixXd& values, const char* sep) {
  std::string out;
  char line[256];
  for (Eigen::Index n = 0; n < p.rows(); ++n) {
    std::snprintf(line, sizeof line, "%.17g%s%.17g%s%.17g%s%.17g\n", p(n, 0), sep, p(n, 1), sep, values(n, 0), sep,
                  values(n, 1));
    out += line;
  }
  return out;
}

std::vector<std::pair<std::string, double>> metrics_of(const Problem& problem) {
  OutputContext context;
  context.values = field_values;
  std::vector<std::pair<std::string, double>> metrics;
  problem.write_outputs(context, metrics);
  return metrics;
}

double metric(const std::vector<std::pair<std::string, double>>& metrics, const std::string& key) {
  for (const auto& [k, v] : metrics)
    if (k == key) return v;
  ADD_FAILURE() << "no metric " << key;
  return NAN;
}

TEST(PdeReference, FileFormatsGiveTheMetricsOfTheExactReference) {
  const fs::path dir = folder("formats");
  const Eigen::MatrixXd p = grid_points(), values = exact_values(p);
  write_text(dir / "ref.csv", "# u* = sin(pi x) y, v* = x + y^2\nx,y,u,v\n" + rows(p, values, ","));
  write_text(dir / "ref.txt", "% Model: made by a test\n% Dimension: 2\n% x  y  u (m)  v (1)\n" + rows(p, values, "  "));
  {
    io::H5Writer out(dir / "ref.h5");
    Eigen::MatrixXd table(p.rows(), 4);
    table << p, values;
    out.write("fields/reference", table);
    out.write_attribute("fields/reference", "columns", std::vector<std::string>{"x", "y", "u", "v"});
    out.commit();
  }
  // reference.exact at the same points: the expected figures.
  write_text(dir / "exact.yaml", std::string(kHead) + "  exact: {u: \"sin(pi*x)*y\", v: \"x + y^2\"}\n");
  const RunSetup exact = load_run(dir / "exact.yaml", {});
  const OutputErrors want = output_errors(field_values(p), exact.problem->exact(p));
  EXPECT_GT(want.rel_l2[1], 10 * want.rel_l2[0]);  // the outputs' errors differ
  for (const std::string file : {"ref.csv", "ref.txt", "ref.h5:/fields/reference"}) {
    const fs::path config = dir / ("config_" + file.substr(4, 3) + ".yaml");
    write_text(config, std::string(kHead) + "  file: " + file + "\n");
    const RunSetup setup = load_run(config, {});
    EXPECT_FALSE(setup.problem->has_exact()) << file;
    const auto metrics = metrics_of(*setup.problem);
    EXPECT_EQ(metric(metrics, "reference_points"), 35) << file;
    EXPECT_NEAR(metric(metrics, "rel_l2"), want.all_rel_l2, 1e-14 * want.all_rel_l2) << file;
    EXPECT_NEAR(metric(metrics, "max_abs_err"), want.all_max_abs, 1e-14 * want.all_max_abs) << file;
    for (int c = 0; c < 2; ++c) {
      const std::string name = c == 0 ? "u" : "v";
      EXPECT_NEAR(metric(metrics, "rel_l2_" + name), want.rel_l2[c], 1e-14 * want.rel_l2[c]) << file;
      EXPECT_NEAR(metric(metrics, "max_abs_err_" + name), want.max_abs[c], 1e-14 * want.max_abs[c]) << file;
    }
    OutputContext context;
    context.values = field_values;
    EXPECT_EQ(setup.problem->reported_error(context).value_or(NAN), metric(metrics, "rel_l2")) << file;
  }
}

// Columns named in the config; the COMSOL layout over time (coordinates, then u @ t=…).
TEST(PdeReference, ColumnNamesAndTimedColumns) {
  const fs::path dir = folder("columns");
  const Eigen::MatrixXd p = grid_points(), values = exact_values(p);
  write_text(dir / "named.csv", "X,Y,u_fd,v_fd\n" + rows(p, values, ","));
  write_text(dir / "named.yaml", std::string(kHead) + "  file: named.csv\n  columns: {x: X, y: Y, u: u_fd, v: v_fd}\n");
  const RunSetup named = load_run(dir / "named.yaml", {});
  const OutputErrors want = output_errors(field_values(p), values);
  EXPECT_NEAR(metric(metrics_of(*named.problem), "rel_l2_v"), want.rel_l2[1], 1e-14 * want.rel_l2[1]);

  // u(x, t) = exp(−t) sin(πx) at t = 0, 0.5, 1, one column per time.
  std::string table = "% x   u (m) @ t=0   u (m) @ t=0.5   u (m) @ t=1\n";
  const auto u = [](double x, double t) { return std::exp(-t) * std::sin(std::numbers::pi * x); };
  for (int i = 0; i <= 4; ++i) {
    const double x = i / 4.0;
    char line[160];
    std::snprintf(line, sizeof line, "%.17g  %.17g  %.17g  %.17g\n", x, u(x, 0), u(x, 0.5), u(x, 1));
    table += line;
  }
  write_text(dir / "timed.txt", table);
  write_text(dir / "timed.yaml", R"yaml(problem: pde
domain: {lower: [0], upper: [1], time: [0, 1]}
equation:
  residuals: ["u_t - u_xx/pi^2"]
reference: {file: timed.txt}
)yaml");
  const RunSetup timed = load_run(dir / "timed.yaml", {});
  OutputContext context;
  Eigen::MatrixXd seen;
  context.values = [&](const Eigen::MatrixXd& x) {
    seen = x;
    Eigen::MatrixXd v(x.rows(), 1);
    for (Eigen::Index n = 0; n < x.rows(); ++n) v(n, 0) = u(x(n, 0), x(n, 1)) + 0.001;
    return v;
  };
  std::vector<std::pair<std::string, double>> metrics;
  timed.problem->write_outputs(context, metrics);
  ASSERT_EQ(seen.rows(), 15);
  EXPECT_EQ(seen(0, 1), 0);
  EXPECT_EQ(seen(5, 1), 0.5);
  EXPECT_EQ(seen(14, 0), 1);
  EXPECT_EQ(seen(14, 1), 1);
  EXPECT_NEAR(metric(metrics, "max_abs_err"), 0.001, 1e-12);
  // A time column after t1 lies outside the domain.
  table.replace(table.find("@ t=1\n"), 6, "@ t=2\n");
  write_text(dir / "timed.txt", table);
  testutil::expect_located_error(dir / "timed.yaml", {5, 19, "reference.file", "column 'u (m) @ t=2' lies outside the domain's time interval"});
}

// The rest of a run config after `reference:`: Dirichlet values of both outputs, a tiny
// field, three Adam steps.
const char* kRunTail = R"yaml(conditions:
  - {on: boundary, type: dirichlet, value: {u: "sin(pi*x)*y", v: "x + y^2"}}
field: {type: siren, hidden: [8], first_omega: 2, hidden_omega: 1}
training:
  seed: 0
  threads: 1
  precision: double
  batch: {interior: 32, boundary: 16}
  stages: [{optimizer: adam, steps: 3, lr: 1.0e-3}]
output: {grid: [5, 5], png: false}
)yaml";

// A short `nfield run` of a file reference: metrics.json has the errors at its points, and
// the last stage's rel_l2 is the same figure.
TEST(PdeReference, RunWritesThePointErrors) {
  const fs::path dir = folder("run");
  const Eigen::MatrixXd p = grid_points();
  write_text(dir / "ref.csv", "x,y,u,v\n" + rows(p, exact_values(p), ","));
  write_text(dir / "run.yaml", std::string(kHead) + "  file: ref.csv\n" + kRunTail);
  RunSetup setup = load_run(dir / "run.yaml", {"output.dir=" + (dir / "out").string()});
  ASSERT_EQ(execute_run(setup), 0);
  const nlohmann::json metrics = nlohmann::json::parse(std::ifstream(dir / "out" / "metrics.json"));
  ASSERT_TRUE(metrics.contains("rel_l2")) << metrics.dump();
  EXPECT_EQ(metrics["reference_points"], 35);
  EXPECT_TRUE(metrics.contains("rel_l2_u") && metrics.contains("max_abs_err_v")) << metrics.dump();
  EXPECT_EQ(metrics["stages"].back()["rel_l2"], metrics["rel_l2"]);
  EXPECT_GT(metrics["rel_l2"].get<double>(), 0);
}

// reference.exact with two outputs: the grid's errors per output beside the overall ones.
TEST(PdeReference, ExactGivesGridErrorsPerOutput) {
  const fs::path dir = folder("exact_run");
  write_text(dir / "run.yaml", std::string(kHead) + "  exact: {u: \"sin(pi*x)*y\", v: \"x + y^2\"}\n" + kRunTail);
  RunSetup setup = load_run(dir / "run.yaml", {"output.dir=" + (dir / "out").string()});
  ASSERT_EQ(execute_run(setup), 0);
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(dir / "out" / "metrics.json"));
  ASSERT_TRUE(m.contains("rel_l2_u") && m.contains("rel_l2_v")) << m.dump();
  EXPECT_FALSE(m.contains("reference_points"));
  EXPECT_EQ(m["max_abs_err"], std::max(m["max_abs_err_u"].get<double>(), m["max_abs_err_v"].get<double>()));
  const double all = m["rel_l2"], u = m["rel_l2_u"], v = m["rel_l2_v"];
  EXPECT_LE(all, std::max(u, v));
  EXPECT_GE(all, std::min(u, v));
}

// Rows "x,y,VALUE" of one output.
std::string rows_of(const Eigen::MatrixXd& p, const Eigen::VectorXd& values) {
  std::string out;
  char line[160];
  for (Eigen::Index n = 0; n < p.rows(); ++n) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", p(n, 0), p(n, 1), values(n));
    out += line;
  }
  return out;
}

// u on the line x = 0.5, v on the line y = 1 (the cavity's centreline tables): one file
// each, the list form. Each output's errors are those at its own file's points; the overall
// rel_l2 pools the squared errors of both.
TEST(PdeReference, ListOfFilesEachWithSomeOutputs) {
  const fs::path dir = folder("list");
  Eigen::MatrixXd pu(9, 2), pv(6, 2);
  for (int k = 0; k < 9; ++k) pu.row(k) << 0.5, 2.0 * k / 8.0;
  for (int k = 0; k < 6; ++k) pv.row(k) << k / 5.0, 1.0;
  const Eigen::MatrixXd eu = exact_values(pu), ev = exact_values(pv);
  write_text(dir / "u_line.csv", "# u along x = 0.5\nx,y,u\n" + rows_of(pu, eu.col(0)));
  write_text(dir / "v_line.csv", "x,y,v_ref\n" + rows_of(pv, ev.col(1)));
  write_text(dir / "list.yaml", std::string(kHead) +
                                    "  file:\n    - {file: u_line.csv, outputs: [u]}\n"
                                    "    - {file: v_line.csv, outputs: [v], columns: {v: v_ref}}\n");
  const RunSetup setup = load_run(dir / "list.yaml", {});
  const auto metrics = metrics_of(*setup.problem);
  const OutputErrors u = output_errors(field_values(pu), eu), v = output_errors(field_values(pv), ev);
  EXPECT_EQ(metric(metrics, "reference_points"), 15);
  EXPECT_NEAR(metric(metrics, "max_abs_err_u"), u.max_abs[0], 1e-15);
  EXPECT_NEAR(metric(metrics, "rel_l2_u"), u.rel_l2[0], 1e-14 * u.rel_l2[0]);
  EXPECT_NEAR(metric(metrics, "max_abs_err_v"), v.max_abs[1], 1e-15);
  EXPECT_NEAR(metric(metrics, "rel_l2_v"), v.rel_l2[1], 1e-14 * v.rel_l2[1]);
  EXPECT_GT(u.max_abs[0], 0);
  EXPECT_NE(u.max_abs[1], v.max_abs[1]);  // v at u's points would give another figure
  const double error2 = (field_values(pu) - eu).col(0).squaredNorm() + (field_values(pv) - ev).col(1).squaredNorm();
  const double norm2 = eu.col(0).squaredNorm() + ev.col(1).squaredNorm();
  EXPECT_NEAR(metric(metrics, "rel_l2"), std::sqrt(error2 / norm2), 1e-14);
  EXPECT_EQ(metric(metrics, "max_abs_err"), std::max(u.max_abs[0], v.max_abs[1]));

  // One file with one output of two: no figures for the other.
  write_text(dir / "one.yaml", std::string(kHead) + "  file: u_line.csv\n  outputs: [u]\n");
  const auto only_u = metrics_of(*load_run(dir / "one.yaml", {}).problem);
  EXPECT_EQ(metric(only_u, "rel_l2"), metric(only_u, "rel_l2_u"));
  for (const auto& [key, value] : only_u) EXPECT_TRUE(key.find("_v") == std::string::npos) << key;
}

// `derived`: a file may hold an expression of the outputs' values and the coordinates
// (here s = u + x v) as it holds an output; its figures are named after it.
TEST(PdeReference, DerivedQuantitiesAreComparedAsOutputs) {
  const fs::path dir = folder("derived");
  const Eigen::MatrixXd p = grid_points(), e = exact_values(p);
  const Eigen::VectorXd s = e.col(0) + p.col(0).cwiseProduct(e.col(1));
  write_text(dir / "s.csv", "x,y,s\n" + rows_of(p, s));
  const std::string head = std::string(kHead).replace(std::string(kHead).find("reference:"), 10,
                                                      "derived: {s: \"u + x*v\"}\nreference:");
  write_text(dir / "derived.yaml", head + "  file: s.csv\n  outputs: [s]\n");
  const auto metrics = metrics_of(*load_run(dir / "derived.yaml", {}).problem);
  const Eigen::MatrixXd f = field_values(p);
  const Eigen::VectorXd fs_values = f.col(0) + p.col(0).cwiseProduct(f.col(1));
  EXPECT_NEAR(metric(metrics, "max_abs_err_s"), (fs_values - s).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(metric(metrics, "rel_l2"), (fs_values - s).norm() / s.norm(), 1e-14);
  EXPECT_GT(metric(metrics, "max_abs_err_s"), 0.01);
  for (const auto& [key, value] : metrics) EXPECT_TRUE(key.find("_u") == std::string::npos) << key;

  using testutil::expect_located_error;
  const auto refused = [&](const std::string& name, const std::string& derived) {
    const fs::path path = dir / (name + ".yaml");
    write_text(path, std::string(kHead).replace(std::string(kHead).find("reference:"), 10, derived + "\nreference:") +
                         "  file: s.csv\n  outputs: [s]\n");
    return path;
  };
  expect_located_error(refused("clash", "derived: {u: \"v\"}"),
                       {6, 14, "derived.u", "expected a new name of letters and digits (not an output"});
  expect_located_error(refused("derivative", "derived: {s: \"u_x + v\"}"),
                       {6, 15, "derived.s", "unknown symbol 'u_x'"});
}

TEST(PdeReference, RefusedListsAndOutputsAreLocated) {
  using testutil::expect_located_error;
  const fs::path dir = folder("refused_list");
  write_text(dir / "u.csv", "x,y,u\n0,0,1\n");
  const auto config = [&](const std::string& name, const std::string& reference) {
    const fs::path path = dir / (name + ".yaml");
    write_text(path, std::string(kHead) + reference);
    return path;
  };
  expect_located_error(config("unknown_output", "  file: u.csv\n  outputs: [u, w]\n"),
                       {8, 12, "reference.outputs", "'w' is no output (outputs: u, v)"});
  expect_located_error(config("twice", "  file: u.csv\n  outputs: [u, u]\n"),
                       {8, 12, "reference.outputs", "'u' is listed twice"});
  expect_located_error(config("empty", "  file: u.csv\n  outputs: []\n"),
                       {8, 12, "reference.outputs", "expected a non-empty list of output names"});
  // Without `outputs`, every output is expected: the file lacks v.
  expect_located_error(config("all_outputs", "  file:\n    - {file: u.csv}\n"),
                       {8, 14, "reference.file[0].file", "no column 'v' (columns: x, y, u)"});
  expect_located_error(config("second_item", "  file:\n    - {file: u.csv, outputs: [u]}\n    - {file: none.csv, outputs: [v]}\n"),
                       {9, 14, "reference.file[1].file", (dir / "none.csv").string() + ": no such file"});
  expect_located_error(config("not_a_map", "  file:\n    - u.csv\n"),
                       {8, 7, "reference.file[0]", "expected a mapping {file, columns, outputs}"});
  expect_located_error(config("outer_outputs", "  file:\n    - {file: u.csv, outputs: [u]}\n  outputs: [u]\n"),
                       {9, 12, "reference.outputs", "with a list of files, each item takes its own columns and outputs"});
  expect_located_error(config("item_key", "  file:\n    - {file: u.csv, outputs: [u], weight: 2}\n"),
                       {8, 35, "reference.file[0].weight", "unknown key"});
}

TEST(PdeReference, RefusedFilesAreLocated) {
  using testutil::expect_located_error;
  const fs::path dir = folder("refused");
  const Eigen::MatrixXd p = grid_points(), values = exact_values(p);
  write_text(dir / "nan.csv", "x,y,u,v\n0,0,1,2\n0.5,1,nan,2\n");
  write_text(dir / "ragged.csv", "x,y,u,v\n0,0,1,2\n0.5,1,2\n");
  write_text(dir / "outside.csv", "x,y,u,v\n0,0,1,2\n0.5,2.5,1,2\n");
  write_text(dir / "no_v.csv", "x,y,u\n0,0,1\n");
  const auto config = [&](const std::string& name, const std::string& reference) {
    const fs::path path = dir / (name + ".yaml");
    write_text(path, std::string(kHead) + reference);
    return path;
  };
  expect_located_error(config("missing", "  file: none.csv\n"),
                       {7, 9, "reference.file", (dir / "none.csv").string() + ": no such file"});
  expect_located_error(config("nan", "  file: nan.csv\n"), {7, 9, "reference.file", "nan.csv:3:7: field 3 (u) is nan"});
  expect_located_error(config("ragged", "  file: ragged.csv\n"),
                       {7, 9, "reference.file", "ragged.csv:3: 3 fields, but the header (line 1) names 4 columns"});
  expect_located_error(config("outside", "  file: outside.csv\n"),
                       {7, 9, "reference.file", "outside.csv:3: the point (x, y) = (0.5, 2.5) lies outside the box"});
  expect_located_error(config("no_column", "  file: no_v.csv\n"),
                       {7, 9, "reference.file", "no column 'v' (columns: x, y, u)"});
  expect_located_error(config("no_named_column", "  file: no_v.csv\n  columns: {v: v_fd}\n"),
                       {8, 16, "reference.columns.v", "no column 'v_fd' (columns: x, y, u)"});
  expect_located_error(config("unknown_name", "  file: no_v.csv\n  columns: {w: v_fd}\n"),
                       {8, 16, "reference.columns.w", "'w' is neither a variable nor an output (variables: x, y; outputs: u, v)"});
  expect_located_error(config("both", "  file: no_v.csv\n  exact: {u: \"0\", v: \"0\"}\n"),
                       {7, 3, "reference", "expected one of exact, solution, file"});
}

const char* kAllenCahn = R"yaml(problem: pde
domain: {lower: [-1], upper: [1], time: [0, 1]}
constants: {eps: 1.0e-4}
equation:
  residuals: ["u_t - eps*u_xx + 5*u^3 - 5*u"]
reference: {solution: allen_cahn, diffusion: eps, reaction: 5, modes: 256}
)yaml";

// reference.solution: allen_cahn is the ETDRK4 solution at the config's coefficients (the
// same values as solvers::AllenCahnReference with those options), over the domain's time.
TEST(PdeReference, AllenCahnSolution) {
  const fs::path dir = folder("allen_cahn");
  write_text(dir / "ac.yaml", kAllenCahn);
  const RunSetup setup = load_run(dir / "ac.yaml", {});
  ASSERT_TRUE(setup.problem->has_exact());
  Eigen::MatrixXd x(4, 2);
  x << -0.5, 0.0, 0.3, 0.25, 1.0, 0.6, -0.95, 1.0;
  const Eigen::MatrixXd u = setup.problem->exact(x);
  const AllenCahnReference reference({.diffusion = 1e-4, .reaction = 5, .modes = 256});
  for (Eigen::Index i = 0; i < x.rows(); ++i) EXPECT_EQ(u(i, 0), reference(x(i, 0), x(i, 1))) << i;
  EXPECT_NEAR(u(0, 0), 0.25 * std::cos(std::numbers::pi * 0.5), 1e-12);  // the initial value x² cos πx
  // Another diffusion gives another solution (the key is read, not the default).
  write_text(dir / "ac_other.yaml", std::string(kAllenCahn).replace(std::string(kAllenCahn).find("eps: 1.0e-4"), 11, "eps: 1.0e-3"));
  Eigen::MatrixXd line(201, 2);
  line.col(0) = Eigen::VectorXd::LinSpaced(201, -1, 1);
  line.col(1).setConstant(1.0);
  const double change = (load_run(dir / "ac_other.yaml", {}).problem->exact(line) - setup.problem->exact(line)).cwiseAbs().maxCoeff();
  EXPECT_GT(change, 1e-2);
}

TEST(PdeReference, AllenCahnKeysAreChecked) {
  using testutil::expect_located_error;
  const fs::path dir = folder("allen_cahn_refused");
  const auto config = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string text = kAllenCahn;
    text.replace(text.find(from), from.size(), to);
    const fs::path path = dir / (name + ".yaml");
    write_text(path, text);
    return path;
  };
  expect_located_error(config("modes", "modes: 256", "modes: 255"), {6, 71, "reference.modes", "even number of modes"});
  expect_located_error(config("modes_range", "modes: 256", "modes: 8"), {6, 71, "reference.modes", "[16, 65536]"});
  expect_located_error(config("diffusion", "diffusion: eps", "diffusion: -eps"),
                       {6, 46, "reference.diffusion", "expected a diffusion in (0, 1]"});
  expect_located_error(config("unknown", "diffusion: eps", "diffusion: eps, nu: 1"),
                       {6, 51, "reference.nu", "unknown key"});
  expect_located_error(config("box", "lower: [-1]", "lower: [-2]"),
                       {6, 23, "reference.solution", "allen_cahn is computed on x in [-1, 1]"});
  expect_located_error(config("start", "time: [0, 1]", "time: [0.5, 1]"),
                       {6, 23, "reference.solution", "from its initial value"});
  expect_located_error(config("name", "allen_cahn", "allen_kahn"),
                       {6, 23, "reference.solution", "allen_cahn"});
}

}  // namespace
}  // namespace nfield::solvers
