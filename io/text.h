// SPDX-License-Identifier: MIT
// Names and numbers in messages and lookups: case folding (registry entries, config choices,
// file extensions, column names), names a config may give (outputs, constants, parts), lists
// of names, numbers in their shortest form.
#pragma once

#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace nfield::io {

// ASCII only, whatever the process's locale: the names it folds are ASCII, and a name must
// match the same entry on every machine.
inline std::string to_lower(std::string_view text) {
  std::string out(text);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

// A name a config gives: an ASCII letter, then letters and digits (and '_' with `underscore`).
inline bool is_name(std::string_view name, bool underscore) {
  const auto letter = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
  if (name.empty() || !letter(name[0])) return false;
  for (char c : name)
    if (!letter(c) && !(c >= '0' && c <= '9') && !(underscore && c == '_')) return false;
  return true;
}

// "a, b, c": the names an error message lists.
inline std::string join(const std::vector<std::string>& names, std::string_view separator = ", ") {
  std::string out;
  for (const std::string& name : names) {
    if (!out.empty()) out += separator;
    out += name;
  }
  return out;
}

// "0", "1e-13", "0.25": an option's value in a message (std::to_string prints 1e-13 as 0.000000).
inline std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace nfield::io
