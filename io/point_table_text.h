// SPDX-License-Identifier: MIT
// Internal to io/: the text formats of io/point_table.h (CSV and whitespace tables).
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "io/table_error.h"

namespace nfield::io {

enum class TextDialect { csv, whitespace };

// A text table as parsed, before it becomes a PointTable.
struct TextTable {
  std::vector<std::string> names;
  std::vector<double> values;  // row-major, rows × names.size()
  std::vector<int> lines;      // 1-based line of each row
};

// Parses `text` (a whole file, named `source` in messages) by the rules of io/point_table.h;
// `names`, when not empty, names the columns. Throws TableError.
TextTable parse_text_table(std::string_view text, const std::string& source, TextDialect dialect,
                           const std::vector<std::string>& names);

// Throws a TableError at `source` (line `line`, 0 for none) unless `names` are non-empty
// and unique; `columns` (if not empty) gives the 1-based byte column of each.
void check_column_names(const std::vector<std::string>& names, const std::string& source,
                        int line, const std::vector<int>& columns = {});

}  // namespace nfield::io
