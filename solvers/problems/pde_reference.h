// SPDX-License-Identifier: MIT
//
// The `reference:` section of `problem: pde`: what its errors are measured against.
//
//   reference: {exact: {u: "sin(pi*x)*exp(-t)", v: "0"}}    an expression per output (one
//                                                           string for one output)
//   reference: {solution: burgers_sine, nu: nu}             the Cole–Hopf solution
//                                                           (solvers/problems/burgers_reference.h)
//   reference: {solution: allen_cahn, diffusion: 1.0e-4,     the ETDRK4 solution from x² cos πx,
//               reaction: 5, modes: 1024}                   periodic on [−1, 1], t from 0
//                                                           (solvers/problems/allen_cahn_reference.h)
//   reference: {solution: burgers_sine, nu: nu,             with a parameter `nu` (a constant
//               held_out: {nu: [0.006, 0.01, 0.02]}}      given as a range): ν per point from
//                                                           its column; held_out lists the values
//                                                           the grid outputs and errors are at
//                                                           (one list per parameter, one length;
//                                                           default: each range's middle)
//   reference:
//     file: data/heat.csv          # CSV with a header, a whitespace (COMSOL) table, or
//                                  # "F.h5:/dataset" (io/point_table.h); relative to the config
//     columns: {t: time, u: u_fd}  # variable or output → column name; default: the same name
//     outputs: [u]                 # the outputs the file has; default: all of them (not
//                                  # the problem's `derived` quantities, which it may name)
//   reference:                     # several files, each with the outputs it has
//     file:
//       - {file: data/ghia_re100_u_centreline.csv, outputs: [u]}
//       - {file: data/ghia_re100_v_centreline.csv, outputs: [v], columns: {v: v_ghia}}
//
// A file gives points and values (one row per point): a column per domain variable (x, y, z
// as the domain has them, and t) and per output it has. Where the domain has time and the
// table has no t column, the COMSOL layout is read instead: coordinates, then one column per
// output and time, "u @ t=0.5" (all outputs at the same times); each row then gives one point
// per time. Points must lie in the domain (tolerance 1e-9 of each side). Refused with the
// config's location (reference.file, reference.columns.NAME, reference.outputs, or
// reference.file[i].… in the list form) and the file's: a missing or unreadable file, a
// missing column, NaN, a ragged row, a point outside the domain; an unknown or repeated name
// in `outputs`, an empty list.
//
// Why a list: published benchmarks often give each output on its own line or set of points
// (the lid-driven cavity's u along x = 0.5 and v along y = 0.5, Ghia et al. 1982); one table
// holding every output at every point would need values nobody has. An output no file has
// (the cavity's pressure) gets no error figures.
//
// Metrics.json: with an expression or a named solution, the output grid's rel_l2 and
// max_abs_err over all outputs and, with several outputs, per output (rel_l2_u,
// max_abs_err_u, …; solvers/run/run.cc), and exact_*/error_* arrays in the grid files; with
// files, the same keys at the files' points (per output: at the points of the files that
// have it; over all outputs: every value given), and reference_points (the rows of all
// files; a COMSOL row counts once per time), no grid arrays. The rel_l2 after each training
// stage is the same figure.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/compiled_expression.h"
#include "io/config.h"
#include "solvers/core/domain.h"
#include "solvers/problems/allen_cahn_reference.h"
#include "solvers/problems/burgers_reference.h"

namespace nfield::io {
struct PointTable;
}  // namespace nfield::io

namespace nfield::solvers {

// How the problem compiles an expression of the variables and constants at node[key]
// (located errors, constants noted), and evaluates a constant expression.
struct PdeExpressions {
  std::function<io::CompiledExpression(const io::ConfigNode& node, const std::string& key)> compile;
  std::function<double(const io::ConfigNode& node, const std::string& key)> constant;
};

struct ReferenceColumns;  // pde_reference.cc

// One file's points and the values of the outputs it has.
struct ReferencePoints {
  Eigen::MatrixXd points;    // n × the domain's inputs
  Eigen::MatrixXd values;    // n × outputs.size()
  std::vector<int> outputs;  // the problem's output of each column of values
};

// rel_l2 = ‖u − u*‖ / ‖u*‖ (‖u − u*‖ where u* = 0) and max |u − u*| per output and over all
// the values compared; points: how many values of each output were compared (0: none, its
// rel_l2 and max_abs are NaN).
struct OutputErrors {
  std::vector<double> rel_l2, max_abs;  // per output
  std::vector<Eigen::Index> points;     // per output
  double all_rel_l2 = 0, all_max_abs = 0;
};

class PdeReference {
 public:
  using FieldValues = std::function<Eigen::MatrixXd(const Eigen::MatrixXd& x)>;  // n × outputs

  PdeReference() = default;
  // `outputs`: the names a file may hold, of which the first `defaults` (all when 0) are
  // what a file without `outputs` holds and what `exact` gives (the problem's outputs; the
  // rest: its derived quantities).
  PdeReference(const io::ConfigNode& node, const Domain& domain, const std::vector<std::string>& outputs,
               const PdeExpressions& expressions, const std::filesystem::path& config_dir, std::size_t defaults = 0);

  // Values anywhere (an expression or a named solution).
  bool has_exact() const { return !exact_.empty() || burgers_.has_value() || allen_cahn_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const;  // n × outputs
  // Points and values from files (rows: points).
  bool has_points() const { return !files_.empty(); }
  const std::vector<ReferencePoints>& files() const { return files_; }
  Eigen::Index point_count() const;
  // `held_out`: the parameter values the field is evaluated at (each parameter_count long;
  // empty when not given).
  const std::vector<Eigen::VectorXd>& held_out() const { return held_out_; }
  // The field's errors at the files' points, per output of the problem and over all.
  OutputErrors errors(const FieldValues& field) const;

 private:
  void read_held_out(const io::ConfigNode& node);
  Eigen::MatrixXd burgers_per_row(const Eigen::MatrixXd& x) const;
  void read_exact(const io::ConfigNode& node, const std::vector<std::string>& outputs, const PdeExpressions& e);
  void read_named_solution(const io::ConfigNode& node, int outputs, const PdeExpressions& e);
  void read_burgers(const io::ConfigNode& node, const PdeExpressions& e);
  void read_allen_cahn(const io::ConfigNode& node, const PdeExpressions& e);
  void read_files(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                  const std::filesystem::path& config_dir);
  std::vector<std::string> file_outputs(const io::ConfigNode& node, const std::vector<std::string>& outputs) const;
  void read_file(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                 const std::filesystem::path& config_dir);
  void read_timed_columns(const io::PointTable& table, const ReferenceColumns& names, const Eigen::MatrixXd& space,
                          const std::vector<std::string>& outputs, ReferencePoints& file);

  Domain domain_{{0.0}, {1.0}};
  int outputs_ = 0;   // the names compared (outputs, derived quantities)
  int defaults_ = 0;  // of which a file holds without `outputs`
  std::vector<io::CompiledExpression> exact_;
  std::optional<BurgersSineOptions> burgers_;
  int burgers_column_ = -1;  // ν from this input column (a parameter); -1: burgers_->nu
  std::vector<Eigen::VectorXd> held_out_;
  std::shared_ptr<const AllenCahnReference> allen_cahn_;  // solved once at load, shared by copies
  std::vector<ReferencePoints> files_;
};

// The errors of n × outputs matrices, every value compared.
OutputErrors output_errors(const Eigen::MatrixXd& values, const Eigen::MatrixXd& reference);

}  // namespace nfield::solvers
