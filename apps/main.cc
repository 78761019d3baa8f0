// SPDX-License-Identifier: MIT
//
// The nfield command-line program: thin dispatch onto the library.
// Exit codes: 0 done, 1 a failure while running, 2 bad input (config, arguments),
// 130 interrupted (outputs so far written).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "apps/allocator_tuning.h"
#include "apps/bench_command.h"
#include "apps/run_commands.h"
#include "io/config.h"
#include "io/expression.h"
#include "io/version.h"

int main(int argc, char** argv) {
  nfield::apps::keep_freed_blocks_in_the_heap();
  CLI::App app{"nfield: solve partial differential equations with neural fields"};
  app.set_version_flag("--version", std::string(nfield::version()));
  app.require_subcommand(1);
  nfield::apps::add_run_commands(app);
  nfield::apps::add_bench_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const nfield::io::ConfigError& e) {
    std::cerr << "nfield: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "nfield: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
