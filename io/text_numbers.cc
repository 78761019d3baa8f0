// SPDX-License-Identifier: MIT
#include "io/text_numbers.h"

#include <charconv>

namespace nfield::io {

bool parse_numbers(std::string_view line, std::vector<double>& out) {
  out.clear();
  line = line.substr(0, line.find('#'));
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && space(line[i])) ++i;
    if (i == line.size()) return true;
    std::size_t j = i;
    while (j < line.size() && !space(line[j])) ++j;
    const char* begin = line.data() + i;
    if (*begin == '+') ++begin;  // from_chars takes no leading '+'
    double v;
    auto [end, ec] = std::from_chars(begin, line.data() + j, v);
    if (ec != std::errc() || end != line.data() + j) return false;
    out.push_back(v);
    i = j;
  }
}

}  // namespace nfield::io
