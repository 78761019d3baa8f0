// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>

namespace nfield::apps {

// `nfield bench`: times full training steps (streams, reverse pass, Adam) against the
// machine's matrix-product rate measured in the same run.
void add_bench_command(CLI::App& app);

}  // namespace nfield::apps
