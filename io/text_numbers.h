// SPDX-License-Identifier: MIT
// Internal to io/: the numbers on one line of a text format (.xyz, .off).
#pragma once
#include <string_view>
#include <vector>

namespace nfield::io {

// Clears `out` and appends the whitespace-separated numbers of `line`, ignoring anything from
// a '#' on. False if a token is not a number.
bool parse_numbers(std::string_view line, std::vector<double>& out);

}  // namespace nfield::io
