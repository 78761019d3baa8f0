// SPDX-License-Identifier: MIT
#pragma once
#include <string_view>

namespace nfield {
// The version written into metrics.json and checkpoints.
std::string_view version();
}  // namespace nfield
