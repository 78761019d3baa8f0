// SPDX-License-Identifier: MIT
#pragma once
// Tables of points and values read from files: reference solutions (`reference.file`) and
// measurements (`data:` loss terms). A table is a matrix, one row per point, and one name per
// column; the caller picks the columns it needs by name.
//
//   PointTable t = read_point_table("data/plate.csv");          // x,y,u
//   Eigen::MatrixXd xy = t.select({"x", "y"});                    // n × 2
//   Eigen::VectorXd u = t.column("u");
//   require_inside_box(t, {"x", "y"}, {0, 0}, {1, 1});            // refuse data off the domain
//
// Formats, chosen from the extension (case-insensitive) unless TableOptions::format says:
//
//  .csv   Comma-separated. Lines starting with '#' before the header are comments. The first
//         other line is the header: names separated by commas, each optionally surrounded by
//         spaces and optionally in double quotes (inside quotes a comma belongs to the name and
//         "" stands for one "). Every following line is a row of numbers, as many as the
//         header has names, optionally surrounded by spaces.
//  .txt, .dat   Whitespace-separated (spaces or tabs), with comment lines starting with '%' or
//         '#' anywhere. Column names come from (a) a first non-comment line that is not all
//         numbers ("x y u"), else (b) the last comment line before the first row, as COMSOL
//         writes it:
//             % Model:     plate.mph
//             % Dimension: 2
//             % x          y           u (m) @ t=0      u (m) @ t=0.5
//             0            0           0.1              0.2
//         Header names may hold single spaces ("u (m) @ t=0"), so a comment header is split at
//         runs of two or more blanks if that gives as many names as the first row has fields,
//         else at single blanks with COMSOL's "(UNIT)" and "@ t=VALUE" joined to the name
//         before them, else at single blanks; if none fits, the columns must be named by the
//         caller (TableOptions::columns). A leading "%"/"#" and blanks are not part of a name.
//  .h5, .hdf5   A 2-D dataset of any numeric type, one row per point: "FILE.h5:/group/dataset"
//         (or TableOptions::dataset). Column names come from its attribute `columns`
//         (TableOptions::columns_attribute): a list of strings (h5py: `d.attrs["columns"] =
//         ["x", "y", "u"]`; numpy S arrays too) or one comma-separated string ("x,y,u").
//
// Naming by the caller: TableOptions::columns names the columns in file order. It is needed
// for a file without names (a CSV or text table whose first line holds numbers, a dataset
// without the attribute) and replaces the file's names where it has some (their count must
// match). Names are compared exactly, case-sensitively.
//
// Looking a column up (PointTable::index and everything built on it): a name matches a column
// of that exact name; failing that, COMSOL's header form NAME (UNIT) @ t=TIME is understood on
// both sides: "u @ t=0.5" finds "u (m) @ t=0.5" (times compared as numbers: "t=0.50" is the
// same), "u (m) @ t=0.5" too; "u" finds "u (m)" and is ambiguous (an error listing the
// candidates) when several times of u exist. PointTable::times lists the columns of one
// quantity by time, for time-dependent references.
//
// Refused, each with one TableError and no partial table: a missing or unreadable file; an
// unknown extension (without an explicit format); a file without rows (empty, comments only,
// a header only); a header without names where the caller gave none; an empty or duplicate
// column name; a row with more or fewer fields than the header (ragged); a field that is not a
// number (empty fields, "1.0D+00", quoted numbers, decimal commas), or out of double's range;
// NaN and infinite values (also in HDF5); a blank line followed by more rows (a blank line
// inside a table usually means two files were joined); a dataset that is not 2-D, or whose
// width differs from its names. Numbers are read by std::from_chars: decimal or scientific
// notation with an optional sign, '.' as the decimal point.
//
// Locations: TableError::what() is `FILE:LINE:COL: message`, LINE and COL 1-based (COL: the
// byte where the field starts), either left out where unknown, e.g.
//   plate.csv:7:9: field 2 (y): expected a number, got 'abc'
//   plate.csv:9: 2 fields, but the header (line 3) names 3 columns: x, y, u
//   plate.h5:/fields/u: row 17 (from 0), column 'u': nan; only finite numbers are accepted
// A config reader puts its own location in front, so the user sees which key named the file:
//   catch (const TableError& e) { throw node.error("file", e.what()); }
//
// Pitfalls:
//  * A CSV written by pandas with its index has an unnamed first column: refused (write with
//    index=False). Semicolon-separated "CSV" (some locales) is refused at the header.
//  * Points printed with few digits may lie just outside the domain (3.1416 > π):
//    require_inside_box refuses them unless given a tolerance that covers the rounding.
//  * COMSOL writes NaN at grid points outside the geometry: such a table is refused; export
//    at the mesh nodes, or drop those rows.
//  * A dataset written column-major (MATLAB, Fortran) appears transposed, shape (columns,
//    rows): refused with a hint rather than read as few long rows.
//  * Text tables are read whole into memory: the file's bytes plus twice the values while
//    they move into the matrix (10⁶ rows × 4 columns, an 80 MB CSV: about 150 MB at the
//    peak; its time: docs/experiments.md).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "io/table_error.h"

namespace nfield::io {

enum class TableFormat {
  automatic,   // from the extension
  csv,         // comma-separated with a header line
  whitespace,  // blank-separated, '%'/'#' comments (COMSOL)
  hdf5,        // a 2-D dataset
};

struct TableOptions {
  TableFormat format = TableFormat::automatic;
  // Names of the columns in file order; empty: the file's own names.
  std::vector<std::string> columns;
  // HDF5: the dataset, where the source does not name it after ".h5:".
  std::string dataset;
  // HDF5: the attribute of the dataset that names its columns.
  std::string columns_attribute = "columns";
};

// One column of a quantity at one time (see PointTable::times).
struct TimedColumn {
  double time = 0;
  Eigen::Index index = 0;
};

struct PointTable {
  std::string source;              // the file as messages name it ("F.h5:/dataset" for HDF5)
  std::vector<std::string> names;  // one per column, unique
  Eigen::MatrixXd values;          // rows × names.size(), all finite
  std::vector<int> lines;          // text formats: the 1-based line of each row; HDF5: empty

  Eigen::Index rows() const { return values.rows(); }
  // The column `name` names (see "Looking a column up" above), or a TableError that lists
  // the columns present.
  Eigen::Index index(std::string_view name) const;
  bool has(std::string_view name) const;
  Eigen::VectorXd column(std::string_view name) const;
  // The named columns side by side, in the order given.
  Eigen::MatrixXd select(const std::vector<std::string>& names) const;
  // The columns NAME @ t=TIME of quantity `name` (compared as by index), sorted by time;
  // empty when there are none.
  std::vector<TimedColumn> times(std::string_view name) const;
  // Where row `row` came from: "F.csv:17" or "F.h5:/dataset row 16 (from 0)".
  std::string row_location(Eigen::Index row) const;
};

// Reads the table at `source`: a path, or "FILE.h5:/dataset" (split at the first ".h5:" or
// ".hdf5:", case-insensitive). Throws TableError.
PointTable read_point_table(std::string_view source, const TableOptions& options = {});

// COMSOL's column header NAME (UNIT) @ t=TIME, both parts optional, blanks around them
// ignored: "u (m) @ t=0.5" -> {"u", "m", 0.5}; "x" -> {"x", "", nullopt}. Nullopt when the
// text has a '(' without ')', an '@' not followed by "t=NUMBER", or an empty name.
struct ComsolName {
  std::string name;
  std::string unit;
  std::optional<double> time;
};
std::optional<ComsolName> parse_comsol_name(std::string_view header);

// Throws a TableError at the first row whose `columns` do not lie in the box
// [lower_i − tol_i, upper_i + tol_i], tol_i = tolerance × (upper_i − lower_i): its line, its
// values and the box, e.g.
//   plate.csv:9: the point (x, y) = (1.5, 0.25) lies outside the box [0, 1] × [0, 1]
//   (x > 1; tolerance 1e-09 of each side)
// `lower` and `upper` have one value per column, lower ≤ upper (else std::invalid_argument).
void require_inside_box(const PointTable& table, const std::vector<std::string>& columns,
                        const std::vector<double>& lower, const std::vector<double>& upper,
                        double tolerance = 1e-9);

}  // namespace nfield::io
