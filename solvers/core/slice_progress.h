// SPDX-License-Identifier: MIT
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

namespace nfield::solvers {

// The progress of evaluating a field slice by slice after training (every pixel of a 4096²
// picture, a 256³ grid: tens of seconds to minutes, which would otherwise look hung): after
// each slice, `advance` prints "WHAT, P % (S s, ETA E s)" when 5 s have passed since the
// start or the last line, and nothing once all is done.
class SliceProgress {
 public:
  explicit SliceProgress(std::string what) : what_(std::move(what)) {}

  void advance(long long done, long long total) {
    const double now = seconds();
    if (now - shown_ < 5 || done >= total || done <= 0) return;
    shown_ = now;
    const double share = static_cast<double>(done) / static_cast<double>(total);
    std::printf("%s, %.0f %% (%.0f s, ETA %.0f s)\n", what_.c_str(), 100 * share, now, now * (1 - share) / share);
    std::fflush(stdout);
  }
  // Since construction.
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  }

 private:
  std::string what_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  double shown_ = 0;
};

}  // namespace nfield::solvers
