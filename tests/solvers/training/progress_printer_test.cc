// SPDX-License-Identifier: MIT
//
// Progress lines keep coming while one optimizer step runs long (a Levenberg–Marquardt
// iteration), and a slow stage prints its steps by time, not only every log_every steps.
#include "solvers/training/progress_printer.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

namespace nfield::solvers {
namespace {

std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, f)) text += buffer;
  return text;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

Progress lm_progress(long step) {
  Progress p;
  p.stage = 1;
  p.optimizer = "lm";
  p.step = step;
  p.total_steps = 1000;
  p.loss = 1.5e-3;
  p.term_names = {"pde"};
  p.term_losses = {1.5e-3};
  p.steps_per_second = 0.25;
  p.eta_seconds = 4 * (1000 - step);
  return p;
}

// What the printer writes to a pseudo-terminal, with the process's environment as it is.
std::string printed_on_a_terminal() {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  EXPECT_GE(master, 0);
  EXPECT_EQ(grantpt(master), 0);
  EXPECT_EQ(unlockpt(master), 0);
  std::FILE* terminal = std::fopen(ptsname(master), "w");
  EXPECT_NE(terminal, nullptr);
  {
    ProgressPrinter printer({.log_every = 1, .interval = 5, .out = terminal});
    Progress last = lm_progress(1);
    last.total_steps = 1;  // a terminal's line is redrawn at most every 100 ms, and at the last step
    printer.step(last);
    printer.notice("stage 2 (lm) ended after 1 of 1000 iterations: converged");
  }
  std::fclose(terminal);
  std::string text;
  char buffer[512];
  fcntl(master, F_SETFL, O_NONBLOCK);
  for (ssize_t n; (n = read(master, buffer, sizeof buffer)) > 0;) text.append(buffer, static_cast<size_t>(n));
  close(master);
  return text;
}

// A terminal gets the line redrawn in place; the same terminal under mpirun (which gives each
// rank a pseudo-terminal, so a log of it would hold the escapes) gets plain lines.
TEST(ProgressPrinter, PlainLinesUnderAnMpiLauncher) {
  unsetenv("OMPI_COMM_WORLD_SIZE");
  unsetenv("PMI_SIZE");
  unsetenv("PMIX_RANK");
  const std::string live = printed_on_a_terminal();
  EXPECT_NE(live.find("\033[K"), std::string::npos) << live;
  setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
  const std::string plain = printed_on_a_terminal();
  unsetenv("OMPI_COMM_WORLD_SIZE");
  EXPECT_EQ(plain.find('\033'), std::string::npos) << plain;
  EXPECT_NE(plain.find("step 1/1 [lm]"), std::string::npos) << plain;
  EXPECT_NE(plain.find("ended after 1 of 1000 iterations: converged"), std::string::npos) << plain;
}

// A notice ends a line redrawn in place and stands on a line of its own.
TEST(ProgressPrinter, ANoticeStandsOnItsOwnLine) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer({.log_every = 1, .interval = 5, .out = f, .terminal = true});
    Progress last = lm_progress(1);
    last.total_steps = 1;
    printer.step(last);
    printer.notice("a notice");
  }
  const std::string text = contents(f);
  EXPECT_NE(text.find("\na notice\n"), std::string::npos) << text;
  std::fclose(f);
}

TEST(ProgressPrinter, ALongStepStillPrintsLines) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer({.log_every = 100, .interval = 0.2, .out = f, .terminal = false});
    printer.stage_begins(lm_progress(500));
    std::this_thread::sleep_for(std::chrono::milliseconds(750));
  }
  const std::string text = contents(f);
  EXPECT_GE(count(text, "step 501/1000 [lm] running for"), 2) << text;
  EXPECT_EQ(count(text, "\n"), count(text, "running for")) << text;
  std::fclose(f);
}

// After a stage's last step (its error being evaluated, a checkpoint written) the lines say
// so instead of announcing a step past the last.
TEST(ProgressPrinter, TimeAfterAStagesLastStepIsNotCalledAStep) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer({.log_every = 100, .interval = 0.2, .out = f, .terminal = false});
    printer.stage_begins(lm_progress(999));
    printer.step(lm_progress(1000));
    std::this_thread::sleep_for(std::chrono::milliseconds(750));
  }
  const std::string text = contents(f);
  EXPECT_GE(count(text, "step 1000/1000 [lm] done, the stage's last:"), 2) << text;
  EXPECT_EQ(count(text, "1001/1000"), 0) << text;
  std::fclose(f);
}

TEST(ProgressPrinter, SlowStepsPrintByTimeAndFastOnesEveryLogEvery) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer({.log_every = 100, .interval = 0.2, .out = f, .terminal = false});
    printer.stage_begins(lm_progress(500));
    printer.step(lm_progress(501));  // a stage's first step always shows
    for (long s = 502; s < 505; ++s) {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      printer.step(lm_progress(s));
    }
    for (long s = 505; s <= 700; ++s) printer.step(lm_progress(s));  // fast: 600 and 700
  }
  const std::string text = contents(f);
  // 502 … 504 each ran longer than the interval: "running" lines, then the step's own.
  for (long s : {502, 503, 504})
    EXPECT_GE(count(text, "step " + std::to_string(s) + "/1000 [lm] running for"), 1) << text;
  for (long s : {501, 502, 503, 504, 600, 700})
    EXPECT_EQ(count(text, "step " + std::to_string(s) + "/1000 [lm] loss"), 1) << s << "\n" << text;
  EXPECT_EQ(count(text, "step 650/1000"), 0) << text;
  EXPECT_NE(text.find("4.00 s/step, ETA"), std::string::npos) << text;
  std::fclose(f);
}

TEST(ProgressPrinter, SaysWhenLaterStagesAreNotInTheEta) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressPrinter printer({.log_every = 1, .interval = 5, .out = f, .terminal = false});
    Progress p = lm_progress(500);
    p.later_stages = 2;
    printer.step(p);
    p = lm_progress(501);
    p.later_stages = 1;
    printer.step(p);
    printer.step(lm_progress(502));
  }
  const std::string text = contents(f);
  EXPECT_EQ(count(text, "(this stage; 2 more stages after)"), 1) << text;
  EXPECT_EQ(count(text, "(this stage; 1 more stage after)"), 1) << text;
  EXPECT_EQ(count(text, "this stage"), 2) << text;  // the last stage's line has no note
  std::fclose(f);
}

TEST(ProgressPrinter, RejectsABadInterval) {
  EXPECT_THROW(ProgressPrinter({.interval = 0}), std::invalid_argument);
  EXPECT_THROW(ProgressPrinter({.log_every = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace nfield::solvers
