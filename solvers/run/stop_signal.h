// SPDX-License-Identifier: MIT
//
// Ctrl-C and SIGTERM end a run cleanly (its outputs written from where it got to); a second
// Ctrl-C kills as usual. One guard per run, on the thread that trains; stop_requested() is
// what the training loops poll.
#pragma once

#include <atomic>
#include <csignal>

namespace nfield::solvers {

class StopSignalGuard {
 public:
  StopSignalGuard() {
    signal_received().store(0);
    struct sigaction action {};
    action.sa_handler = on_signal;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopSignalGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignalGuard(const StopSignalGuard&) = delete;
  StopSignalGuard& operator=(const StopSignalGuard&) = delete;

  static bool stop_requested() { return signal_received().load() != 0; }

 private:
  static std::atomic<int>& signal_received() {
    static std::atomic<int> received{0};
    return received;
  }
  static void on_signal(int signal) { signal_received().store(signal); }

  struct sigaction old_int_ {}, old_term_ {};
};

}  // namespace nfield::solvers
