// SPDX-License-Identifier: MIT
#include "solvers/problems/pde_reference.h"

#include <algorithm>
#include <cmath>

#include "io/point_table.h"
#include "io/text.h"

namespace nfield::solvers {

namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

PdeReference::PdeReference(const io::ConfigNode& node, const Domain& domain, const std::vector<std::string>& outputs,
                           const PdeExpressions& expressions, const std::filesystem::path& config_dir)
    : domain_(domain) {
  const int given = (node.has("exact") ? 1 : 0) + (node.has("solution") ? 1 : 0) + (node.has("file") ? 1 : 0);
  node.require(given == 1, "expected one of exact, solution, file");
  if (node.has("solution"))
    read_named_solution(node, static_cast<int>(outputs.size()), expressions);
  else if (node.has("file"))
    read_file(node, outputs, config_dir);
  else
    read_exact(node, outputs, expressions);
  node.reject_unknown_keys();
}

Eigen::MatrixXd PdeReference::exact(const Eigen::MatrixXd& x) const {
  if (burgers_) {
    Eigen::MatrixXd xt(x.rows(), 2);
    xt << x.col(0), x.col(domain_.time_column());
    return burgers_sine_solution(xt, *burgers_);
  }
  Eigen::MatrixXd out(x.rows(), static_cast<Eigen::Index>(exact_.size()));
  std::vector<double> scratch;
  for (Eigen::Index c = 0; c < out.cols(); ++c)
    exact_[static_cast<std::size_t>(c)].evaluate<double>(x.rows(), x.data(), x.rows(), out.col(c).data(), scratch);
  return out;
}

// `exact`: an expression per output ({u: "…"}), or one string for one output.
void PdeReference::read_exact(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                              const PdeExpressions& e) {
  if (!node.has_map("exact")) {
    node.require("exact", outputs.size() == 1,
                 "expected a mapping of output names to expressions (outputs: " + io::join(outputs) + ")");
    exact_.push_back(e.compile(node, "exact"));
    return;
  }
  const io::ConfigNode exact = node.child("exact");
  for (const std::string& key : exact.keys())
    if (!contains(outputs, key))
      throw exact.error(key, "'" + key + "' is no output (outputs: " + io::join(outputs) + ")");
  for (const std::string& output : outputs) {
    if (!exact.has(output)) throw exact.error("missing the exact solution of output '" + output + "'");
    exact_.push_back(e.compile(exact, output));
  }
}

// `solution: burgers_sine, nu: EXPRESSION`: on x ∈ [−1, 1] (any part of it) and t ∈ [0, 10],
// one output.
void PdeReference::read_named_solution(const io::ConfigNode& node, int outputs, const PdeExpressions& e) {
  node.get_choice("solution", {"burgers_sine"});
  node.require("solution", domain_.space_dim() == 1 && domain_.has_time() && outputs == 1,
               "burgers_sine needs one output over one space variable and time (domain: lower, upper "
               "of size 1 and time)");
  node.require("solution", domain_.time().first >= 0 && domain_.time().second <= 10,
               "burgers_sine is computed for t in [0, 10]");
  const double nu = e.constant(node, "nu");
  node.require("nu", nu >= 1e-4 && nu <= 1e3, "expected a viscosity in [1e-4, 1e3]");
  BurgersSineOptions options;
  options.nu = nu;
  burgers_ = options;
}

// `file` and `columns`: see the header.
void PdeReference::read_file(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                             const std::filesystem::path& config_dir) {
  const std::vector<std::string> variables = domain_.input_names();
  std::vector<std::pair<std::string, std::string>> column;  // name → column, variables then outputs
  std::optional<io::ConfigNode> columns;
  if (node.has("columns")) {
    columns = node.child("columns");
    columns->require(columns->is_map(), "expected a mapping of variable and output names to column names");
    for (const std::string& key : columns->keys())
      if (!contains(variables, key) && !contains(outputs, key))
        throw columns->error(key, "'" + key + "' is neither a variable nor an output (variables: " +
                                      io::join(variables) + "; outputs: " + io::join(outputs) + ")");
  }
  for (const auto* names : {&variables, &outputs})
    for (const std::string& name : *names)
      column.emplace_back(name, columns && columns->has(name) ? columns->get<std::string>(name) : name);
  // A missing column is the columns entry's fault where it named one, else the file's.
  const auto located = [&](const std::string& name, const io::TableError& e) {
    return columns && columns->has(name) ? columns->error(name, e.what()) : node.error("file", e.what());
  };
  std::string source = node.get<std::string>("file");
  if (std::filesystem::path(source).is_relative()) source = (config_dir / source).string();
  io::PointTable table;
  try {
    table = io::read_point_table(source);
  } catch (const io::TableError& e) {
    throw node.error("file", e.what());
  }
  const int d = domain_.input_dim(), n_out = static_cast<int>(outputs.size());
  const bool timed = domain_.has_time() && !table.has(column[static_cast<size_t>(domain_.time_column())].second);
  const int coordinates = timed ? domain_.space_dim() : d;
  Eigen::MatrixXd space(table.rows(), coordinates);
  for (int a = 0; a < coordinates; ++a) {
    const auto& [name, col] = column[static_cast<size_t>(a)];
    try {
      space.col(a) = table.column(col);
    } catch (const io::TableError& e) {
      throw located(name, e);
    }
  }
  std::vector<double> lower(domain_.lower()), upper(domain_.upper());
  if (!timed && domain_.has_time()) {
    lower.push_back(domain_.time().first);
    upper.push_back(domain_.time().second);
  }
  std::vector<std::string> coordinate_columns;
  for (int a = 0; a < coordinates; ++a) coordinate_columns.push_back(table.names[static_cast<size_t>(table.index(column[static_cast<size_t>(a)].second))]);
  try {
    io::require_inside_box(table, coordinate_columns, lower, upper);
  } catch (const io::TableError& e) {
    throw node.error("file", e.what());
  }
  if (!timed) {
    points_ = space;
    values_.resize(table.rows(), n_out);
    for (int c = 0; c < n_out; ++c) {
      const auto& [name, col] = column[static_cast<size_t>(d + c)];
      try {
        values_.col(c) = table.column(col);
      } catch (const io::TableError& e) {
        throw located(name, e);
      }
    }
    return;
  }
  // COMSOL layout: one column per output and time, every output at the same times.
  std::vector<std::vector<io::TimedColumn>> timed_columns;
  for (int c = 0; c < n_out; ++c) {
    const auto& [name, col] = column[static_cast<size_t>(d + c)];
    timed_columns.push_back(table.times(col));
    const auto& times = timed_columns.back();
    if (times.empty())
      throw located(name, io::TableError(table.source, 0, 0,
                                         "no column '" + column[static_cast<size_t>(domain_.time_column())].second +
                                             "' and no columns '" + col + " @ t=…' (columns: " +
                                             io::join(table.names) + ")"));
    for (std::size_t k = 0; k < times.size(); ++k) {
      if (times[k].time < domain_.time().first - 1e-9 * (domain_.time().second - domain_.time().first) ||
          times[k].time > domain_.time().second + 1e-9 * (domain_.time().second - domain_.time().first))
        throw node.error("file", table.source + ": column '" + table.names[static_cast<size_t>(times[k].index)] +
                                     "' lies outside the domain's time interval");
      if (c > 0 && (times.size() != timed_columns[0].size() || times[k].time != timed_columns[0][k].time))
        throw located(name, io::TableError(table.source, 0, 0,
                                           "output '" + name + "' has other times than output '" + outputs[0] + "'"));
    }
  }
  const Eigen::Index rows = table.rows(), frames = static_cast<Eigen::Index>(timed_columns[0].size());
  points_.resize(rows * frames, d);
  values_.resize(rows * frames, n_out);
  for (Eigen::Index k = 0; k < frames; ++k) {
    points_.middleRows(k * rows, rows).leftCols(coordinates) = space;
    points_.middleRows(k * rows, rows).col(domain_.time_column()).setConstant(timed_columns[0][static_cast<size_t>(k)].time);
    for (int c = 0; c < n_out; ++c)
      values_.middleRows(k * rows, rows).col(c) = table.values.col(timed_columns[static_cast<size_t>(c)][static_cast<size_t>(k)].index);
  }
}

OutputErrors output_errors(const Eigen::MatrixXd& values, const Eigen::MatrixXd& reference) {
  const auto rel = [](double error, double norm) { return norm > 0 ? error / norm : error; };
  const Eigen::MatrixXd error = values - reference;
  OutputErrors e;
  for (Eigen::Index c = 0; c < error.cols(); ++c) {
    e.rel_l2.push_back(rel(error.col(c).norm(), reference.col(c).norm()));
    e.max_abs.push_back(error.col(c).cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
  }
  e.all_rel_l2 = rel(error.norm(), reference.norm());
  e.all_max_abs = error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>();
  return e;
}

}  // namespace nfield::solvers
