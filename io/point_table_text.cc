// SPDX-License-Identifier: MIT
#include "io/point_table_text.h"
#include "io/text.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <utility>

namespace nfield::io {
namespace {

bool blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

// The lines of a text with their 1-based numbers; a '\r' before '\n' is dropped.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {
    if (text_.starts_with("\xEF\xBB\xBF")) text_.remove_prefix(3);  // a UTF-8 byte-order mark
  }
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
    line = text_.substr(pos_, end - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  int number() const { return number_; }
  // Lines after the current one (at most): a bound on the rows still to come.
  std::size_t remaining() const {
    return pos_ >= text_.size()
               ? 0
               : static_cast<std::size_t>(std::count(text_.begin() + pos_, text_.end(), '\n')) + 1;
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int number_ = 0;
};

struct Field {
  std::size_t begin, end;  // bytes of the line
};

// The fields of a row: CSV splits at every comma and trims blanks around each field (so
// "1,,2" has an empty field); whitespace splits at runs of blanks.
void split_row(std::string_view line, TextDialect dialect, std::vector<Field>& out) {
  out.clear();
  std::size_t i = 0;
  if (dialect == TextDialect::csv) {
    while (true) {
      const std::size_t comma = std::min(line.find(',', i), line.size());
      std::size_t b = i, e = comma;
      while (b < e && blank(line[b])) ++b;
      while (e > b && blank(line[e - 1])) --e;
      out.push_back({b, e});
      if (comma == line.size()) return;
      i = comma + 1;
    }
  }
  while (true) {
    while (i < line.size() && blank(line[i])) ++i;
    if (i == line.size()) return;
    std::size_t j = i;
    while (j < line.size() && !blank(line[j])) ++j;
    out.push_back({i, j});
    i = j;
  }
}

enum class Number { ok, invalid, out_of_range };

Number parse_number(std::string_view text, double& value) {
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (end - begin > 1 && *begin == '+' && begin[1] != '-') ++begin;  // from_chars takes no '+'
  const auto [stop, error] = std::from_chars(begin, end, value);
  if (error == std::errc::result_out_of_range && stop == end) return Number::out_of_range;
  return error == std::errc() && stop == end ? Number::ok : Number::invalid;
}

// A whitespace table's header split into `width` names: at runs of two or more blanks (or a
// tab, as COMSOL aligns its columns), else at single blanks with COMSOL's "(UNIT)" and
// "@ t=VALUE" joined to the name before them, else at single blanks. Nullopt if none fits.
std::optional<std::vector<std::string>> split_header(std::string_view header, std::size_t width) {
  header = trim(header);
  std::vector<std::string> wide, words;
  std::string name;
  for (std::size_t i = 0; i < header.size();) {
    std::size_t j = i;
    while (j < header.size() && !blank(header[j])) ++j;
    words.emplace_back(header.substr(i, j - i));
    name += (name.empty() ? "" : " ") + words.back();
    std::size_t k = j;
    while (k < header.size() && blank(header[k])) ++k;
    if (k - j >= 2 || header.substr(j, k - j).find('\t') != std::string_view::npos ||
        k == header.size())
      wide.push_back(std::exchange(name, {}));
    i = k;
  }
  if (wide.size() == width) return wide;
  std::vector<std::string> joined;
  bool after_at = false;
  for (const std::string& word : words) {
    if (!joined.empty() && (after_at || word.front() == '(' || word.front() == '@'))
      joined.back() += " " + word;
    else
      joined.push_back(word);
    after_at = word == "@";
  }
  if (joined.size() == width) return joined;
  if (words.size() == width) return words;
  return std::nullopt;
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& source, TextDialect dialect,
         const std::vector<std::string>& names)
      : lines_(text), source_(source), dialect_(dialect) {
    if (names.empty()) return;
    check_column_names(names, source, 0);
    table_.names = names;
    width_ = names.size();
    width_origin_ = std::to_string(width_) + " columns were named: " + join(names);
  }

  TextTable run() {
    std::string_view line;
    bool first = true;  // before the first line that is neither blank nor a comment
    while (lines_.next(line)) {
      const int number = lines_.number();
      const std::string_view text = trim(line);
      if (text.empty()) {
        if (!table_.lines.empty() && blank_after_rows_ == 0) blank_after_rows_ = number;
      } else if (is_comment(text, first)) {
        if (table_.lines.empty()) comment_ = {trim(text.substr(1)), number};
      } else if (first && !holds_numbers(line)) {
        read_header(line, number);
        first = false;
      } else {
        first = false;
        if (blank_after_rows_ > 0)
          fail(number, 0,
               "a row after the blank line " + std::to_string(blank_after_rows_) +
                   ": blank lines may only end a table (were two tables joined?)");
        add_row(line, number);
      }
    }
    if (table_.lines.empty())
      fail(0, 0,
           header_.line > 0 ? "no rows after the header (line " + std::to_string(header_.line) + ")"
                            : std::string("no rows: the table is empty"));
    return std::move(table_);
  }

 private:
  struct Text {
    std::string_view text;
    int line = 0;  // 0: none
  };

  [[noreturn]] void fail(int line, int column, std::string message) const {
    throw TableError(source_, line, column, std::move(message));
  }

  bool is_comment(std::string_view text, bool before_header) const {
    if (dialect_ == TextDialect::csv) return before_header && text.front() == '#';
    return text.front() == '%' || text.front() == '#';
  }

  // Whether `line` is a row of numbers rather than a header: no field is other than a
  // number or empty (so "1,,2" is a row with a missing value, not a header).
  bool holds_numbers(std::string_view line) {
    split_row(line, dialect_, fields_);
    double ignored;
    return std::all_of(fields_.begin(), fields_.end(), [&](const Field& f) {
      return f.begin == f.end ||
             parse_number(line.substr(f.begin, f.end - f.begin), ignored) != Number::invalid;
    });
  }

  void read_header(std::string_view line, int number) {
    header_ = {line, number};
    if (dialect_ == TextDialect::whitespace) return;  // split once the rows' width is known
    std::vector<std::string> names;
    std::vector<int> columns;
    split_csv_header(line, number, names, columns);
    if (names.size() == 1 && names[0].find(';') != std::string::npos)
      fail(number, 0,
           "the header holds semicolons but no comma: semicolon-separated files are "
           "not read (write commas between fields and '.' as the decimal point)");
    check_column_names(names, source_, number, columns);
    if (!table_.names.empty()) {
      if (names.size() != width_)
        fail(number, 0,
             "the header names " + std::to_string(names.size()) + " columns (" + join(names) +
                 "), but " + width_origin_);
      return;  // the caller's names replace the file's
    }
    set_names(std::move(names), "the header (line " + std::to_string(number) + ")");
  }

  void set_names(std::vector<std::string> names, const std::string& origin) {
    width_ = names.size();
    width_origin_ = origin + " names " + std::to_string(width_) + " columns: " + join(names);
    table_.names = std::move(names);
  }

  // CSV header names with the 1-based byte column where each starts.
  void split_csv_header(std::string_view line, int number, std::vector<std::string>& names,
                        std::vector<int>& columns) const {
    std::size_t pos = 0;
    while (true) {
      while (pos < line.size() && blank(line[pos])) ++pos;
      const std::size_t start = pos;
      std::string name;
      if (pos < line.size() && line[pos] == '"') {
        for (++pos;; ++pos) {
          if (pos >= line.size()) fail(number, int(start) + 1, "unclosed quote in the header");
          if (line[pos] != '"') {
            name += line[pos];
          } else if (pos + 1 < line.size() && line[pos + 1] == '"') {
            name += line[pos++];  // "" stands for "
          } else {
            break;
          }
        }
        for (++pos; pos < line.size() && blank(line[pos]);) ++pos;
        if (pos < line.size() && line[pos] != ',')
          fail(number, int(pos) + 1,
               "text after the closing quote of column " + std::to_string(names.size() + 1));
      } else {
        const std::size_t comma = std::min(line.find(',', pos), line.size());
        name = trim(line.substr(pos, comma - pos));
        pos = comma;
      }
      names.push_back(std::move(name));
      columns.push_back(int(start) + 1);
      if (pos >= line.size()) return;
      ++pos;  // the comma
    }
  }

  // A whitespace table learns its names from its first row's width.
  void resolve_names(std::size_t width, int row_line) {
    const std::string row = "the first row (line " + std::to_string(row_line) + ") has " +
                            std::to_string(width) + " fields";
    // A CSV's names come from its header line only; a whitespace table's may be a comment.
    const Text header = header_.line > 0                         ? header_
                        : dialect_ == TextDialect::whitespace ? comment_
                                                              : Text{};
    if (header.line == 0)
      fail(row_line, 0,
           "no column names: the first row holds numbers and no header precedes "
           "it; name the columns");
    auto names = split_header(header.text, width);
    if (!names && header_.line > 0)
      fail(header.line, 0,
           "the header ('" + std::string(trim(header.text)) +
               "') does not split into as many names as " + row);
    if (!names)
      fail(header.line, 0,
           "the last comment line before the rows ('" + std::string(header.text) +
               "') does not name their columns: " + row +
               "; if that line is no header, name the columns");
    check_column_names(*names, source_, header.line);
    set_names(std::move(*names), "the header (line " + std::to_string(header.line) + ")");
  }

  void add_row(std::string_view line, int number) {
    split_row(line, dialect_, fields_);
    if (width_ == 0) {
      resolve_names(fields_.size(), number);
      const std::size_t rows = lines_.remaining() + 1;  // this row and those after it
      table_.values.reserve(rows * width_);
      table_.lines.reserve(rows);
    }
    if (fields_.size() != width_)
      fail(number, 0,
           std::to_string(fields_.size()) + (fields_.size() == 1 ? " field" : " fields") +
               ", but " + width_origin_);
    for (std::size_t i = 0; i < width_; ++i) {
      const Field f = fields_[i];
      const std::string_view text = line.substr(f.begin, f.end - f.begin);
      double value;
      const Number status = parse_number(text, value);
      const auto where = [&] {
        return "field " + std::to_string(i + 1) + " (" + table_.names[i] + ")";
      };
      if (status == Number::invalid)
        fail(number, int(f.begin) + 1,
             where() + ": expected a number, got '" + std::string(text) + "'");
      if (status == Number::out_of_range)
        fail(number, int(f.begin) + 1,
             where() + ": " + std::string(text) + " is out of the range of double");
      if (!std::isfinite(value))
        fail(number, int(f.begin) + 1,
             where() + " is " + std::string(text) + ": only finite numbers are accepted");
      table_.values.push_back(value);
    }
    table_.lines.push_back(number);
  }

  Lines lines_;
  const std::string& source_;
  TextDialect dialect_;
  TextTable table_;
  std::vector<Field> fields_;  // of the current line, reused
  Text header_;                // a header line that is no comment
  Text comment_;               // the last comment line before the first row
  std::size_t width_ = 0;      // fields per row; 0 until known
  std::string width_origin_;   // where the width comes from, for ragged rows
  int blank_after_rows_ = 0;   // the first blank line after a row
};

}  // namespace

TextTable parse_text_table(std::string_view text, const std::string& source, TextDialect dialect,
                           const std::vector<std::string>& names) {
  return Parser(text, source, dialect, names).run();
}

void check_column_names(const std::vector<std::string>& names, const std::string& source, int line,
                        const std::vector<int>& columns) {
  std::unordered_map<std::string_view, std::size_t> first;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const int column = columns.empty() ? 0 : columns[i];
    if (names[i].empty())
      throw TableError(
          source, line, column,
          "column " + std::to_string(i + 1) + " has no name" +
              (i == 0 ? " (pandas writes its index so: use to_csv(index=False))" : ""));
    const auto [it, fresh] = first.emplace(names[i], i);
    if (!fresh)
      throw TableError(source, line, column,
                       "column " + std::to_string(i + 1) + " '" + names[i] +
                           "' has the name of column " + std::to_string(it->second + 1));
  }
}

}  // namespace nfield::io
