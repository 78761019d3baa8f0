// SPDX-License-Identifier: MIT
//
// The nfield command-line program: thin dispatch onto the library.
// Exit codes: 0 done, 1 a failure while running, 2 bad input (config, arguments),
// 3 diverged (a non-finite loss, gradient or update; the last finite state written),
// 130 interrupted (outputs so far written).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <optional>

#include "apps/allocator_tuning.h"
#include "apps/bench_command.h"
#include "apps/run_commands.h"
#include "io/config.h"
#include "io/expression.h"
#include "io/version.h"
#include "solvers/training/communicator.h"

namespace {

// Under mpirun an error on one rank would leave the others waiting in a sum: end them all.
int failed(int code) {
  if (nfield::solvers::world_communicator().size() > 1) nfield::solvers::abort_all_ranks(code);
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  nfield::apps::keep_freed_blocks_in_the_heap();
  std::optional<nfield::solvers::CommunicationScope> communication;
  try {
    communication.emplace(argc, argv);  // starts MPI when run by mpirun (and built with it)
  } catch (const std::exception& e) {
    std::cerr << "nfield: error: " << e.what() << "\n";
    return 2;
  }
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
    // Every rank reads the same arguments and config and fails alike: one message, and no
    // rank is left waiting.
    if (nfield::solvers::world_communicator().rank() != 0) return e.get_exit_code() == 0 ? 0 : 2;
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const nfield::io::ConfigError& e) {
    if (nfield::solvers::world_communicator().rank() == 0)
      std::cerr << "nfield: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "nfield: error: " << e.what() << "\n";
    return failed(1);
  }
  return 0;
}
