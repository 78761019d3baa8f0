// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>

namespace nfield::apps {

// `nfield run`, `nfield validate`, `nfield eval`, `nfield fit-code` and `nfield render`.
void add_run_commands(CLI::App& app);

}  // namespace nfield::apps
