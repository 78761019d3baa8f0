// SPDX-License-Identifier: MIT
#include "io/point_table.h"

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "io/hdf5_file.h"
#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {

namespace fs = std::filesystem;
using testing::scratch_dir;
using testing::write_text;

// The TableError that `action` throws (a failure if it throws none).
TableError error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const TableError& e) {
    return e;
  }
  ADD_FAILURE() << "no TableError";
  return TableError("", 0, 0, "none");
}

// The message of reading `file` (a failure if it reads).
std::string read_error(const fs::path& file, const TableOptions& options = {}) {
  return error_of([&] { read_point_table(file.string(), options); }).what();
}

std::string shortest(double value) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

// Awkward but finite values: signed zero, a subnormal, extremes, plain decimals.
Eigen::MatrixXd awkward(int rows, int cols) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-10, 10);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(rng);
  m(0, 0) = -0.0;
  m(1, 0) = std::numeric_limits<double>::denorm_min();
  m(2, 0) = std::numeric_limits<double>::max();
  m(0, 1) = std::numeric_limits<double>::lowest();
  m(1, 1) = 0.1;
  return m;
}

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// `m` as text: one row per line, fields joined by `separator`.
std::string rows_text(const Eigen::MatrixXd& m, const std::string& separator,
                      const std::string& newline = "\n") {
  std::string out;
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) out += (j ? separator : "") + shortest(m(i, j));
    out += newline;
  }
  return out;
}

TEST(PointTable, CsvRoundTripsBitExactly) {
  const fs::path file = scratch_dir() / "table.csv";
  const Eigen::MatrixXd m = awkward(5, 3);
  // Comments, a quoted name with a comma and a quote, blanks around fields, CRLF line ends,
  // a '+' sign, blank trailing lines.
  write_text(file, "# made by a test\n#\n x , \"u, \"\"measured\"\"\" ,\"y\"\r\n" +
                       rows_text(m, " ,  ", "\r\n") + "+1.5,2,3\n\n  \n");
  const PointTable t = read_point_table(file.string());
  EXPECT_EQ(t.source, file.string());
  EXPECT_EQ(t.names, (std::vector<std::string>{"x", "u, \"measured\"", "y"}));
  ASSERT_EQ(t.rows(), 6);
  EXPECT_TRUE(same_bits(t.values.topRows(5), m));
  EXPECT_EQ(t.values.row(5), Eigen::RowVector3d(1.5, 2, 3));
  EXPECT_EQ(t.lines, (std::vector<int>{4, 5, 6, 7, 8, 9}));
  const Eigen::MatrixXd yx = m(Eigen::all, std::vector<int>{2, 0});
  EXPECT_TRUE(same_bits(t.select({"y", "x"}).topRows(5), yx));
  EXPECT_EQ(t.column("u, \"measured\"").head(5), m.col(1));
  EXPECT_EQ(t.row_location(2), file.string() + ":6");
}

TEST(PointTable, WhitespaceTablesRoundTrip) {
  const fs::path dir = scratch_dir();
  const Eigen::MatrixXd m = awkward(4, 3);
  write_text(dir / "a.txt", "x y\tu\n" + rows_text(m, " \t "));
  write_text(dir / "b.DAT", "# comment\n\n   " + rows_text(m, "   ") + "# trailing comment\n");
  const PointTable a = read_point_table((dir / "a.txt").string());
  EXPECT_EQ(a.names, (std::vector<std::string>{"x", "y", "u"}));
  EXPECT_TRUE(same_bits(a.values, m));
  EXPECT_EQ(a.lines, (std::vector<int>{2, 3, 4, 5}));
  // b has no header line: the caller names the columns; a comment line that does not name
  // three columns ("comment") is no header.
  const PointTable b = read_point_table((dir / "b.DAT").string(), {.columns = {"p", "q", "r"}});
  EXPECT_EQ(b.names, (std::vector<std::string>{"p", "q", "r"}));
  EXPECT_TRUE(same_bits(b.values, m));
  EXPECT_EQ(b.lines.front(), 3);
  // An explicit format reads any extension; caller names replace a file's own.
  write_text(dir / "c.out", "a,b\n1,2\n");
  const PointTable c =
      read_point_table((dir / "c.out").string(), {.format = TableFormat::csv, .columns = {"x", "y"}});
  EXPECT_EQ(c.names, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(c.values, Eigen::RowVector2d(1, 2));
  write_text(dir / "d.csv", "1,2\n3,4\n");
  EXPECT_EQ(read_point_table((dir / "d.csv").string(), {.columns = {"x", "y"}}).rows(), 2);
}

// COMSOL's "Export > Data" text: '%' metadata, then a comment line naming the columns, with
// units and times, aligned by runs of blanks.
const char* kComsol =
    "% Model:              plate.mph\n"
    "% Version:            COMSOL 6.1.0.252\n"
    "% Date:               Mar 4 2024, 10:12\n"
    "% Dimension:          2\n"
    "% Nodes:              3\n"
    "% Expressions:        3\n"
    "% Description:        Displacement\n"
    "% Length unit:        m\n"
    "% x                       y                        u (m) @ t=0              u (m) @ t=0.5"
    "            u (m) @ t=1                v (1)\n"
    "0                         0                        0.1                      0.2"
    "                      0.3                        7\n"
    "0.5                       1                        1.1                      1.2"
    "                      1.3                        8\n"
    "1                         0.25                     2.1                      2.2"
    "                      2.3                        9\n";

TEST(PointTable, ComsolHeadersWithUnitsAndTimes) {
  const fs::path file = scratch_dir() / "plate.txt";
  write_text(file, kComsol);
  const PointTable t = read_point_table(file.string());
  EXPECT_EQ(t.names, (std::vector<std::string>{"x", "y", "u (m) @ t=0", "u (m) @ t=0.5",
                                               "u (m) @ t=1", "v (1)"}));
  ASSERT_EQ(t.rows(), 3);
  EXPECT_EQ(t.lines.front(), 10);
  EXPECT_EQ(t.index("u (m) @ t=0.5"), 3);  // exactly
  EXPECT_EQ(t.index("u @ t=0.5"), 3);      // without the unit
  EXPECT_EQ(t.index("u @ t=5e-1"), 3);     // times compared as numbers
  EXPECT_EQ(t.index("u (m) @t = 1"), 4);
  EXPECT_EQ(t.index("v"), 5);
  EXPECT_EQ(t.column("u @ t=1"), Eigen::Vector3d(0.3, 1.3, 2.3));
  EXPECT_TRUE(t.has("u @ t=0"));
  EXPECT_FALSE(t.has("u"));             // ambiguous
  EXPECT_FALSE(t.has("u (mm) @ t=0"));  // another unit
  EXPECT_EQ(std::string(error_of([&] { t.index("u"); }).what()),
            file.string() + ": column 'u' is ambiguous: it may be any of u (m) @ t=0, "
                            "u (m) @ t=0.5, u (m) @ t=1 (name one, e.g. with its '@ t=')");
  EXPECT_EQ(std::string(error_of([&] { t.index("u @ t=2"); }).what()),
            file.string() + ": no column 'u @ t=2' (columns: x, y, u (m) @ t=0, u (m) @ t=0.5, "
                            "u (m) @ t=1, v (1))");
  const std::vector<TimedColumn> times = t.times("u");
  ASSERT_EQ(times.size(), 3u);
  EXPECT_EQ(times[0].time, 0);
  EXPECT_EQ(times[1].time, 0.5);
  EXPECT_EQ(times[2].index, 4);
  EXPECT_TRUE(t.times("v").empty());

  // The same header written with single blanks: "(UNIT)" and "@ t=VALUE" join their name.
  write_text(file, "% x y u (m) @ t=0 u (m) @ t=0.5\n0 0 1 2\n");
  EXPECT_EQ(read_point_table(file.string()).names,
            (std::vector<std::string>{"x", "y", "u (m) @ t=0", "u (m) @ t=0.5"}));
}

TEST(PointTable, ParsesComsolNames) {
  const auto parsed = parse_comsol_name("  T (K) @ t=1.5e-3 ");
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->name, "T");
  EXPECT_EQ(parsed->unit, "K");
  EXPECT_EQ(parsed->time, 1.5e-3);
  const auto plain = parse_comsol_name("spf.U");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->name, "spf.U");
  EXPECT_EQ(plain->unit, "");
  EXPECT_FALSE(plain->time);
  EXPECT_EQ(parse_comsol_name("sin(x)")->name, "sin(x)");  // no blank before '(': no unit
  EXPECT_EQ(parse_comsol_name("u @ t=+2")->time, 2);
  EXPECT_FALSE(parse_comsol_name("u @ s=1"));
  EXPECT_FALSE(parse_comsol_name("u @ t=abc"));
  EXPECT_FALSE(parse_comsol_name("u (m"));
  EXPECT_FALSE(parse_comsol_name(" @ t=1"));
}

TEST(PointTable, Hdf5DatasetsWithAndWithoutNames) {
  const fs::path file = scratch_dir() / "data.h5";
  const Eigen::MatrixXd m = awkward(6, 3);
  Eigen::Matrix<std::int32_t, -1, -1> ints(2, 2);
  ints << 1, 2, 3, 4;
  {
    H5Writer out(file);
    out.write("fields/u", m);
    out.write_attribute("fields/u", "columns", std::vector<std::string>{"x", "y", "u"});
    out.write("fields/v", m);
    out.write_attribute("fields/v", "columns", " x, y ,v");
    out.write("bare", ints);
    out.write("vector", Eigen::VectorXd::Ones(3));
    out.write("transposed", Eigen::MatrixXd::Zero(2, 5));
    out.write_attribute("transposed", "columns", std::vector<std::string>{"x", "u"});
    out.write("twice", Eigen::MatrixXd::Zero(2, 2));
    out.write_attribute("twice", "columns", "x,x");
    Eigen::MatrixXd nan = Eigen::MatrixXd::Zero(4, 2);
    nan(2, 1) = std::nan("");
    out.write("nan", nan);
    out.write_attribute("nan", "columns", "x,u");
    out.commit();
  }
  const std::string f = file.string();
  const PointTable u = read_point_table(f + ":/fields/u");
  EXPECT_EQ(u.source, f + ":/fields/u");
  EXPECT_EQ(u.names, (std::vector<std::string>{"x", "y", "u"}));
  EXPECT_TRUE(same_bits(u.values, m));
  EXPECT_TRUE(u.lines.empty());
  EXPECT_EQ(u.row_location(4), f + ":/fields/u row 4 (from 0)");
  EXPECT_EQ(read_point_table(f, {.dataset = "fields/v"}).names,
            (std::vector<std::string>{"x", "y", "v"}));
  const PointTable bare = read_point_table(f + ":bare", {.columns = {"a", "b"}});
  EXPECT_EQ(bare.values, Eigen::Matrix2d({{1, 2}, {3, 4}}));

  EXPECT_EQ(read_error(f + ":/bare"),
            f + ":/bare: no attribute 'columns' naming the columns; name them");
  EXPECT_EQ(read_error(f),
            f + ": name the dataset (" + f +
                ":/NAME); the file holds bare, fields/u, fields/v, nan, transposed, twice, vector");
  EXPECT_EQ(read_error(f + ":/none"), f + ":/none: no such dataset; the file holds bare, "
                                          "fields/u, fields/v, nan, transposed, twice, vector");
  EXPECT_EQ(read_error(f + ":/vector", {.columns = {"x"}}),
            f + ":/vector: the dataset has 1 dimensions, expected 2 (rows × columns)");
  EXPECT_EQ(read_error(f + ":/transposed"),
            f + ":/transposed: the dataset has shape (2, 5) but 2 columns are named: x, u (is it "
                "stored transposed, one row per column?)");
  EXPECT_EQ(read_error(f + ":/twice"), f + ":/twice: column 2 'x' has the name of column 1");
  EXPECT_EQ(read_error(f + ":/nan"),
            f + ":/nan: row 2 (from 0), column 'u': nan; only finite numbers are accepted");
  const fs::path text = file.parent_path() / "text.h5";
  write_text(text, "x,y\n1,2\n");
  EXPECT_EQ(read_error(text.string() + ":/t"), text.string() + ":/t: not an HDF5 file");
  EXPECT_EQ(read_error(file.parent_path() / "none.hdf5"),
            (file.parent_path() / "none.hdf5").string() + ": no such file");
}

TEST(PointTable, ErrorsNameFileLineAndColumn) {
  const fs::path dir = scratch_dir();
  const auto error = [&](const std::string& name, const std::string& text,
                         const TableOptions& options = {}) {
    write_text(dir / name, text);
    const TableError e = error_of([&] { read_point_table((dir / name).string(), options); });
    return std::string(e.what()).substr((dir / name).string().size());
  };
  EXPECT_EQ(read_error(dir / "missing.csv"), (dir / "missing.csv").string() + ": no such file");
  fs::create_directories(dir / "folder.csv");
  EXPECT_EQ(read_error(dir / "folder.csv"), (dir / "folder.csv").string() + ": not a regular file");
  EXPECT_EQ(error("a.xyz", "x y\n"),
            ": unknown table format '.xyz' (expected .csv, .txt or .dat (whitespace-separated), "
            ".h5 or .hdf5)");
  // Fields that are no finite numbers, at their line and byte column.
  EXPECT_EQ(error("b.csv", "x,y,u\n1,2,3\n4, abc ,6\n"),
            ":3:4: field 2 (y): expected a number, got 'abc'");
  EXPECT_EQ(error("c.csv", "x,y,u\n1,,3\n"), ":2:3: field 2 (y): expected a number, got ''");
  EXPECT_EQ(error("d.csv", "x,y\n1,2\n1,1.0D+00\n"),
            ":3:3: field 2 (y): expected a number, got '1.0D+00'");
  EXPECT_EQ(error("e.txt", "x y\n1 2\n3 nan\n"),
            ":3:3: field 2 (y) is nan: only finite numbers are accepted");
  EXPECT_EQ(error("f.csv", "x,y\n-inf,2\n"),
            ":2:1: field 1 (x) is -inf: only finite numbers are accepted");
  EXPECT_EQ(error("g.csv", "x,y\n1,1e999\n"),
            ":2:3: field 2 (y): 1e999 is out of the range of double");
  EXPECT_EQ(error("h.csv", "x\n1\n# late comment\n"),
            ":3:1: field 1 (x): expected a number, got '# late comment'");
  EXPECT_EQ(error("h2.csv", "x,y\n1,2\n# late, comment\n"),
            ":3:1: field 1 (x): expected a number, got '# late'");
  // Ragged rows.
  EXPECT_EQ(error("i.csv", "x,y,u\n1,2,3\n1,2\n"),
            ":3: 2 fields, but the header (line 1) names 3 columns: x, y, u");
  EXPECT_EQ(error("j.txt", "% x y\n1 2\n1 2 3\n"),
            ":3: 3 fields, but the header (line 1) names 2 columns: x, y");
  EXPECT_EQ(error("k.txt", "1 2\n", {.columns = {"x", "y", "u"}}),
            ":1: 2 fields, but 3 columns were named: x, y, u");
  // Empty tables.
  EXPECT_EQ(error("l.csv", ""), ": no rows: the table is empty");
  EXPECT_EQ(error("m.csv", "# only\n\n"), ": no rows: the table is empty");
  EXPECT_EQ(error("n.csv", "x,y\n\n"), ": no rows after the header (line 1)");
  // Names: duplicates, empty ones, none at all, not fitting the rows.
  EXPECT_EQ(error("o.csv", "x, y ,x\n1,2,3\n"), ":1:7: column 3 'x' has the name of column 1");
  EXPECT_EQ(error("p.txt", "% x  u (m) @ t=0  u (m) @ t=0\n1 2 3\n"),
            ":1: column 3 'u (m) @ t=0' has the name of column 2");
  EXPECT_EQ(error("q.csv", "1,2\n", {.columns = {"x", "x"}}),
            ": column 2 'x' has the name of column 1");
  EXPECT_EQ(error("r.csv", ",x,y\n0,1,2\n"),
            ":1:1: column 1 has no name (pandas writes its index so: use to_csv(index=False))");
  EXPECT_EQ(error("s.csv", "x,y,\n1,2,3\n"), ":1:5: column 3 has no name");
  EXPECT_EQ(error("t.csv", "1,2\n"),
            ":1: no column names: the first row holds numbers and no header precedes it; name the "
            "columns");
  EXPECT_EQ(error("u.txt", "% Nodes: 2\n1 2 3\n"),
            ":1: the last comment line before the rows ('Nodes: 2') does not name their columns: "
            "the first row (line 2) has 3 fields; if that line is no header, name the columns");
  EXPECT_EQ(error("v.txt", "x y\n1 2 3\n"),
            ":1: the header ('x y') does not split into as many names as the first row (line 2) "
            "has 3 fields");
  EXPECT_EQ(error("w.csv", "x,y\n1,2\n", {.columns = {"a", "b", "c"}}),
            ":1: the header names 2 columns (x, y), but 3 columns were named: a, b, c");
  // Malformed headers and layouts.
  EXPECT_EQ(error("x.csv", "x;y;u\n1;2;3\n"),
            ":1: the header holds semicolons but no comma: semicolon-separated files are not read "
            "(write commas between fields and '.' as the decimal point)");
  EXPECT_EQ(error("y.csv", "x,\"y\n1,2\n"), ":1:3: unclosed quote in the header");
  EXPECT_EQ(error("z.csv", "x,\"y\" z\n1,2\n"), ":1:7: text after the closing quote of column 2");
  EXPECT_EQ(error("aa.csv", "x,y\n1,2\n\n3,4\n"),
            ":4: a row after the blank line 3: blank lines may only end a table (were two tables "
            "joined?)");
  // The parts of the error, for a config reader that puts its own location in front.
  write_text(dir / "parts.csv", "x,y\n1,2\n3,q\n");
  const TableError e = error_of([&] { read_point_table((dir / "parts.csv").string()); });
  EXPECT_EQ(e.file(), (dir / "parts.csv").string());
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.column(), 3);
  EXPECT_EQ(e.message(), "field 2 (y): expected a number, got 'q'");
  // A missing column lists those present.
  write_text(dir / "columns.csv", "a,b,c\n1,2,3\n");
  const PointTable t = read_point_table((dir / "columns.csv").string());
  EXPECT_EQ(std::string(error_of([&] { t.column("u"); }).what()),
            (dir / "columns.csv").string() + ": no column 'u' (columns: a, b, c)");
}

TEST(PointTable, BoxCheckReportsTheFirstRowOutside) {
  const fs::path file = scratch_dir() / "points.csv";
  write_text(file, "x,y,u\n0,0,5\n1,0.5,6\n3.1416,1,7\n0.5,-0.25,8\n");
  const PointTable t = read_point_table(file.string());
  require_inside_box(t, {"x", "y"}, {0, -1}, {3.1416, 1});
  const TableError e = error_of([&] { require_inside_box(t, {"x", "y"}, {0, 0}, {std::numbers::pi, 1}); });
  EXPECT_EQ(std::string(e.what()),
            file.string() + ":4: the point (x, y) = (3.1416, 1) lies outside the box "
                            "[0, 3.141592653589793] × [0, 1] (x > 3.141592653589793; tolerance "
                            "1e-09 of each side)");
  EXPECT_EQ(e.line(), 4);
  // A tolerance covering the rounding of 3.1416 lets that row pass; the next one is below y.
  EXPECT_EQ(std::string(
                error_of([&] { require_inside_box(t, {"x", "y"}, {0, 0}, {std::numbers::pi, 1}, 1e-5); }).what()),
            file.string() + ":5: the point (x, y) = (0.5, -0.25) lies outside the box "
                            "[0, 3.141592653589793] × [0, 1] (y < 0; tolerance 1e-05 of each side)");
  EXPECT_THROW(require_inside_box(t, {"x"}, {1}, {0}), std::invalid_argument);
  EXPECT_THROW(require_inside_box(t, {"x"}, {0, 0}, {1, 1}), std::invalid_argument);
  EXPECT_THROW(require_inside_box(t, {"w"}, {0}, {1}), TableError);

  const fs::path h5 = file.parent_path() / "points.h5";
  {
    H5Writer out(h5);
    out.write("p", t.values);
    out.write_attribute("p", "columns", "x,y,u");
    out.commit();
  }
  const PointTable p = read_point_table(h5.string() + ":p");
  EXPECT_EQ(std::string(error_of([&] { require_inside_box(p, {"u"}, {5}, {7.5}); }).what()),
            h5.string() + ":/p: row 3 (from 0): the point (u) = (8) lies outside the box [5, 7.5] "
                          "(u > 7.5; tolerance 1e-09 of each side)");
}

// 10⁶ rows of 4 columns, as a reference solution or a measurement may have.
TEST(PointTable, ReadsAMillionRowCsvQuickly) {
  const fs::path file = scratch_dir() / "big.csv";
  const int rows = 1'000'000;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::string text = "x,y,t,u\n";
  text.reserve(static_cast<std::size_t>(rows) * 80);
  double last[4] = {};
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < 4; ++j) {
      last[j] = uniform(rng);
      text += shortest(last[j]);
      text += j == 3 ? '\n' : ',';
    }
  write_text(file, text);
  const auto start = std::chrono::steady_clock::now();
  const PointTable t = read_point_table(file.string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("read %d rows × 4 columns (%.1f MB) in %.3f s\n", rows, text.size() / 1e6, seconds);
  ASSERT_EQ(t.rows(), rows);
  EXPECT_EQ(t.values.row(rows - 1), Eigen::RowVector4d(last[0], last[1], last[2], last[3]));
  EXPECT_EQ(t.lines.back(), rows + 1);
  EXPECT_LT(seconds, 5.0);
}

}  // namespace
}  // namespace nfield::io
