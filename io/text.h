// SPDX-License-Identifier: MIT
// Case folding of names (registry entries, config choices, file extensions, column names).
#pragma once

#include <string>
#include <string_view>

namespace nfield::io {

// ASCII only, whatever the process's locale: the names it folds are ASCII, and a name must
// match the same entry on every machine.
inline std::string to_lower(std::string_view text) {
  std::string out(text);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

}  // namespace nfield::io
