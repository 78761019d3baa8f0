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
//   reference:
//     file: data/heat.csv          # CSV with a header, a whitespace (COMSOL) table, or
//                                  # "F.h5:/dataset" (io/point_table.h); relative to the config
//     columns: {t: time, u: u_fd}  # variable or output → column name; default: the same name
//
// A file gives points and values (one row per point): a column per domain variable (x, y, z
// as the domain has them, and t) and per output. Where the domain has time and the table has
// no t column, the COMSOL layout is read instead: coordinates, then one column per output
// and time, "u @ t=0.5" (all outputs at the same times); each row then gives one point per
// time. Points must lie in the domain (tolerance 1e-9 of each side). Refused with the
// config's location (reference.file or reference.columns.NAME) and the file's: a missing or
// unreadable file, a missing column, NaN, a ragged row, a point outside the domain.
//
// Metrics.json: with an expression or a named solution, the output grid's rel_l2 and
// max_abs_err over all outputs and, with several outputs, per output (rel_l2_u,
// max_abs_err_u, …; solvers/run.cc), and exact_*/error_* arrays in the grid files; with a
// file, the same keys at the file's points, and reference_points (their count), no grid
// arrays. The rel_l2 after each training stage is the same figure.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/compiled_expression.h"
#include "io/config.h"
#include "solvers/domain.h"
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

class PdeReference {
 public:
  PdeReference() = default;
  PdeReference(const io::ConfigNode& node, const Domain& domain, const std::vector<std::string>& outputs,
               const PdeExpressions& expressions, const std::filesystem::path& config_dir);

  // Values anywhere (an expression or a named solution).
  bool has_exact() const { return !exact_.empty() || burgers_.has_value() || allen_cahn_ != nullptr; }
  Eigen::MatrixXd exact(const Eigen::MatrixXd& x) const;  // n × outputs
  // Points and values from a file (rows: points).
  bool has_points() const { return points_.rows() > 0; }
  const Eigen::MatrixXd& points() const { return points_; }
  const Eigen::MatrixXd& values() const { return values_; }

 private:
  void read_exact(const io::ConfigNode& node, const std::vector<std::string>& outputs, const PdeExpressions& e);
  void read_named_solution(const io::ConfigNode& node, int outputs, const PdeExpressions& e);
  void read_burgers(const io::ConfigNode& node, const PdeExpressions& e);
  void read_allen_cahn(const io::ConfigNode& node, const PdeExpressions& e);
  void read_file(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                 const std::filesystem::path& config_dir);
  void read_timed_columns(const io::PointTable& table, const ReferenceColumns& names,
                          const Eigen::MatrixXd& space, const std::vector<std::string>& outputs);

  Domain domain_{{0.0}, {1.0}};
  std::vector<io::CompiledExpression> exact_;
  std::optional<BurgersSineOptions> burgers_;
  std::shared_ptr<const AllenCahnReference> allen_cahn_;  // solved once at load, shared by copies
  Eigen::MatrixXd points_, values_;
};

// rel_l2 = ‖u − u*‖ / ‖u*‖ (‖u − u*‖ where u* = 0) and max |u − u*| per column and over all
// columns of n × outputs matrices.
struct OutputErrors {
  std::vector<double> rel_l2, max_abs;  // per output
  double all_rel_l2 = 0, all_max_abs = 0;
};
OutputErrors output_errors(const Eigen::MatrixXd& values, const Eigen::MatrixXd& reference);

}  // namespace nfield::solvers
