// SPDX-License-Identifier: MIT
//
// What `nfield run` and `nfield eval` write, checked value by value against the trained
// field read back from the checkpoint, and Ctrl-C + --resume: a run interrupted by SIGINT
// writes a whole checkpoint and its outputs (exit 130), and resuming it ends with the same
// checkpoint, bit for bit, as a run never interrupted.
#include <gtest/gtest.h>

#include <signal.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test_support.h"
#include "fields/field_io.h"
#include "io/hdf5_file.h"
#include "io/vtk_image.h"

namespace nfield::apps::testing {
namespace {

constexpr double kPi = std::numbers::pi;

nlohmann::json read_json(const std::filesystem::path& path) {
  return nlohmann::json::parse(read_text(path));
}

// No temporary of an atomic write (name.tmp, .name.tmp-PID-N) left anywhere below `dir`.
void expect_no_temporaries(const std::filesystem::path& dir) {
  for (const std::string& name : tree(dir))
    EXPECT_EQ(name.find("tmp"), std::string::npos) << "left over: " << (dir / name);
}

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

// Every dataset of two HDF5 files: the same names, types, shapes and bits.
void expect_same_datasets(const std::filesystem::path& a_path, const std::filesystem::path& b_path) {
  const io::H5Reader a(a_path), b(b_path);
  const std::vector<std::string> names = a.dataset_names();
  ASSERT_EQ(names, b.dataset_names());
  bool has_weights = false;
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    has_weights = has_weights || name.find("field/layers/") == 0;
    ASSERT_EQ(a.type(name), b.type(name));
    const auto shape = a.shape(name);
    ASSERT_EQ(shape, b.shape(name));
    // Reading as double converts float exactly, so equal doubles mean equal floats.
    if (shape.size() == 2) {
      EXPECT_TRUE(same_bits(a.read_matrix<double>(name), b.read_matrix<double>(name)));
    } else if (shape.size() == 1) {
      const Eigen::MatrixXd va = a.read_vector<double>(name), vb = b.read_vector<double>(name);
      EXPECT_TRUE(same_bits(va, vb));
    }
  }
  EXPECT_TRUE(has_weights);
}

// ---- Ctrl-C and --resume ------------------------------------------------------------

class ResumeTest : public ::testing::TestWithParam<std::string> {};

constexpr int kSteps = 80;

std::string resume_config(const std::string& precision) {
  return poisson_config("{lower: [0, 0], upper: [1, 1]}",
                        "  seed: 7\n"
                        "  precision: " + precision + "\n"
                        "  threads: 2\n"
                        "  batch: {interior: 256, boundary: 64}\n"
                        "  resample_every: 4\n"
                        "  log_every: 1\n"
                        "  checkpoint_every: 30\n"
                        "  stages:\n"
                        "    - {optimizer: adam, steps: " + std::to_string(kSteps) +
                            ", lr: 2.0e-3, schedule: cosine, lr_final: 1.0e-4}\n",
                        "{grid: [9, 9]}");
}

TEST_P(ResumeTest, InterruptedRunResumesBitExact) {
  const auto dir = scratch_dir();
  const auto config = dir / "resume.yaml";
  write_text(config, resume_config(GetParam()));
  const auto uninterrupted = dir / "uninterrupted", interrupted = dir / "interrupted",
             resumed = dir / "resumed";

  Outcome o = run_nfield({"run", config.string(), "--out", uninterrupted.string()}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  expect_no_temporaries(uninterrupted);

  // Interrupt after step 21 (resample_every is 4: the resumed run starts on the saved
  // points, not on new ones). The child writes a line (some 95 bytes) per step into a pipe
  // of 4 KiB that is read no further than that line, so it cannot get more than some 45
  // steps ahead: it stops before the end (80) however late the signal comes.
  const Interrupted stop =
      interrupt_after_step({"run", config.string(), "--out", interrupted.string()}, dir, dir / "stderr.txt", 21);
  ASSERT_GE(stop.stopped_after, 21) << "no progress line for step 21";
  ASSERT_TRUE(stop.signalled);
  const long stopped_after = stop.stopped_after;
  o = stop.outcome;
  ASSERT_EQ(o.code, 130) << describe(o);
  EXPECT_FALSE(o.signaled);
  for (const char* file : {"config.yaml", "checkpoint.h5", "metrics.json", "solution.vti", "solution.png"})
    EXPECT_TRUE(std::filesystem::exists(interrupted / file)) << file;
  expect_no_temporaries(interrupted);
  const nlohmann::json metrics = read_json(interrupted / "metrics.json");
  EXPECT_EQ(metrics["finished"], false);
  const long steps = metrics["steps"];
  EXPECT_GE(steps, stopped_after);
  EXPECT_LT(steps, kSteps);
  EXPECT_NE(o.out.find("interrupted at step " + std::to_string(steps)), std::string::npos) << o.out;
  {
    // The checkpoint is whole and holds the state reached.
    const io::H5Reader checkpoint(interrupted / "checkpoint.h5");
    EXPECT_EQ(checkpoint.read_attribute<std::int64_t>("trainer", "global_step"), steps);
    EXPECT_EQ(checkpoint.read_attribute<std::int64_t>("trainer", "stage_step"), steps);
    EXPECT_NO_THROW(fields::load_field<double>(checkpoint));
  }

  o = run_nfield({"run", config.string(), "--resume", (interrupted / "checkpoint.h5").string(), "--out",
                  resumed.string()},
                 dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("at step " + std::to_string(steps)), std::string::npos) << o.out;
  expect_no_temporaries(resumed);
  const nlohmann::json resumed_metrics = read_json(resumed / "metrics.json");
  const nlohmann::json full_metrics = read_json(uninterrupted / "metrics.json");
  EXPECT_EQ(resumed_metrics["finished"], true);
  EXPECT_EQ(resumed_metrics["steps"], kSteps);
  EXPECT_EQ(resumed_metrics["losses"], full_metrics["losses"]);
  EXPECT_EQ(resumed_metrics["rel_l2"], full_metrics["rel_l2"]);

  // Parameters, Adam moments, points and losses: bit for bit.
  expect_same_datasets(uninterrupted / "checkpoint.h5", resumed / "checkpoint.h5");
  const io::ImageData a = io::read_vti(uninterrupted / "solution.vti");
  const io::ImageData b = io::read_vti(resumed / "solution.vti");
  for (const auto& [name, values] : a.arrays) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(b.arrays.count(name));
    EXPECT_TRUE(same_bits(values, b.arrays.at(name)));
  }
}

INSTANTIATE_TEST_SUITE_P(Precisions, ResumeTest, ::testing::Values("double", "float"));

// A checkpoint of another network is refused before anything is written.
TEST(Resume, CheckpointOfAnotherFieldWritesNothing) {
  const auto dir = scratch_dir();
  const std::string training =
      "  threads: 2\n  batch: {interior: 32, boundary: 16}\n"
      "  stages:\n    - {optimizer: adam, steps: 2, lr: 1.0e-3}\n";
  write_text(dir / "small.yaml", poisson_config("{lower: [0, 0], upper: [1, 1]}", training, "{grid: [5, 5]}"));
  std::string other = poisson_config("{lower: [0, 0], upper: [1, 1]}", training, "{grid: [5, 5]}");
  other.replace(other.find("[16, 16]"), 8, "[8]");
  write_text(dir / "other.yaml", other);
  Outcome o = run_nfield({"run", (dir / "small.yaml").string(), "--out", (dir / "small").string()}, dir,
                         dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  o = run_nfield({"run", (dir / "other.yaml").string(), "--resume", (dir / "small/checkpoint.h5").string(),
                  "--out", (dir / "other").string()},
                 dir, dir / "capture");
  EXPECT_NE(o.code, 0) << describe(o);
  EXPECT_NE(o.code, 130) << describe(o);
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_NE(o.err.find("parameters"), std::string::npos) << o.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "other"));
}

// Resuming a finished run trains nothing and says so; a stage added to the config trains on
// from where the run ended.
TEST(Resume, FinishedRunTrainsOnlyAnAddedStage) {
  const auto dir = scratch_dir();
  const std::string one_stage =
      "  batch: {interior: 32, boundary: 16}\n  stages:\n    - {optimizer: adam, steps: 2, lr: 1.0e-3}\n";
  write_text(dir / "small.yaml", poisson_config("{lower: [0, 0], upper: [1, 1]}", one_stage, "{grid: [5, 5]}"));
  write_text(dir / "longer.yaml",
             poisson_config("{lower: [0, 0], upper: [1, 1]}",
                            one_stage + "    - {optimizer: adam, steps: 3, lr: 1.0e-4}\n", "{grid: [5, 5]}"));
  Outcome o = run_nfield({"run", (dir / "small.yaml").string(), "--out", (dir / "small").string()}, dir,
                         dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const std::string checkpoint = (dir / "small/checkpoint.h5").string();

  o = run_nfield({"run", (dir / "small.yaml").string(), "--resume", checkpoint, "--out", (dir / "again").string()},
                 dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("nothing is trained"), std::string::npos) << o.out;
  EXPECT_EQ(read_json(dir / "again/metrics.json")["steps"], 2);

  o = run_nfield({"run", (dir / "longer.yaml").string(), "--resume", checkpoint, "--out", (dir / "longer").string()},
                 dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_EQ(o.out.find("nothing is trained"), std::string::npos) << o.out;
  const nlohmann::json metrics = read_json(dir / "longer/metrics.json");
  EXPECT_EQ(metrics["steps"], 5);
  EXPECT_EQ(metrics["finished"], true);
}

// ---- outputs, value by value ----------------------------------------------------------

// A box other than the unit square and a grid of unequal counts, so that mixing up the
// axes or the point order shows.
constexpr double kLower[2] = {0.0, -0.5}, kUpper[2] = {2.0, 1.0};

std::string outputs_config(const std::string& precision) {
  return poisson_config("{lower: [0, -0.5], upper: [2, 1]}",
                        "  seed: 3\n"
                        "  precision: " + precision + "\n"
                        "  threads: 2\n"
                        "  batch: {interior: 64, boundary: 16}\n"
                        "  stages:\n"
                        "    - {optimizer: adam, steps: 10, lr: 5.0e-3}\n",
                        "{grid: [9, 7]}");
}

// Checks a solution.vti against the field in `checkpoint`: grid, u, grad_u, exact_u,
// error_u. Returns the arrays.
io::ImageData check_solution(const std::filesystem::path& vti, const std::filesystem::path& checkpoint,
                             int nx, int ny, double tolerance) {
  const io::ImageData image = io::read_vti(vti);
  EXPECT_EQ(image.grid.dims, (std::array<int, 3>{nx, ny, 1}));
  EXPECT_DOUBLE_EQ(image.grid.origin[0], kLower[0]);
  EXPECT_DOUBLE_EQ(image.grid.origin[1], kLower[1]);
  EXPECT_DOUBLE_EQ(image.grid.spacing[0], (kUpper[0] - kLower[0]) / (nx - 1));
  EXPECT_DOUBLE_EQ(image.grid.spacing[1], (kUpper[1] - kLower[1]) / (ny - 1));
  const Eigen::MatrixXd x = image.grid.points(2);
  const Eigen::Index n = x.rows();
  EXPECT_EQ(n, nx * ny);
  // The last point is the upper corner.
  EXPECT_NEAR(x(n - 1, 0), kUpper[0], 1e-12);
  EXPECT_NEAR(x(n - 1, 1), kUpper[1], 1e-12);

  const fields::Field<double> field = fields::load_field<double>(io::H5Reader(checkpoint));
  const Eigen::MatrixXd values = field.values(x);
  const Eigen::MatrixXd& u = io::require_array(image.arrays, "u", vti);
  const Eigen::MatrixXd& exact = io::require_array(image.arrays, "exact_u", vti);
  const Eigen::MatrixXd& error = io::require_array(image.arrays, "error_u", vti);
  const Eigen::MatrixXd& gradient = io::require_array(image.arrays, "grad_u", vti);
  EXPECT_TRUE(image.arrays.count("residual"));
  EXPECT_EQ(u.rows(), n);
  EXPECT_EQ(u.cols(), 1);
  EXPECT_EQ(gradient.cols(), 3);
  // grad_u against central differences of the field (all points in one evaluation).
  const double h = 1e-6;
  Eigen::MatrixXd shifted(4 * n, 2);
  for (int a = 0; a < 2; ++a) {
    shifted.middleRows((2 * a) * n, n) = x;
    shifted.middleRows((2 * a + 1) * n, n) = x;
    shifted.middleRows((2 * a) * n, n).col(a).array() += h;
    shifted.middleRows((2 * a + 1) * n, n).col(a).array() -= h;
  }
  const Eigen::MatrixXd f = field.values(shifted);
  for (Eigen::Index i = 0; i < n; ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    EXPECT_NEAR(u(i, 0), values(i, 0), tolerance * (1 + std::abs(values(i, 0))));
    EXPECT_NEAR(exact(i, 0), std::sin(kPi * x(i, 0)) * std::sin(kPi * x(i, 1)), 1e-14);
    EXPECT_EQ(error(i, 0), u(i, 0) - exact(i, 0));
    for (int a = 0; a < 2; ++a) {
      const double difference = (f(2 * a * n + i, 0) - f((2 * a + 1) * n + i, 0)) / (2 * h);
      EXPECT_NEAR(gradient(i, a), difference, std::max(1e-5, 10 * tolerance) * (1 + std::abs(difference)));
    }
    EXPECT_EQ(gradient(i, 2), 0.0);
  }
  return image;
}

class OutputsTest : public ::testing::TestWithParam<std::string> {};

TEST_P(OutputsTest, SolutionAndMetricsMatchTheCheckpointField) {
  const std::string precision = GetParam();
  const double tolerance = precision == "double" ? 1e-12 : 1e-5;
  const auto dir = scratch_dir();
  const auto config = dir / "outputs.yaml", out = dir / "out";
  write_text(config, outputs_config(precision));
  Outcome o = run_nfield({"run", config.string(), "--out", out.string()}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_EQ(tree(out), (std::vector<std::string>{"checkpoint.h5", "config.yaml", "metrics.json",
                                                  "solution.png", "solution.vti"}));

  const io::ImageData image = check_solution(out / "solution.vti", out / "checkpoint.h5", 9, 7, tolerance);
  const Eigen::MatrixXd& error = image.arrays.at("error_u");
  const Eigen::MatrixXd& exact = image.arrays.at("exact_u");
  const Eigen::MatrixXd& residual = image.arrays.at("residual");

  const nlohmann::json metrics = read_json(out / "metrics.json");
  EXPECT_EQ(metrics["problem"], "poisson");
  EXPECT_EQ(metrics["finished"], true);
  EXPECT_EQ(metrics["steps"], 10);
  EXPECT_EQ(metrics["precision"], precision);
  EXPECT_EQ(metrics["parameters"],
            fields::load_field<double>(io::H5Reader(out / "checkpoint.h5")).parameter_count());
  const double rel_l2 = std::sqrt(error.squaredNorm() / exact.squaredNorm());
  EXPECT_NEAR(metrics["rel_l2"].get<double>(), rel_l2, 1e-12 * rel_l2);
  EXPECT_EQ(metrics["max_abs_err"].get<double>(), error.cwiseAbs().maxCoeff());
  const double residual_rms = std::sqrt(residual.squaredNorm() / static_cast<double>(residual.rows()));
  EXPECT_NEAR(metrics["residual_rms"].get<double>(), residual_rms, 1e-12 * residual_rms);
  double loss = 0;
  for (const auto& [name, value] : metrics["losses"].items()) loss += value.get<double>();
  EXPECT_EQ(metrics["losses"].size(), 2u);
  EXPECT_NEAR(metrics["loss"].get<double>(), loss, 1e-12 * loss);
  EXPECT_GT(rel_l2, 0);

  // The resolved config is itself a valid config.
  o = run_nfield({"validate", (out / "config.yaml").string()}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);

  // nfield eval: the same field on another grid.
  const auto evaluated = dir / "eval17";
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "17", "--out", evaluated.string()},
                 dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  check_solution(evaluated / "solution.vti", out / "checkpoint.h5", 17, 17, tolerance);
  EXPECT_TRUE(std::filesystem::exists(evaluated / "config.yaml"));
  expect_no_temporaries(evaluated);

  // Without --out: beside the checkpoint, in eval/.
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "5"}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  check_solution(out / "eval" / "solution.vti", out / "checkpoint.h5", 5, 5, tolerance);
}

// A config whose data file is named relative to the config's folder: run and eval both find
// it whatever the working directory (eval reads the folder from the checkpoint, since the
// config it re-reads is the copy in the output folder).
TEST(EvalTest, RelativeDataPathsResolveAgainstTheOriginalConfigFolder) {
  const auto dir = scratch_dir();
  const auto project = dir / "project";
  std::filesystem::create_directories(project / "data");
  std::string cloud;
  for (int k = 0; k < 64; ++k) {
    const double a = 2 * kPi * k / 64;
    char line[160];
    std::snprintf(line, sizeof line, "%.17g %.17g 0 %.17g %.17g 0\n", 0.5 * std::cos(a),
                  0.5 * std::sin(a), std::cos(a), std::sin(a));
    cloud += line;
  }
  write_text(project / "data" / "ring.xyz", cloud);
  write_text(project / "sdf.yaml",
             "problem: sdf\n"
             "equation: {points: data/ring.xyz, normalize: false}\n"
             "field: {type: siren, hidden: [8, 8], first_omega: 3, hidden_omega: 1}\n"
             "training: {threads: 1, batch: {surface: 16, interior: 16},\n"
             "           stages: [{optimizer: adam, steps: 2}]}\n"
             "output: {grid: [6, 6, 6], png: false}\n");
  const auto elsewhere = dir / "elsewhere";
  std::filesystem::create_directories(elsewhere);
  const auto out = dir / "out";
  Outcome o = run_nfield({"run", (project / "sdf.yaml").string(), "--out", out.string()}, elsewhere,
                         dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "5", "--out", (dir / "ev").string()},
                 elsewhere, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_TRUE(std::filesystem::exists(dir / "ev" / "solution.vti"));
}

// A pde run compared with a reference.file (two CSVs, one of a derived quantity, both named
// relative to the config): eval, run from another folder, gives the run's per-output errors at
// the files' points, key by key; with a file gone, eval is the located config error (exit 2)
// and writes no outputs.
TEST(EvalTest, ReferenceFileErrorsMatchTheRunsAndAMissingFileIsLocated) {
  const auto dir = scratch_dir();
  const auto project = dir / "project";
  std::filesystem::create_directories(project / "data");
  std::string s_table = "x,y,s\n", b_table = "x,y,b\n";
  for (int k = 0; k < 9; ++k) {
    const double y = 0.1 * (k + 0.5);
    char line[160];
    std::snprintf(line, sizeof line, "0.5,%.17g,%.17g\n", y, 0.5 * y + 0.5);  // s = a + x, a = x·y
    s_table += line;
    std::snprintf(line, sizeof line, "%.17g,0.5,%.17g\n", y, 0.5 * 0.5);  // b = y²
    b_table += line;
  }
  write_text(project / "data" / "s.csv", s_table);
  write_text(project / "data" / "b.csv", b_table);
  write_text(project / "pde.yaml",
             "problem: pde\n"
             "domain: {lower: [0, 0], upper: [1, 1]}\n"
             "outputs: [a, b]\n"
             "derived: {s: \"a + x\"}\n"
             "equation:\n"
             "  residuals:\n"
             "    - {name: fa, expr: \"a - x*y\"}\n"
             "    - {name: fb, expr: \"b - y^2\"}\n"
             "reference:\n"
             "  file:\n"
             "    - {file: data/s.csv, outputs: [s]}\n"
             "    - {file: data/b.csv, outputs: [b]}\n"
             "field: {type: siren, hidden: [8, 8], first_omega: 3, hidden_omega: 1}\n"
             "training: {threads: 1, precision: double, batch: {interior: 32},\n"
             "           stages: [{optimizer: adam, steps: 20, lr: 1.0e-2}]}\n"
             "output: {grid: [5, 5], png: false}\n");
  const auto elsewhere = dir / "elsewhere";
  std::filesystem::create_directories(elsewhere);
  const auto out = dir / "out";
  Outcome o = run_nfield({"run", (project / "pde.yaml").string(), "--out", out.string()}, elsewhere,
                         dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json ran = read_json(out / "metrics.json");
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "5", "--out", (dir / "ev").string()},
                 elsewhere, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("reference.file, 18 points"), std::string::npos) << o.out;
  const nlohmann::json evaluated = read_json(dir / "ev" / "metrics.json");
  for (const char* key : {"rel_l2", "max_abs_err", "rel_l2_s", "max_abs_err_s", "rel_l2_b", "max_abs_err_b",
                          "reference_points"}) {
    ASSERT_TRUE(ran.contains(key) && evaluated.contains(key)) << key;
    const double r = ran[key].get<double>(), e = evaluated[key].get<double>();
    EXPECT_GT(r, 0) << key;  // 20 Adam steps leave an error to compare
    EXPECT_NEAR(e, r, 1e-12 * r) << key;  // the same double field at the same points
  }
  EXPECT_FALSE(evaluated.contains("rel_l2_a")) << "a has no reference file";

  std::filesystem::remove(project / "data" / "b.csv");
  const auto gone = dir / "ev_gone";
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "5", "--out", gone.string()}, elsewhere,
                 dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("reference.file"), std::string::npos) << describe(o);
  EXPECT_NE(o.err.find("b.csv"), std::string::npos) << describe(o);
  EXPECT_NE(o.err.find("config.yaml:"), std::string::npos) << describe(o);  // located in the config copy
  EXPECT_FALSE(std::filesystem::exists(gone / "solution.vti"));
  EXPECT_FALSE(std::filesystem::exists(gone / "metrics.json"));
}

// A parametric field (constants: {nu: {range: …}}): run and eval write each held-out value's
// frames into its own folder, metrics.json lists each value's error and reports the worst, and
// the frames hold the checkpoint's field at the points with the value as their ν column.
TEST(EvalTest, ParametricFieldIsWrittenPerHeldOutValue) {
  const auto dir = scratch_dir();
  write_text(dir / "family.yaml",
             "problem: pde\n"
             "domain: {lower: [-1], upper: [1], time: [0, 1]}\n"
             "constants: {nu: {range: [0.01, 0.05]}}\n"
             "equation: {residuals: [\"u_t + u*u_x - nu*u_xx\"]}\n"
             "conditions: [{on: initial, type: value, value: \"-sin(pi*x)\", enforce: hard}]\n"
             "reference: {solution: burgers_sine, nu: nu, held_out: {nu: [0.02, 0.04]}}\n"
             "field: {type: mlp, hidden: [8, 8]}\n"
             "training: {threads: 1, batch: {interior: 32}, stages: [{optimizer: adam, steps: 3}]}\n"
             "output: {grid: [9], frames: 3, png: false}\n");
  const auto out = dir / "out";
  Outcome o = run_nfield({"run", (dir / "family.yaml").string(), "--out", out.string()}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json metrics = read_json(out / "metrics.json");
  ASSERT_EQ(metrics["held_out"].size(), 2u) << metrics.dump();
  const double worst = std::max(metrics["held_out"][0]["rel_l2"].get<double>(), metrics["held_out"][1]["rel_l2"].get<double>());
  EXPECT_EQ(metrics["rel_l2"].get<double>(), worst);
  EXPECT_NE(metrics["held_out"][0]["rel_l2"], metrics["held_out"][1]["rel_l2"]);
  EXPECT_EQ(metrics["held_out"][1]["nu"].get<double>(), 0.04);
  o = run_nfield({"eval", (out / "checkpoint.h5").string(), "--grid", "5", "--out", (dir / "ev").string()}, dir,
                 dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const fields::Field<double> field = fields::load_field<double>(io::H5Reader(out / "checkpoint.h5"));
  ASSERT_EQ(field.input_dim(), 3);
  for (const char* folder : {"held_out_nu_0.02", "held_out_nu_0.04"}) {
    ASSERT_TRUE(std::filesystem::exists(out / folder / "solution.pvd")) << folder;
    const io::ImageData last = io::read_vti(dir / "ev" / folder / "frame_0002.vti");
    const Eigen::MatrixXd& u = last.arrays.at("u");
    ASSERT_EQ(u.rows(), 5);
    // u = A + D·N with the hard initial value: A = −sin πx, D = (t − t0)/(t1 − t0) = 1 at t = 1.
    Eigen::MatrixXd x(5, 3);
    for (int i = 0; i < 5; ++i) x.row(i) << -1 + 0.5 * i, 1.0, std::string(folder) == "held_out_nu_0.02" ? 0.02 : 0.04;
    const Eigen::MatrixXd n = field.values(x);
    for (int i = 0; i < 5; ++i) EXPECT_NEAR(u(i, 0), -std::sin(kPi * x(i, 0)) + n(i, 0), 1e-12) << folder << " " << i;
  }
}

// The last JSON line of `nfield bench --accuracy` (the summary line follows it).
nlohmann::json last_case_row(const std::string& out) {
  const size_t at = out.rfind("{\"case\"");
  EXPECT_NE(at, std::string::npos) << out;
  return nlohmann::json::parse(out.substr(at, out.find('\n', at) - at));
}

// nfield bench --accuracy on a folder holding one tiny case: the table's JSON line carries
// the final error and the error after the Adam stage, both as metrics.json has them. The tiny
// case misses the table's target (1e-6): exit code 4 after a line naming it, 0 with --no-fail.
TEST(AccuracyBenchTest, ReportsTheErrorAfterEachStage) {
  const auto dir = scratch_dir();
  std::filesystem::create_directories(dir / "configs");
  write_text(dir / "configs" / "accuracy_poisson_2d.yaml",
             poisson_config("{lower: [0, 0], upper: [1, 1]}",
                            "  precision: double\n  threads: 1\n  batch: {interior: 64, boundary: 32}\n"
                            "  stages:\n    - {optimizer: adam, steps: 20, lr: 1.0e-2}\n"
                            "    - {optimizer: lbfgs, steps: 20}\n",
                            "{grid: [9, 9], png: false}"));
  Outcome o = run_nfield({"bench", "--accuracy", "--cases", "poisson_2d", "--configs",
                          (dir / "configs").string(), "--out", (dir / "out").string()},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 4) << describe(o);
  EXPECT_NE(o.out.find("\n1 of 1 cases missed their targets: poisson_2d\n"), std::string::npos) << o.out;
  const nlohmann::json metrics = read_json(dir / "out" / "poisson_2d" / "metrics.json");
  ASSERT_EQ(metrics["stages"].size(), 2u);
  const nlohmann::json row = last_case_row(o.out);
  EXPECT_EQ(row["case"], "poisson_2d");
  EXPECT_EQ(row["rel_l2"].get<double>(), metrics["rel_l2"].get<double>());
  EXPECT_EQ(row["rel_l2_after_adam"].get<double>(), metrics["stages"][0]["rel_l2"].get<double>());
  EXPECT_EQ(row["wall_s"].get<double>(), metrics["wall_s"].get<double>());
  // The last stage's error is the run's final error (same grid).
  EXPECT_EQ(metrics["stages"][1]["rel_l2"].get<double>(), metrics["rel_l2"].get<double>());
  EXPECT_LT(row["rel_l2"].get<double>(), row["rel_l2_after_adam"].get<double>());
  EXPECT_FALSE(row["met"].get<bool>());
  EXPECT_FALSE(row.contains("sign_accuracy_band"));  // no SDF there

  o = run_nfield({"bench", "--accuracy", "--no-fail", "--cases", "poisson_2d", "--configs",
                  (dir / "configs").string(), "--out", (dir / "out").string()},
                 dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("1 of 1 cases missed their targets: poisson_2d"), std::string::npos) << o.out;

  o = run_nfield({"bench", "--accuracy", "--cases", "poison_2d", "--configs", (dir / "configs").string()},
                 dir, dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("unknown case 'poison_2d' (valid: poisson_2d,"), std::string::npos) << o.err;
}

// An SDF case's JSON line carries both sign shares of its metrics.json: the whole grid's and
// that of the 5 % band around the reference surface (a few steps on the shipped sphere).
TEST(AccuracyBenchTest, ReportsBothSignSharesOfAnSdfCase) {
  const auto dir = scratch_dir();
  std::filesystem::create_directories(dir / "configs");
  const std::string sphere = (std::filesystem::path(NFIELD_SOURCE_DIR) / "data/meshes/sphere.ply").string();
  write_text(dir / "configs" / "sdf_bunny.yaml",
             "problem: sdf\nequation: {points: " + sphere + ", reference_mesh: " + sphere + "}\n"
             "field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 3}\n"
             "training:\n  threads: 1\n  batch: {surface: 128, interior: 128}\n"
             "  stages: [{optimizer: adam, steps: 30, lr: 1.0e-3}]\n"
             "output: {grid: [16, 16, 16], png: false}\n");
  // 30 steps miss the case's targets: --no-fail.
  Outcome o = run_nfield({"bench", "--accuracy", "--no-fail", "--cases", "sdf_bunny", "--configs",
                          (dir / "configs").string(), "--out", (dir / "out").string()},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json metrics = read_json(dir / "out" / "sdf_bunny" / "metrics.json");
  const nlohmann::json row = last_case_row(o.out);
  for (const char* key : {"sign_accuracy", "sign_accuracy_band"}) {
    ASSERT_TRUE(metrics[key].is_number()) << key;
    EXPECT_EQ(row[key].get<double>(), metrics[key].get<double>()) << key;
  }
  EXPECT_LT(o.out.find("sign_accuracy_band"), o.out.rfind("{\"case\"")) << "the table has its row";
}

// nfield bench --widths --thread-counts: one JSON row per thread count, width and operator,
// each with its hidden widths, its thread count and a share of the FMA peak measured for
// those threads (no timing is asserted beyond the share lying in (0, 1]; printed to four
// significant digits, a share stays above 0 however slow a step of this tiny network is on a
// loaded machine: one 2-thread step took 21 ms and its share, printed to 1e-4, read 0).
TEST(StepBenchTest, PrintsTheShareOfThePeakPerWidthAndThreadCount) {
  const auto dir = scratch_dir();
  Outcome o = run_nfield({"bench", "--op", "laplacian", "wave", "--batch", "64", "--hidden", "8", "8", "--widths", "8", "16",
                          "--thread-counts", "1", "2", "--steps", "1", "--warmup", "0", "--json"},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  std::istringstream lines(o.out);
  std::vector<nlohmann::json> rows;
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("{\"impl\"", 0) == 0) rows.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(rows.size(), 8u) << o.out;  // 2 thread counts × 2 widths × 2 operators
  for (size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k]["threads"].get<int>(), k < 4 ? 1 : 2) << rows[k];
    EXPECT_EQ(rows[k]["hidden"], (k / 2) % 2 == 0 ? "8x8" : "16x16") << rows[k];
    EXPECT_EQ(rows[k]["op"], k % 2 == 0 ? "laplacian" : "wave") << rows[k];
    EXPECT_GT(rows[k]["peak_share"].get<double>(), 0) << rows[k];
    EXPECT_LE(rows[k]["peak_share"].get<double>(), 1) << rows[k];
    // gflops and the peak are printed to 0.01, the share to 1e-4 or finer: the share recomputed from the
    // printed numbers is off by at most their rounding (large when gflops is small, as in a
    // sanitizer build).
    const double peak = rows[k]["fma_peak_gflops"].get<double>(), share = rows[k]["peak_share"].get<double>();
    const double rounding = (0.005 + share * 0.005) / (peak - 0.005) + 5e-5;
    EXPECT_NEAR(share, rows[k]["gflops"].get<double>() / peak, rounding + 1e-9) << rows[k];
  }
}

// nfield bench --nerf in a tiny setting on the shipped bunny config: the JSON line carries
// every figure bench/compare_nerf.sh reads, each positive (no timing is asserted), and the
// --block it was given in place of the config's training.block. A config without a radiance
// field is refused with exit code 2.
TEST(NerfBenchTest, PrintsTheFiguresTheComparisonReads) {
  const auto dir = scratch_dir();
  const std::string config = NFIELD_SOURCE_DIR "/configs/nerf_bunny.yaml";
  Outcome o = run_nfield({"bench", "--nerf", "--config", config, "--steps", "2", "--warmup", "1", "--rays", "8",
                          "--threads", "1", "--render-stride", "16", "--render-repeats", "1", "--block", "48", "--json"},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const std::string last = o.out.substr(o.out.rfind("{\"impl\""));
  const nlohmann::json row = nlohmann::json::parse(last);
  EXPECT_EQ(row["impl"], "nfield");
  EXPECT_EQ(row["bench"], "nerf");
  EXPECT_EQ(row["rays_per_step"].get<int>(), 8);
  EXPECT_EQ(row["threads"].get<int>(), 1);
  EXPECT_EQ(row["block"].get<int>(), 48);
  EXPECT_EQ(row["frame_pixels"].get<int>(), 64);  // every 16th pixel of every 16th row of 128²
  for (const char* key : {"rays_per_s", "median_step_ms", "anatomy_median_step_ms", "samples_per_step",
                          "network_ms", "rendering_ms", "share_network", "share_rendering", "mlp_gflops",
                          "step_gflops", "gemm_gflops",
                          "mlp_gemm_ratio", "fma_peak_gflops", "mlp_peak_ratio", "step_gflop", "frame_ms",
                          "frame_samples", "params"}) {
    ASSERT_TRUE(row.contains(key)) << key << " missing from " << last;
    EXPECT_GT(row[key].get<double>(), 0) << key << " in " << last;
  }
  EXPECT_LE(row["share_network"].get<double>() + row["share_rendering"].get<double>(), 1.0 + 1e-3);
  // No product runs above the chip's FMA ceiling: a peak below the step's rate is a broken peak.
  EXPECT_LT(row["mlp_gflops"].get<double>(), row["fma_peak_gflops"].get<double>()) << last;

  write_text(dir / "poisson.yaml",
             poisson_config("{lower: [0, 0], upper: [1, 1]}",
                            "  batch: {interior: 16, boundary: 8}\n  stages: [{optimizer: adam, steps: 1}]\n",
                            "{grid: [5, 5], png: false}"));
  o = run_nfield({"bench", "--nerf", "--config", (dir / "poisson.yaml").string()}, dir, dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("needs a radiance field"), std::string::npos) << o.err;
  // An AutoInt config trains a rate along rays, not NeRF's quadrature: refused, not timed wrongly.
  o = run_nfield({"bench", "--nerf", "--config", NFIELD_SOURCE_DIR "/configs/autoint_bunny.yaml"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("use --autoint"), std::string::npos) << o.err;
}

// nfield run on the shipped AutoInt config in a small fast setting (60 steps of 256 rays at a
// constant learning rate, a 32-wide network, 8 sections): the test views come out, their mean
// PSNR at least 15 dB (16.6 dB on the 2-core machine; an untrained field gives 9.8).
TEST(AutointRunTest, ShippedConfigTrainsInASmallSetting) {
  const auto dir = scratch_dir();
  Outcome o = run_nfield({"run", NFIELD_SOURCE_DIR "/configs/autoint_bunny.yaml", "--out", (dir / "run").string(),
                          "--set", "field.hidden=[32, 32]", "--set", "field.color_hidden=[16]", "--set",
                          "field.encoding.frequencies=6", "--set", "render.sections=8", "--set",
                          "render.samples_per_section=2", "--set", "training.batch.rays=256", "--set",
                          "training.stages[0].seconds=0", "--set", "training.stages[0].steps=60", "--set",
                          "training.stages[0].lr_final=5.0e-3"},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json metrics = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(metrics["steps"].get<int>(), 60);
  EXPECT_GE(metrics["psnr_mean"].get<double>(), 15.0) << describe(o);
  EXPECT_EQ(metrics["field_evaluations_per_ray"].get<int>(), 9);
  EXPECT_TRUE(std::filesystem::exists(dir / "run" / "test_views" / "test_007_render.png"));
}

// nfield bench --autoint in a tiny setting (half a second of training per run, small
// networks): the table and one JSON line per run come out, and the JSON file holds the same
// rows. No figure is asserted beyond the reference's own speed-up of 1.
TEST(AutointBenchTest, PrintsTheTableAndWritesItsRows) {
  const auto dir = scratch_dir();
  Outcome o = run_nfield({"bench", "--autoint", "--seconds", "0.5", "--sections", "2", "3", "--nerf-samples", "8",
                          "--no-grid", "--set", "field.hidden=[8]", "--set", "field.color_hidden=[4]", "--set",
                          "training.batch.rays=32", "--autoint-config", NFIELD_SOURCE_DIR "/configs/autoint_bunny.yaml",
                          "--nerf-config", NFIELD_SOURCE_DIR "/configs/nerf_bunny_quadrature.yaml", "--autoint-out",
                          (dir / "out").string()},
                         dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("test PSNR"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("speed-up"), std::string::npos) << o.out;
  std::vector<std::string> runs;
  for (size_t at = o.out.find("{\"bench\":\"autoint\""); at != std::string::npos;
       at = o.out.find("{\"bench\":\"autoint\"", at + 1)) {
    const nlohmann::json row = nlohmann::json::parse(o.out.substr(at, o.out.find('\n', at) - at));
    runs.push_back(row["run"]);
    for (const char* key : {"psnr_mean", "render_ms", "speedup", "psnr_loss_db", "steps"})
      EXPECT_TRUE(row.contains(key)) << key;
    if (row["run"] == "nerf_quadrature") EXPECT_EQ(row["speedup"].get<double>(), 1.0);
  }
  EXPECT_EQ(runs, (std::vector<std::string>{"nerf_quadrature", "autoint_2", "autoint_3", "autoint_2_sampler",
                                            "autoint_3_sampler"}));
  EXPECT_NE(o.out.find("4+S"), std::string::npos) << o.out;
  const nlohmann::json written = read_json(dir / "out" / "autoint_bench.json");
  ASSERT_EQ(written.size(), 5u);
  EXPECT_EQ(written[2]["evaluations_per_ray"].get<int>(), 4);
  EXPECT_FALSE(written[2]["sampling_network"].get<bool>());
  EXPECT_TRUE(written[4]["sampling_network"].get<bool>());
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "autoint_3" / "test_views" / "test_000_render.png"));
  // The sampled runs' configs name the network; the equal-section runs' do not.
  const nlohmann::json sampled = read_json(dir / "out" / "autoint_3_sampler" / "metrics.json");
  const nlohmann::json equal = read_json(dir / "out" / "autoint_3" / "metrics.json");
  EXPECT_EQ(sampled["sampling_network"].get<double>(), 1.0);
  EXPECT_EQ(equal["sampling_network"].get<double>(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Precisions, OutputsTest, ::testing::Values("double", "float"));

// nfield run on an audio integrand in a tiny setting: the outputs an AutoInt run promises are
// written (the curves, the integral and timing metrics), whatever the figures.
TEST(AutoIntRunTest, WritesCurvesAndIntegralMetrics) {
  const auto dir = scratch_dir();
  write_text(dir / "audio.yaml", "problem: autoint_1d\n"
                                 "domain: {lower: [-1], upper: [1]}\n"
                                 "equation: {audio: " NFIELD_SOURCE_DIR "/data/audio/counting_espeak.wav, "
                                 "audio_seconds: [0, 0.01], intervals: 50}\n"
                                 "field: {type: siren, hidden: [16], first_omega: 100}\n"
                                 "training: {batch: {interior: 64}, stages: [{optimizer: adam, steps: 20}]}\n"
                                 "output: {dir: out, grid: [16]}\n");
  const Outcome o = run_nfield({"run", "audio.yaml"}, dir, dir / "capture");
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("integrals: rel. L2 error"), std::string::npos) << o.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "integrand.png"));
  const std::string csv = read_text(dir / "out" / "integrand.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "x,f,fitted_integrand,antiderivative");
  const nlohmann::json metrics = nlohmann::json::parse(read_text(dir / "out" / "metrics.json"));
  EXPECT_EQ(metrics["timed_intervals"].get<double>(), 50);
  for (const char* key : {"integral_rel_l2", "integrand_rel_l2", "autoint_us_per_integral",
                          "quadrature_us_per_integral", "quadrature_evaluations_per_integral",
                          "autoint_speedup_over_quadrature"}) {
    ASSERT_TRUE(metrics.contains(key)) << key;
    EXPECT_GT(metrics[key].get<double>(), 0) << key;
  }
  EXPECT_GE(metrics["quadrature_evaluations_per_integral"].get<double>(), 15);
}

// nfield run on the shipped signal-fitting configs in a tiny setting: each writes its files;
// a bad key exits 2 with one located line and writes nothing; an Adam run resumed from its
// checkpoint ends where an uninterrupted one does.
TEST(FitRunTest, ShippedConfigsWriteTheirOutputsAndRefuseBadKeys) {
  const auto dir = scratch_dir();
  const std::vector<std::string> small = {"--set", "training.stages=[{optimizer: adam, steps: 4, lr: 1.0e-2}]",
                                          "--set", "training.batch.interior=256"};
  const auto run = [&](const std::string& config, const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> args = {"run", std::string(NFIELD_SOURCE_DIR "/configs/") + config, "--out", (dir / out).string()};
    args.insert(args.end(), small.begin(), small.end());
    args.insert(args.end(), extra.begin(), extra.end());
    return run_nfield(args, dir, dir / "capture");
  };
  Outcome o = run("fit_image.yaml", "image", {"--set", "equation.crop=24"});
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_TRUE(read_json(dir / "image" / "metrics.json").contains("ssim"));
  for (const char* file : {"reconstruction.png", "error.png", "checkpoint.h5", "config.yaml"})
    EXPECT_TRUE(std::filesystem::exists(dir / "image" / file)) << file;
  o = run("fit_audio.yaml", "audio", {"--set", "equation.seconds=[0, 0.02]"});
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_TRUE(read_json(dir / "audio" / "metrics.json").contains("snr_db"));
  EXPECT_TRUE(std::filesystem::exists(dir / "audio" / "reconstruction.wav"));
  o = run("fit_video.yaml", "video", {"--set", "equation.frames=2", "--set", "equation.crop=16"});
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_TRUE(read_json(dir / "video" / "metrics.json").contains("psnr_frame_001"));
  EXPECT_TRUE(std::filesystem::exists(dir / "video" / "frames" / "error_001.png"));
  expect_no_temporaries(dir);

  o = run("fit_image.yaml", "bad", {"--set", "equation.signal=volume"});
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_NE(o.err.find("equation.signal"), std::string::npos) << o.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
  o = run("fit_video.yaml", "bad", {"--set", "equation.path=../data/audio"});
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_NE(o.err.find("equation.path"), std::string::npos) << o.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));

  // Interrupted by SIGINT after step 21 of 80, then resumed: the same losses and
  // parameters as a run never interrupted (the pipe of 4 KiB keeps the child from running
  // far ahead of the line read, as in ResumeTest).
  const std::vector<std::string> eighty = {"--set", "equation.crop=24", "--set", "training.log_every=1", "--set",
                                           "training.threads=2", "--set",
                                           "training.stages=[{optimizer: adam, steps: 80, lr: 1.0e-2}]"};
  ASSERT_EQ(run("fit_image.yaml", "straight", eighty).code, 0);
  std::vector<std::string> args = {"run", NFIELD_SOURCE_DIR "/configs/fit_image.yaml", "--out",
                                   (dir / "interrupted").string()};
  args.insert(args.end(), small.begin(), small.end());
  args.insert(args.end(), eighty.begin(), eighty.end());
  const Interrupted stop = interrupt_after_step(args, dir, dir / "stderr.txt", 21);
  ASSERT_GE(stop.stopped_after, 21) << "no progress line for step 21";
  ASSERT_TRUE(stop.signalled);
  o = stop.outcome;
  ASSERT_EQ(o.code, 130) << describe(o);
  EXPECT_LT(read_json(dir / "interrupted" / "metrics.json")["steps"].get<long>(), 80);
  std::vector<std::string> resumed = eighty;
  resumed.insert(resumed.end(), {"--resume", (dir / "interrupted" / "checkpoint.h5").string()});
  o = run("fit_image.yaml", "resumed", resumed);
  ASSERT_EQ(o.code, 0) << describe(o);
  EXPECT_EQ(read_json(dir / "resumed" / "metrics.json")["losses"], read_json(dir / "straight" / "metrics.json")["losses"]);
  EXPECT_EQ(read_json(dir / "resumed" / "metrics.json")["psnr_db"], read_json(dir / "straight" / "metrics.json")["psnr_db"]);
  expect_same_datasets(dir / "straight" / "checkpoint.h5", dir / "resumed" / "checkpoint.h5");
}

// nfield run on the shipped BACON image config, small (a 32² crop, three scales at 8², 16²
// and 32², 40 Adam steps): the loss falls from its first step, every scale is written and
// measured, and a bad bacon key exits 2 with one located line and writes nothing.
TEST(FitRunTest, BaconConfigLossFallsAndWritesEveryScale) {
  const auto dir = scratch_dir();
  const auto run = [&](const std::string& out, int steps, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"run", NFIELD_SOURCE_DIR "/configs/fit_image_bacon.yaml", "--out", (dir / out).string(),
                                     "--set", "equation.crop=32", "--set", "field.hidden=[24, 24, 24, 24, 24]",
                                     "--set", "field.resolution=[8, 16, 32]", "--set", "training.batch.interior=1024",
                                     "--set", "training.stages=[{optimizer: adam, steps: " + std::to_string(steps) +
                                                  ", lr: 1.0e-2}]"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_nfield(args, dir, dir / "capture");
  };
  Outcome o = run("first", 1);
  ASSERT_EQ(o.code, 0) << describe(o);
  o = run("bacon", 40);
  ASSERT_EQ(o.code, 0) << describe(o);
  const nlohmann::json first = read_json(dir / "first" / "metrics.json"), last = read_json(dir / "bacon" / "metrics.json");
  EXPECT_LT(last["loss"].get<double>(), 0.2 * first["loss"].get<double>());
  for (int s = 0; s < 3; ++s) {
    const std::string tag = "_scale" + std::to_string(s);
    ASSERT_TRUE(last.contains("psnr" + tag)) << tag;
    EXPECT_EQ(last["resolution" + tag].get<double>(), 8 << s) << tag;
    EXPECT_TRUE(last.contains("psnr_full" + tag)) << tag;
    EXPECT_TRUE(std::filesystem::exists(dir / "bacon" / ("reconstruction" + tag + ".png"))) << tag;
  }
  EXPECT_EQ(last["psnr_full_scale2"], last["psnr_db"]);  // the outputs are the finest scale's
  expect_no_temporaries(dir);

  o = run("bad", 1, {"--set", "field.output_layers=[0, 3, 2]"});
  EXPECT_EQ(o.code, 2) << describe(o);
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_NE(o.err.find("field.output_layers"), std::string::npos) << o.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

}  // namespace
}  // namespace nfield::apps::testing
