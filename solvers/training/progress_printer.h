// SPDX-License-Identifier: MIT
//
// Progress lines of a training run, whatever the optimizer.
//
// A terminal gets one line redrawn in place (at most every 100 ms); a pipe or a file gets a
// line every `log_every` steps, and also whenever `interval` seconds have passed since the
// last line, so a slow optimizer still shows its steps. A watchdog thread covers the time
// inside one long step (a Levenberg–Marquardt iteration on a large Jacobian can take
// minutes): when no line has been printed for `interval` seconds it prints how long the
// current step has been running and how long the last one took, so that a user can tell
// progress from a hang.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "solvers/training/trainer.h"

namespace nfield::solvers {

struct ProgressPrinterOptions {
  int log_every = 100;       // steps between lines when the output is not a terminal
  double interval = 5.0;     // seconds: the longest silence, in and between steps; > 0
  std::FILE* out = stdout;   // not owned
  // Lines redrawn in place (true) or one per line (false); unset: redrawn when `out` is a
  // terminal and the process was not started by an MPI launcher (mpirun hands each rank a
  // pseudo-terminal, and a log of its output would hold the redraws).
  std::optional<bool> terminal;
};

class ProgressPrinter {
 public:
  explicit ProgressPrinter(ProgressPrinterOptions options);
  ~ProgressPrinter();
  ProgressPrinter(const ProgressPrinter&) = delete;
  ProgressPrinter& operator=(const ProgressPrinter&) = delete;

  // A step has finished (Trainer::Callbacks::progress).
  void step(const Progress& p);
  // A stage is starting; `p` holds the step counters and losses so far
  // (Trainer::Callbacks::stage_begins).
  void stage_begins(const Progress& p);
  // A line of its own between the progress lines (Trainer::Callbacks::notice): why a stage
  // ended early, a retry after a non-finite step.
  void notice(const std::string& line);
  // Ends a line redrawn in place.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  void print_step(const Progress& p);
  void print_running(Clock::time_point now);
  void watch();

  ProgressPrinterOptions options_;
  bool tty_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool open_line_ = false;
  bool have_progress_ = false;
  bool stage_has_steps_ = false;        // a step of the current stage has been reported
  bool running_shown_ = false;          // the watchdog reported the step now running
  Progress last_;                       // the latest step or stage start
  Clock::time_point shown_{};           // when the last line was printed
  Clock::time_point step_started_{};    // when the step now running began
  double last_step_seconds_ = 0;        // duration of the last finished step
  std::thread watchdog_;
};

}  // namespace nfield::solvers
