// SPDX-License-Identifier: MIT
#include "solvers/training/progress_printer.h"

#include <cstdlib>

#include <unistd.h>

#include <stdexcept>
#include <string>

namespace nfield::solvers {
namespace {

std::string rate_text(double steps_per_second) {
  char buffer[48];
  if (steps_per_second >= 1 || steps_per_second <= 0)
    std::snprintf(buffer, sizeof buffer, "%.1f steps/s", steps_per_second);
  else
    std::snprintf(buffer, sizeof buffer, "%.2f s/step", 1.0 / steps_per_second);
  return buffer;
}

std::string duration_text(double seconds) {
  char buffer[48];
  if (seconds < 10)
    std::snprintf(buffer, sizeof buffer, "%.1f s", seconds);
  else if (seconds < 120)
    std::snprintf(buffer, sizeof buffer, "%.0f s", seconds);
  else if (seconds < 7200)
    std::snprintf(buffer, sizeof buffer, "%.1f min", seconds / 60);
  else
    std::snprintf(buffer, sizeof buffer, "%.1f h", seconds / 3600);
  return buffer;
}

// OpenMPI's mpirun (OMPI_COMM_WORLD_SIZE), MPICH's and Intel's (PMI_SIZE) and PMIx launchers
// such as srun (PMIX_RANK) set these in every rank's environment.
bool started_by_mpi_launcher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name)) return true;
  return false;
}

}  // namespace

ProgressPrinter::ProgressPrinter(ProgressPrinterOptions options) : options_(options) {
  if (options_.log_every < 1)
    throw std::invalid_argument("ProgressPrinterOptions.log_every = " +
                                std::to_string(options_.log_every) + ": must be >= 1");
  if (!(options_.interval > 0))
    throw std::invalid_argument("ProgressPrinterOptions.interval = " +
                                std::to_string(options_.interval) + ": must be > 0");
  tty_ = options_.terminal ? *options_.terminal
                           : isatty(fileno(options_.out)) != 0 && !started_by_mpi_launcher();
  shown_ = step_started_ = Clock::now();
  watchdog_ = std::thread([this] { watch(); });
}

ProgressPrinter::~ProgressPrinter() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  watchdog_.join();
  finish();
}

void ProgressPrinter::notice(const std::string& line) {
  const std::lock_guard lock(mutex_);
  std::fprintf(options_.out, "%s%s\n", open_line_ ? "\n" : "", line.c_str());
  std::fflush(options_.out);
  open_line_ = false;
  shown_ = Clock::now();
}

void ProgressPrinter::finish() {
  const std::lock_guard lock(mutex_);
  if (open_line_) std::fprintf(options_.out, "\n");
  std::fflush(options_.out);
  open_line_ = false;
}

void ProgressPrinter::stage_begins(const Progress& p) {
  const std::lock_guard lock(mutex_);
  last_ = p;
  have_progress_ = true;
  stage_has_steps_ = false;
  step_started_ = Clock::now();
  last_step_seconds_ = 0;
}

void ProgressPrinter::step(const Progress& p) {
  const std::lock_guard lock(mutex_);
  const auto now = Clock::now();
  const bool first_of_stage = !stage_has_steps_ || last_.stage != p.stage;
  // A step the watchdog reported as running shows its end too.
  const bool was_running = running_shown_;
  stage_has_steps_ = true;
  running_shown_ = false;
  last_step_seconds_ = std::chrono::duration<double>(now - step_started_).count();
  step_started_ = now;
  last_ = p;
  have_progress_ = true;
  const bool last = p.step == p.total_steps;
  const double silent = std::chrono::duration<double>(now - shown_).count();
  if (tty_) {
    if (!last && silent < 0.1) return;
  } else if (p.step % options_.log_every != 0 && !last && p.step != 1 && !first_of_stage &&
             !was_running && silent < options_.interval) {
    return;
  }
  print_step(p);
  shown_ = now;
}

void ProgressPrinter::print_step(const Progress& p) {
  std::string terms;
  for (size_t k = 0; k < p.term_names.size(); ++k) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, " %s %.3e", p.term_names[k].c_str(), p.term_losses[k]);
    terms += buffer;
  }
  for (const auto& [name, value] : p.extras) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, " | %s %.3g", name.c_str(), value);
    terms += buffer;
  }
  std::string later;
  if (p.later_stages > 0)
    later = " (this stage; " + std::to_string(p.later_stages) + " more stage" + (p.later_stages > 1 ? "s" : "") + " after)";
  std::fprintf(options_.out, "%sstep %ld/%ld [%s] loss %.3e |%s | %s, ETA %s%s%s",
               tty_ ? "\r\033[K" : "", p.step, p.total_steps, p.optimizer.c_str(), p.loss,
               terms.c_str(), rate_text(p.steps_per_second).c_str(),
               duration_text(p.eta_seconds).c_str(), later.c_str(), tty_ ? "" : "\n");
  std::fflush(options_.out);
  open_line_ = tty_;
}

void ProgressPrinter::print_running(Clock::time_point now) {
  const double running = std::chrono::duration<double>(now - step_started_).count();
  if (last_.step >= last_.total_steps) {  // the stage's steps are done; what follows its last is not a step
    std::fprintf(options_.out,
                 "%sstep %ld/%ld [%s] done, the stage's last: %s since, in its checkpoint and error | loss %.3e%s",
                 tty_ ? "\r\033[K" : "", last_.step, last_.total_steps, last_.optimizer.c_str(),
                 duration_text(running).c_str(), last_.loss, tty_ ? "" : "\n");
    std::fflush(options_.out);
    open_line_ = tty_;
    return;
  }
  std::string last_step;
  if (last_step_seconds_ > 0) last_step = ", last step " + duration_text(last_step_seconds_);
  std::fprintf(options_.out, "%sstep %ld/%ld [%s] running for %s%s | loss %.3e%s",
               tty_ ? "\r\033[K" : "", last_.step + 1, last_.total_steps,
               last_.optimizer.c_str(), duration_text(running).c_str(), last_step.c_str(),
               last_.loss, tty_ ? "" : "\n");
  std::fflush(options_.out);
  open_line_ = tty_;
}

void ProgressPrinter::watch() {
  std::unique_lock lock(mutex_);
  const auto tick = std::chrono::duration<double>(std::min(1.0, options_.interval / 4));
  while (!stopping_) {
    wake_.wait_for(lock, tick);
    if (stopping_ || !have_progress_) continue;
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - shown_).count() < options_.interval) continue;
    if (std::chrono::duration<double>(now - step_started_).count() < options_.interval) continue;
    print_running(now);
    shown_ = now;
    running_shown_ = true;
  }
}

}  // namespace nfield::solvers
