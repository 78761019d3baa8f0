// SPDX-License-Identifier: MIT
#include "io/point_table.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "io/hdf5_file.h"
#include "io/point_table_text.h"
#include "io/text.h"

namespace nfield::io {
namespace {

// The shortest text that reads back as `value`.
std::string number_text(double value) {
  std::array<char, 32> buffer;
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string read_whole_file(const std::filesystem::path& path, const std::string& source) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw TableError(source, 0, 0, "no such file");
  if (!std::filesystem::is_regular_file(path, ec))
    throw TableError(source, 0, 0, "not a regular file");
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw TableError(source, 0, 0, "cannot open the file for reading");
  std::string text(static_cast<std::size_t>(in.tellg()), '\0');
  in.seekg(0);
  if (!in.read(text.data(), static_cast<std::streamsize>(text.size())))
    throw TableError(source, 0, 0, "cannot read the file");
  return text;
}

TableFormat format_of(const std::filesystem::path& path, const std::string& source) {
  const std::string extension = to_lower(path.extension().string());
  if (extension == ".csv") return TableFormat::csv;
  if (extension == ".txt" || extension == ".dat") return TableFormat::whitespace;
  if (extension == ".h5" || extension == ".hdf5") return TableFormat::hdf5;
  throw TableError(source, 0, 0,
                   "unknown table format '" + extension +
                       "' (expected .csv, .txt or .dat (whitespace-separated), .h5 or .hdf5)");
}

// The column names of an HDF5 table: the caller's, else the attribute's (a list of strings
// or one comma-separated string).
std::vector<std::string> hdf5_names(const H5Reader& file, const std::string& dataset,
                                    const TableOptions& options, const std::string& source) {
  if (!options.columns.empty()) {
    check_column_names(options.columns, source, 0);
    return options.columns;
  }
  if (!file.has_attribute(dataset, options.columns_attribute))
    throw TableError(
        source, 0, 0,
        "no attribute '" + options.columns_attribute + "' naming the columns; name them");
  std::vector<std::string> names =
      file.read_attribute<std::vector<std::string>>(dataset, options.columns_attribute);
  if (names.size() == 1) {
    std::string_view all = names[0];
    names.clear();
    for (std::size_t comma; (comma = all.find(',')) != std::string_view::npos;
         all.remove_prefix(comma + 1))
      names.emplace_back(trim(all.substr(0, comma)));
    names.emplace_back(trim(all));
  }
  check_column_names(names, source, 0);
  return names;
}

PointTable read_hdf5_table(const std::filesystem::path& path, std::string dataset,
                           const TableOptions& options) {
  if (dataset.empty()) dataset = options.dataset;
  if (!dataset.empty() && dataset.front() != '/') dataset.insert(0, "/");
  PointTable table;
  table.source = path.string() + (dataset.empty() ? "" : ":" + dataset);
  const std::string& source = table.source;
  try {
    const H5Reader file(path);
    if (dataset.empty())
      throw TableError(source, 0, 0,
                       "name the dataset (" + path.string() + ":/NAME); the file holds " +
                           join(file.dataset_names()));
    if (!file.has_dataset(dataset))
      throw TableError(source, 0, 0,
                       "no such dataset; the file holds " + join(file.dataset_names()));
    const std::vector<std::uint64_t> shape = file.shape(dataset);
    if (shape.size() != 2)
      throw TableError(source, 0, 0,
                       "the dataset has " + std::to_string(shape.size()) +
                           " dimensions, expected 2 (rows × columns)");
    table.names = hdf5_names(file, dataset, options, source);
    const std::uint64_t width = table.names.size();
    if (shape[1] != width)
      throw TableError(
          source, 0, 0,
          "the dataset has shape (" + std::to_string(shape[0]) + ", " + std::to_string(shape[1]) +
              ") but " + std::to_string(width) + " columns are named: " + join(table.names) +
              (shape[0] == width ? " (is it stored transposed, one row per column?)" : ""));
    if (shape[0] == 0) throw TableError(source, 0, 0, "no rows: the table is empty");
    table.values = file.read_matrix<double>(dataset);
  } catch (const H5Error& e) {
    std::string message = e.what();
    const std::string prefix = path.string() + ": ";
    if (message.starts_with(prefix)) message.erase(0, prefix.size());
    throw TableError(source, 0, 0, message);
  }
  for (Eigen::Index i = 0; i < table.values.rows(); ++i)
    for (Eigen::Index j = 0; j < table.values.cols(); ++j)
      if (!std::isfinite(table.values(i, j)))
        throw TableError(source, 0, 0,
                         "row " + std::to_string(i) + " (from 0), column '" +
                             table.names[static_cast<std::size_t>(j)] +
                             "': " + number_text(table.values(i, j)) +
                             "; only finite numbers are accepted");
  return table;
}

// The name as the caller gave it, and as COMSOL's NAME (UNIT) @ t=TIME if it parses so.
struct Request {
  std::string_view text;
  std::optional<ComsolName> parsed;
};

bool matches(const Request& request, const ComsolName& column) {
  const ComsolName& want = *request.parsed;
  return want.name == column.name && (want.unit.empty() || want.unit == column.unit) &&
         (!want.time || column.time == want.time);
}

// Columns whose COMSOL form matches `request` (for a request that named no column exactly).
std::vector<Eigen::Index> comsol_matches(const PointTable& table, const Request& request,
                                         bool timed_only) {
  std::vector<Eigen::Index> found;
  if (!request.parsed) return found;
  for (std::size_t j = 0; j < table.names.size(); ++j) {
    const std::optional<ComsolName> column = parse_comsol_name(table.names[j]);
    if (column && (!timed_only || column->time) && matches(request, *column))
      found.push_back(static_cast<Eigen::Index>(j));
  }
  return found;
}

std::string names_of(const PointTable& table, const std::vector<Eigen::Index>& columns) {
  std::vector<std::string> names;
  for (Eigen::Index j : columns) names.push_back(table.names[static_cast<std::size_t>(j)]);
  return join(names);
}

}  // namespace

TableError::TableError(std::string file, int line, int column, std::string message)
    : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : "") +
                         (line > 0 && column > 0 ? ":" + std::to_string(column) : "") + ": " +
                         message),
      file_(std::move(file)),
      line_(line),
      column_(column),
      message_(std::move(message)) {}

PointTable read_point_table(std::string_view source, const TableOptions& options) {
  // "FILE.h5:/dataset": split at the first ".h5:" or ".hdf5:".
  std::string path_text(source), dataset;
  const std::string folded = to_lower(source);
  for (const std::string_view extension : {".h5:", ".hdf5:"}) {
    const std::size_t at = folded.find(extension);
    if (at != std::string::npos && dataset.empty() && path_text.size() == source.size()) {
      path_text = source.substr(0, at + extension.size() - 1);
      dataset = source.substr(at + extension.size());
    }
  }
  const std::filesystem::path path(path_text);
  const TableFormat format =
      options.format == TableFormat::automatic ? format_of(path, path_text) : options.format;
  if (format == TableFormat::hdf5) return read_hdf5_table(path, dataset, options);

  PointTable table;
  table.source = path_text;
  const std::string text = read_whole_file(path, table.source);
  TextTable parsed = parse_text_table(
      text, table.source, format == TableFormat::csv ? TextDialect::csv : TextDialect::whitespace,
      options.columns);
  const auto rows = static_cast<Eigen::Index>(parsed.lines.size());
  const auto cols = static_cast<Eigen::Index>(parsed.names.size());
  table.values =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          parsed.values.data(), rows, cols);
  table.names = std::move(parsed.names);
  table.lines = std::move(parsed.lines);
  return table;
}

Eigen::Index PointTable::index(std::string_view name) const {
  for (std::size_t j = 0; j < names.size(); ++j)
    if (names[j] == name) return static_cast<Eigen::Index>(j);
  const std::vector<Eigen::Index> found =
      comsol_matches(*this, {name, parse_comsol_name(name)}, false);
  if (found.size() == 1) return found.front();
  if (found.size() > 1)
    throw TableError(source, 0, 0,
                     "column '" + std::string(name) + "' is ambiguous: it may be any of " +
                         names_of(*this, found) + " (name one, e.g. with its '@ t=')");
  throw TableError(source, 0, 0,
                   "no column '" + std::string(name) + "' (columns: " + join(names) + ")");
}

bool PointTable::has(std::string_view name) const {
  if (std::find(names.begin(), names.end(), name) != names.end()) return true;
  return comsol_matches(*this, {name, parse_comsol_name(name)}, false).size() == 1;
}

Eigen::VectorXd PointTable::column(std::string_view name) const { return values.col(index(name)); }

Eigen::MatrixXd PointTable::select(const std::vector<std::string>& wanted) const {
  Eigen::MatrixXd out(values.rows(), static_cast<Eigen::Index>(wanted.size()));
  for (std::size_t k = 0; k < wanted.size(); ++k)
    out.col(static_cast<Eigen::Index>(k)) = values.col(index(wanted[k]));
  return out;
}

std::vector<TimedColumn> PointTable::times(std::string_view name) const {
  std::vector<TimedColumn> out;
  for (Eigen::Index j : comsol_matches(*this, {name, parse_comsol_name(name)}, true))
    out.push_back({*parse_comsol_name(names[static_cast<std::size_t>(j)])->time, j});
  std::sort(out.begin(), out.end(),
            [](const TimedColumn& a, const TimedColumn& b) { return a.time < b.time; });
  for (std::size_t k = 1; k < out.size(); ++k)
    if (out[k].time == out[k - 1].time)
      throw TableError(source, 0, 0,
                       "column '" + std::string(name) +
                           "' is ambiguous at t=" + number_text(out[k].time) + ": " +
                           names_of(*this, {out[k - 1].index, out[k].index}));
  return out;
}

std::string PointTable::row_location(Eigen::Index row) const {
  if (!lines.empty()) return source + ":" + std::to_string(lines[static_cast<std::size_t>(row)]);
  return source + " row " + std::to_string(row) + " (from 0)";
}

std::optional<ComsolName> parse_comsol_name(std::string_view header) {
  std::string_view text = trim(header);
  ComsolName out;
  if (const std::size_t at = text.find('@'); at != std::string_view::npos) {
    std::string_view rest = trim(text.substr(at + 1));
    if (!rest.starts_with('t')) return std::nullopt;
    rest = trim(rest.substr(1));
    if (!rest.starts_with('=')) return std::nullopt;
    rest = trim(rest.substr(1));
    if (rest.size() > 1 && rest.front() == '+' && rest[1] != '-') rest.remove_prefix(1);
    double time;
    const auto [stop, error] = std::from_chars(rest.data(), rest.data() + rest.size(), time);
    if (error != std::errc() || stop != rest.data() + rest.size() || !std::isfinite(time))
      return std::nullopt;
    out.time = time;
    text = trim(text.substr(0, at));
  }
  if (text.ends_with(')')) {
    // A unit is "(...)" after a blank: "u (m)"; "sin(x)" is a name.
    const std::size_t open = text.rfind('(');
    if (open == std::string_view::npos) return std::nullopt;
    if (open > 0 && (text[open - 1] == ' ' || text[open - 1] == '\t')) {
      out.unit = trim(text.substr(open + 1, text.size() - open - 2));
      text = trim(text.substr(0, open));
    }
  } else if (text.find('(') != std::string_view::npos) {
    return std::nullopt;
  }
  if (text.empty()) return std::nullopt;
  out.name = text;
  return out;
}

void require_inside_box(const PointTable& table, const std::vector<std::string>& columns,
                        const std::vector<double>& lower, const std::vector<double>& upper,
                        double tolerance) {
  const std::size_t n = columns.size();
  if (lower.size() != n || upper.size() != n)
    throw std::invalid_argument("require_inside_box: one lower and upper bound per column");
  if (!(tolerance >= 0)) throw std::invalid_argument("require_inside_box: tolerance < 0");
  std::vector<Eigen::Index> index(n);
  std::string box;
  for (std::size_t k = 0; k < n; ++k) {
    if (!(lower[k] <= upper[k]))
      throw std::invalid_argument("require_inside_box: lower > upper for " + columns[k]);
    index[k] = table.index(columns[k]);
    box += (k ? " × [" : "[") + number_text(lower[k]) + ", " + number_text(upper[k]) + "]";
  }
  for (Eigen::Index i = 0; i < table.rows(); ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      const double v = table.values(i, index[k]);
      const double slack = tolerance * (upper[k] - lower[k]);
      if (v >= lower[k] - slack && v <= upper[k] + slack) continue;
      std::string point;
      for (std::size_t m = 0; m < n; ++m)
        point += (m ? ", " : "") + number_text(table.values(i, index[m]));
      const std::string message =
          "the point (" + join(columns) + ") = (" + point + ") lies outside the box " + box + " (" +
          columns[k] +
          (v < lower[k] ? " < " + number_text(lower[k]) : " > " + number_text(upper[k])) +
          "; tolerance " + number_text(tolerance) + " of each side)";
      if (table.lines.empty())
        throw TableError(table.source, 0, 0, "row " + std::to_string(i) + " (from 0): " + message);
      throw TableError(table.source, table.lines[static_cast<std::size_t>(i)], 0, message);
    }
  }
}

}  // namespace nfield::io
