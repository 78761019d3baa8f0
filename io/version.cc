// SPDX-License-Identifier: MIT
#include "io/version.h"

namespace nfield {
std::string_view version() { return NFIELD_VERSION; }
}  // namespace nfield
