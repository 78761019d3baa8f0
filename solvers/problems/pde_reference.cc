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
                           const PdeExpressions& expressions, const std::filesystem::path& config_dir,
                           std::size_t defaults)
    : domain_(domain),
      outputs_(static_cast<int>(outputs.size())),
      defaults_(static_cast<int>(defaults > 0 ? defaults : outputs.size())) {
  const std::vector<std::string> own(outputs.begin(), outputs.begin() + defaults_);
  if (node.has("held_out")) read_held_out(node);
  const int given = (node.has("exact") ? 1 : 0) + (node.has("solution") ? 1 : 0) + (node.has("file") ? 1 : 0);
  node.require(given == 1, "expected one of exact, solution, file");
  if (node.has("solution"))
    read_named_solution(node, defaults_, expressions);
  else if (node.has("file"))
    read_files(node, outputs, config_dir);
  else
    read_exact(node, own, expressions);
  node.reject_unknown_keys();
}

// `held_out: {nu: [0.007, 0.012, …]}`: a list per parameter, all of one length; value i of
// each list makes held-out point i. Values must lie in the parameter's range.
void PdeReference::read_held_out(const io::ConfigNode& node) {
  const io::ConfigNode held = node.child("held_out");
  std::vector<std::string> names;
  for (const DomainParameter& p : domain_.parameters()) names.push_back(p.name);
  node.require("held_out", domain_.parameter_count() > 0 && held.is_map(),
               domain_.parameter_count() > 0
                   ? "expected a mapping of each parameter (" + io::join(names) + ") to a list of values"
                   : "held-out values are for parameters (a constant given as {range: [lower, upper]}); this "
                     "problem has none");
  for (const std::string& key : held.keys())
    if (domain_.parameter_index(key) < 0)
      throw held.error(key, "'" + key + "' is no parameter (parameters: " + io::join(names) + ")");
  std::size_t count = 0;
  for (int k = 0; k < domain_.parameter_count(); ++k) {
    const DomainParameter& p = domain_.parameters()[static_cast<std::size_t>(k)];
    if (!held.has(p.name)) throw held.error("missing the held-out values of parameter '" + p.name + "'");
    const std::vector<double> values = held.get<std::vector<double>>(p.name);
    held.require(p.name, !values.empty() && (k == 0 || values.size() == count),
                 k == 0 ? "expected a non-empty list of values"
                        : "expected " + std::to_string(count) + " values, as many as '" +
                              domain_.parameters()[0].name + "' has");
    count = values.size();
    held_out_.resize(count, Eigen::VectorXd::Zero(domain_.parameter_count()));
    for (std::size_t i = 0; i < count; ++i) {
      held.require(p.name, values[i] >= p.lower && values[i] <= p.upper,
                   "held-out value " + io::format_number(values[i]) + " lies outside the range [" +
                       io::format_number(p.lower) + ", " + io::format_number(p.upper) + "]");
      held_out_[i](k) = values[i];
    }
  }
}

Eigen::MatrixXd PdeReference::exact(const Eigen::MatrixXd& x) const {
  if (burgers_ && burgers_column_ >= 0) return burgers_per_row(x);
  if (burgers_ || allen_cahn_) {
    Eigen::MatrixXd xt(x.rows(), 2);
    xt << x.col(0), x.col(domain_.time_column());
    return burgers_ ? Eigen::MatrixXd(burgers_sine_solution(xt, *burgers_)) : Eigen::MatrixXd(allen_cahn_->evaluate(xt));
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

// `solution: NAME` and its parameters; both named solutions are of one output over one
// space variable and time.
void PdeReference::read_named_solution(const io::ConfigNode& node, int outputs, const PdeExpressions& e) {
  const std::string name = node.get_choice("solution", {"burgers_sine", "allen_cahn"});
  node.require("solution", domain_.space_dim() == 1 && domain_.has_time() && outputs == 1,
               name + " needs one output over one space variable and time (domain: lower, upper "
               "of size 1 and time)");
  if (name == "burgers_sine")
    read_burgers(node, e);
  else
    read_allen_cahn(node, e);
}

// The Cole–Hopf solution at ν = each row's parameter column: one parallel pass per distinct
// value (a grid frame has one; sampled points have as many as rows).
Eigen::MatrixXd PdeReference::burgers_per_row(const Eigen::MatrixXd& x) const {
  std::vector<double> values(x.rows());
  for (Eigen::Index r = 0; r < x.rows(); ++r) values[static_cast<std::size_t>(r)] = x(r, burgers_column_);
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  Eigen::MatrixXd out(x.rows(), 1);
  for (const double nu : values) {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index r = 0; r < x.rows(); ++r)
      if (x(r, burgers_column_) == nu) rows.push_back(r);
    Eigen::MatrixXd xt(static_cast<Eigen::Index>(rows.size()), 2);
    for (std::size_t i = 0; i < rows.size(); ++i)
      xt.row(static_cast<Eigen::Index>(i)) << x(rows[i], 0), x(rows[i], domain_.time_column());
    BurgersSineOptions options = *burgers_;
    options.nu = nu;
    const Eigen::VectorXd u = burgers_sine_solution(xt, options);
    for (std::size_t i = 0; i < rows.size(); ++i) out(rows[i], 0) = u(static_cast<Eigen::Index>(i));
  }
  return out;
}

// `nu: EXPRESSION`, or the name of a parameter (its column gives ν per point): on x ∈ [−1, 1]
// (any part of it) and t ∈ [0, 10].
void PdeReference::read_burgers(const io::ConfigNode& node, const PdeExpressions& e) {
  node.require("solution", domain_.time().first >= 0 && domain_.time().second <= 10,
               "burgers_sine is computed for t in [0, 10]");
  const int parameter = domain_.parameter_index(node.get<std::string>("nu"));
  if (parameter >= 0) {
    const DomainParameter& p = domain_.parameters()[static_cast<std::size_t>(parameter)];
    node.require("nu", p.lower >= 1e-4 && p.upper <= 1e3,
                 "expected the range of parameter '" + p.name + "' inside [1e-4, 1e3] (viscosities)");
    burgers_column_ = domain_.parameter_column(parameter);
    burgers_ = BurgersSineOptions{};
    return;
  }
  const double nu = e.constant(node, "nu");
  node.require("nu", nu >= 1e-4 && nu <= 1e3, "expected a viscosity in [1e-4, 1e3]");
  BurgersSineOptions options;
  options.nu = nu;
  burgers_ = options;
}

// `diffusion`, `reaction` (constant expressions, default 1e-4 and 5), `modes` (default
// 1024): u_t = ε u_xx + ρ(u − u³) from x² cos πx, periodic on [−1, 1], solved from t = 0
// to the domain's end time at load (0.1 s at the defaults).
void PdeReference::read_allen_cahn(const io::ConfigNode& node, const PdeExpressions& e) {
  node.require("solution", domain_.lower()[0] >= -1 - 1e-12 && domain_.upper()[0] <= 1 + 1e-12,
               "allen_cahn is computed on x in [-1, 1] (periodic)");
  node.require("solution", domain_.time().first == 0 && domain_.time().second <= 10,
               "allen_cahn is computed from its initial value x^2 cos(pi x) at t = 0, to t <= 10");
  AllenCahnOptions options;
  if (node.has("diffusion")) options.diffusion = e.constant(node, "diffusion");
  node.require("diffusion", options.diffusion > 0 && options.diffusion <= 1, "expected a diffusion in (0, 1]");
  if (node.has("reaction")) options.reaction = e.constant(node, "reaction");
  node.require("reaction", options.reaction >= 0 && options.reaction <= 100, "expected a reaction rate in [0, 100]");
  if (node.has("modes")) options.modes = node.get_in_range("modes", 16, 65536);
  node.require("modes", options.modes % 2 == 0, "expected an even number of modes");
  options.t_end = domain_.time().second;
  allen_cahn_ = std::make_shared<const AllenCahnReference>(options);
}

// The file's column of each variable, then of each output, and where to blame a missing one.
struct ReferenceColumns {
  std::vector<std::pair<std::string, std::string>> column;  // name → column
  std::optional<io::ConfigNode> columns;                     // reference.columns
  io::ConfigNode node;                                       // reference

  const std::string& of(std::size_t k) const { return column[k].second; }
  // A missing column is the columns entry's fault where it named one, else the file's.
  io::ConfigError located(std::size_t k, const io::TableError& e) const {
    const std::string& name = column[k].first;
    return columns && columns->has(name) ? columns->error(name, e.what()) : node.error("file", e.what());
  }
  Eigen::VectorXd read(const io::PointTable& table, std::size_t k) const {
    try {
      return table.column(of(k));
    } catch (const io::TableError& e) {
      throw located(k, e);
    }
  }
};

namespace {

// The columns of the variables, then of `outputs` (the file's); `columns` may name any of
// `all` (the problem's outputs).
ReferenceColumns column_names(const io::ConfigNode& node, const std::vector<std::string>& variables,
                              const std::vector<std::string>& outputs, const std::vector<std::string>& all) {
  ReferenceColumns names{{}, std::nullopt, node};
  if (node.has("columns")) {
    names.columns = node.child("columns");
    names.columns->require(names.columns->is_map(), "expected a mapping of variable and output names to column names");
    for (const std::string& key : names.columns->keys())
      if (!contains(variables, key) && !contains(all, key))
        throw names.columns->error(key, "'" + key + "' is neither a variable nor an output (variables: " +
                                            io::join(variables) + "; outputs: " + io::join(all) + ")");
  }
  for (const auto* list : {&variables, &outputs})
    for (const std::string& name : *list)
      names.column.emplace_back(name, names.columns && names.columns->has(name) ? names.columns->get<std::string>(name) : name);
  return names;
}

}  // namespace

// `file` one path or a list of {file, columns, outputs}: see the header.
void PdeReference::read_files(const io::ConfigNode& node, const std::vector<std::string>& outputs,
                              const std::filesystem::path& config_dir) {
  if (!node.has_list("file")) return read_file(node, outputs, config_dir);
  for (const char* key : {"columns", "outputs"})
    node.require(key, !node.has(key), "with a list of files, each item takes its own columns and outputs");
  const io::ConfigNode list = node.child("file");
  list.require(list.size() > 0, "expected a path or a non-empty list of {file, columns, outputs}");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const io::ConfigNode item = list.at(i);
    item.require(item.is_map(), "expected a mapping {file, columns, outputs}");
    read_file(item, outputs, config_dir);
    item.reject_unknown_keys();
  }
}

// `outputs` of one file: names of the problem's outputs or derived quantities, distinct;
// default the outputs.
std::vector<std::string> PdeReference::file_outputs(const io::ConfigNode& node,
                                                    const std::vector<std::string>& outputs) const {
  if (!node.has("outputs")) return {outputs.begin(), outputs.begin() + defaults_};
  const auto names = node.get<std::vector<std::string>>("outputs");
  node.require("outputs", !names.empty(), "expected a non-empty list of output names");
  for (std::size_t k = 0; k < names.size(); ++k) {
    node.require("outputs", contains(outputs, names[k]),
                 "'" + names[k] + "' is no output (outputs: " + io::join(outputs) + ")");
    node.require("outputs", std::find(names.begin(), names.begin() + static_cast<long>(k), names[k]) ==
                                names.begin() + static_cast<long>(k),
                 "'" + names[k] + "' is listed twice");
  }
  return names;
}

// One file: `file`, `columns` and `outputs` of `node` (see the header).
void PdeReference::read_file(const io::ConfigNode& node, const std::vector<std::string>& all_outputs,
                             const std::filesystem::path& config_dir) {
  const std::vector<std::string> outputs = file_outputs(node, all_outputs);
  ReferencePoints file;
  for (const std::string& name : outputs)
    file.outputs.push_back(
        static_cast<int>(std::find(all_outputs.begin(), all_outputs.end(), name) - all_outputs.begin()));
  const ReferenceColumns names = column_names(node, domain_.input_names(), outputs, all_outputs);
  std::string source = node.get<std::string>("file");
  if (std::filesystem::path(source).is_relative()) source = (config_dir / source).string();
  io::PointTable table;
  try {
    table = io::read_point_table(source);
  } catch (const io::TableError& e) {
    throw node.error("file", e.what());
  }
  const int d = domain_.input_dim(), n_out = static_cast<int>(outputs.size());
  const bool timed = domain_.has_time() && !table.has(names.of(static_cast<size_t>(domain_.time_column())));
  const int coordinates = timed ? domain_.space_dim() : d;
  Eigen::MatrixXd space(table.rows(), coordinates);
  std::vector<std::string> coordinate_columns;
  for (int a = 0; a < coordinates; ++a) {
    space.col(a) = names.read(table, static_cast<size_t>(a));
    coordinate_columns.push_back(table.names[static_cast<size_t>(table.index(names.of(static_cast<size_t>(a))))]);
  }
  if (timed && domain_.parameter_count() > 0)
    throw node.error("file", "a parametric field's points need a column per input (" +
                                 io::join(domain_.input_names()) + "); the table has no '" +
                                 names.of(static_cast<size_t>(domain_.time_column())) + "' column");
  std::vector<double> lower(domain_.lower()), upper(domain_.upper());
  if (!timed && domain_.has_time()) {
    lower.push_back(domain_.time().first);
    upper.push_back(domain_.time().second);
  }
  for (const DomainParameter& p : domain_.parameters()) {
    lower.push_back(p.lower);
    upper.push_back(p.upper);
  }
  try {
    io::require_inside_box(table, coordinate_columns, lower, upper);
  } catch (const io::TableError& e) {
    throw node.error("file", e.what());
  }
  if (timed) {
    read_timed_columns(table, names, space, outputs, file);
  } else {
    file.points = space;
    file.values.resize(table.rows(), n_out);
    for (int c = 0; c < n_out; ++c) file.values.col(c) = names.read(table, static_cast<size_t>(d + c));
  }
  files_.push_back(std::move(file));
}

// COMSOL layout: one column per output and time, every output at the same times.
void PdeReference::read_timed_columns(const io::PointTable& table, const ReferenceColumns& names,
                                      const Eigen::MatrixXd& space, const std::vector<std::string>& outputs,
                                      ReferencePoints& file) {
  const int d = domain_.input_dim(), n_out = static_cast<int>(outputs.size());
  const auto [t0, t1] = domain_.time();
  std::vector<std::vector<io::TimedColumn>> timed;
  for (int c = 0; c < n_out; ++c) {
    const std::size_t k = static_cast<size_t>(d + c);
    timed.push_back(table.times(names.of(k)));
    const auto& times = timed.back();
    if (times.empty())
      throw names.located(k, io::TableError(table.source, 0, 0,
                                            "no column '" + names.of(static_cast<size_t>(domain_.time_column())) +
                                                "' and no columns '" + names.of(k) + " @ t=…' (columns: " +
                                                io::join(table.names) + ")"));
    for (std::size_t j = 0; j < times.size(); ++j) {
      if (times[j].time < t0 - 1e-9 * (t1 - t0) || times[j].time > t1 + 1e-9 * (t1 - t0))
        throw names.node.error("file", table.source + ": column '" + table.names[static_cast<size_t>(times[j].index)] +
                                           "' lies outside the domain's time interval");
      if (c > 0 && (times.size() != timed[0].size() || times[j].time != timed[0][j].time))
        throw names.located(k, io::TableError(table.source, 0, 0,
                                              "output '" + outputs[static_cast<size_t>(c)] +
                                                  "' has other times than output '" + outputs[0] + "'"));
    }
  }
  const Eigen::Index rows = table.rows(), frames = static_cast<Eigen::Index>(timed[0].size());
  file.points.resize(rows * frames, d);
  file.values.resize(rows * frames, n_out);
  for (Eigen::Index j = 0; j < frames; ++j) {
    file.points.middleRows(j * rows, rows).leftCols(space.cols()) = space;
    file.points.middleRows(j * rows, rows).col(domain_.time_column()).setConstant(timed[0][static_cast<size_t>(j)].time);
    for (int c = 0; c < n_out; ++c)
      file.values.middleRows(j * rows, rows).col(c) = table.values.col(timed[static_cast<size_t>(c)][static_cast<size_t>(j)].index);
  }
}

Eigen::Index PdeReference::point_count() const {
  Eigen::Index n = 0;
  for (const ReferencePoints& file : files_) n += file.points.rows();
  return n;
}

// Per output, the squared errors and reference values of every file that has it, summed.
OutputErrors PdeReference::errors(const FieldValues& field) const {
  const std::size_t n_out = static_cast<std::size_t>(outputs_);
  std::vector<double> error2(n_out, 0.0), norm2(n_out, 0.0);
  OutputErrors e;
  e.max_abs.assign(n_out, 0.0);
  e.points.assign(n_out, 0);
  for (const ReferencePoints& file : files_) {
    const Eigen::MatrixXd values = field(file.points);
    for (std::size_t k = 0; k < file.outputs.size(); ++k) {
      const std::size_t c = static_cast<std::size_t>(file.outputs[k]);
      const Eigen::VectorXd error = values.col(file.outputs[k]) - file.values.col(static_cast<Eigen::Index>(k));
      error2[c] += error.squaredNorm();
      norm2[c] += file.values.col(static_cast<Eigen::Index>(k)).squaredNorm();
      e.max_abs[c] = std::max(e.max_abs[c], error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
      if (std::isnan(error.sum())) e.max_abs[c] = NAN;
      e.points[c] += error.size();
    }
  }
  const auto rel = [](double error, double norm) { return norm > 0 ? std::sqrt(error / norm) : std::sqrt(error); };
  double all_error2 = 0, all_norm2 = 0;
  for (std::size_t c = 0; c < n_out; ++c) {
    e.rel_l2.push_back(e.points[c] > 0 ? rel(error2[c], norm2[c]) : NAN);
    if (e.points[c] == 0) e.max_abs[c] = NAN;
    all_error2 += error2[c];
    all_norm2 += norm2[c];
    if (e.points[c] > 0) e.all_max_abs = std::isnan(e.max_abs[c]) ? NAN : std::max(e.all_max_abs, e.max_abs[c]);
  }
  e.all_rel_l2 = rel(all_error2, all_norm2);
  return e;
}

OutputErrors output_errors(const Eigen::MatrixXd& values, const Eigen::MatrixXd& reference) {
  const auto rel = [](double error, double norm) { return norm > 0 ? error / norm : error; };
  const Eigen::MatrixXd error = values - reference;
  OutputErrors e;
  for (Eigen::Index c = 0; c < error.cols(); ++c) {
    e.rel_l2.push_back(rel(error.col(c).norm(), reference.col(c).norm()));
    e.max_abs.push_back(error.col(c).cwiseAbs().maxCoeff<Eigen::PropagateNaN>());
    e.points.push_back(error.rows());
  }
  e.all_rel_l2 = rel(error.norm(), reference.norm());
  e.all_max_abs = error.cwiseAbs().maxCoeff<Eigen::PropagateNaN>();
  return e;
}

}  // namespace nfield::solvers
