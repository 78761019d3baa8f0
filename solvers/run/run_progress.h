// SPDX-License-Identifier: MIT
//
// A family run's training loop with the run's progress lines and a clean stop on Ctrl-C: the
// outer loops of solvers/run/meta_run.h and solvers/run/latent_run.h take their callbacks
// from here.
#pragma once

#include <functional>

#include "solvers/run/run_setup.h"
#include "solvers/run/stop_signal.h"
#include "solvers/training/progress_printer.h"
#include "solvers/training/trainer.h"

namespace nfield::solvers {

// Calls train(stop_requested, progress) under a StopSignalGuard, progress lines printed as
// training.log_every and the run's live_progress say; returns what train returns.
template <class Train>
auto train_with_progress(const RunSetup& setup, Train&& train) {
  const StopSignalGuard guard;
  ProgressPrinterOptions printing;
  printing.log_every = setup.training.log_every;
  printing.terminal = setup.live_progress;
  ProgressPrinter printer(printing);
  const std::function<bool()> stop_requested = [] { return StopSignalGuard::stop_requested(); };
  const std::function<void(const Progress&)> progress = [&printer](const Progress& p) { printer.step(p); };
  auto result = train(stop_requested, progress);
  printer.finish();
  return result;
}

}  // namespace nfield::solvers
