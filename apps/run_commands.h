// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>

namespace nfield::apps {

// `nfield run`, `nfield validate` and `nfield eval`.
void add_run_commands(CLI::App& app);

}  // namespace nfield::apps
