// SPDX-License-Identifier: MIT
// Running the nfield program from tests: a child process with its stdout read through a
// pipe (line by line if wanted), its stderr kept, its exit code or signal reported.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace nfield::apps::testing {

inline std::filesystem::path nfield_program() {
  return std::filesystem::path(NFIELD_BINARY_DIR) / "bin" / "nfield";
}

// An empty folder <build>/test_scratch/apps/<suite>.<test>, emptied again on each call.
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  std::replace(name.begin(), name.end(), '/', '_');
  const auto dir = std::filesystem::path(NFIELD_BINARY_DIR) / "test_scratch" / "apps" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every file and folder below `dir`, as paths relative to it, sorted.
inline std::vector<std::string> tree(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    names.push_back(std::filesystem::relative(e.path(), dir).string());
  std::sort(names.begin(), names.end());
  return names;
}

// A small Poisson config (u* = sin πx sin πy, a 16 x 16 SIREN) with the given `domain`, lines
// of `training:` and `output:`.
inline std::string poisson_config(const std::string& domain, const std::string& training,
                                  const std::string& output) {
  return "problem: poisson\n"
         "domain: " + domain + "\n"
         "equation:\n"
         "  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n"
         "  exact: \"sin(pi*x)*sin(pi*y)\"\n"
         "conditions:\n"
         "  - {on: boundary, type: dirichlet, value: \"0\"}\n"
         "field: {type: siren, hidden: [16, 16], first_omega: 3, hidden_omega: 1}\n"
         "training:\n" + training +
         "output: " + output + "\n";
}

struct Outcome {
  int code = -1;        // exit status; 128 + N when killed by signal N
  bool signaled = false;
  std::string out, err;
};

// A running `nfield ARGS...` in folder `cwd`; stdout comes through a pipe, stderr goes to
// `stderr_file` (outside the folders under test).
class Child {
 public:
  Child(const std::vector<std::string>& args, const std::filesystem::path& cwd,
        std::filesystem::path stderr_file, int pipe_bytes = 0)
      : stderr_file_(std::move(stderr_file)) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
    // A small pipe holds the child back once the reader stops reading.
    if (pipe_bytes > 0) fcntl(fds[0], F_SETPIPE_SZ, pipe_bytes);
    std::vector<std::string> argv_text{nfield_program().string()};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string err_path = stderr_file_.string();
    const std::string dir = cwd.string();
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      if (chdir(dir.c_str()) != 0) _exit(126);
      const int err = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (err < 0) _exit(126);
      dup2(fds[1], 1);
      dup2(err, 2);
      close(fds[0]);
      close(fds[1]);
      close(err);
      execv(argv[0], argv.data());
      _exit(127);
    }
    close(fds[1]);
    out_ = fds[0];
  }
  ~Child() {
    if (out_ >= 0) close(out_);
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }

  // The next line of stdout (without '\n'); false at end of output or after `timeout`.
  // Reads byte by byte, so that what the child wrote after that line stays in the pipe
  // (and a small pipe holds the child back).
  bool read_line(std::string& line, std::chrono::seconds timeout = std::chrono::seconds(60),
                 size_t chunk_bytes = 1) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      const auto newline = buffer_.find('\n');
      if (newline != std::string::npos) {
        line = buffer_.substr(0, newline);
        buffer_.erase(0, newline + 1);
        return true;
      }
      if (eof_) {
        if (buffer_.empty()) return false;
        line.swap(buffer_);
        buffer_.clear();
        return true;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return false;
      pollfd p{out_, POLLIN, 0};
      const int ready = poll(&p, 1, static_cast<int>(left));
      if (ready < 0 && errno == EINTR) continue;
      if (ready <= 0) return false;
      char chunk[4096];
      const ssize_t n = read(out_, chunk, std::min(chunk_bytes, sizeof chunk));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        eof_ = true;
      } else {
        buffer_.append(chunk, static_cast<size_t>(n));
        all_.append(chunk, static_cast<size_t>(n));
      }
    }
  }

  // Reads stdout to its end and waits for the exit (killing the child after `timeout`).
  Outcome finish(std::chrono::seconds timeout = std::chrono::seconds(120)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::string line;
    while (std::chrono::steady_clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::seconds>(
          deadline - std::chrono::steady_clock::now());
      if (!read_line(line, std::max(left, std::chrono::seconds(1)), 4096) && eof_) break;
    }
    Outcome o;
    if (!eof_) {
      ADD_FAILURE() << "nfield did not finish within " << timeout.count() << " s; killed";
      kill(pid_, SIGKILL);
    }
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    if (WIFEXITED(status)) {
      o.code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
      o.signaled = true;
      o.code = 128 + WTERMSIG(status);
    }
    o.out = all_;
    o.err = read_text(stderr_file_);
    return o;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  bool eof_ = false;
  bool reaped_ = false;
  std::string buffer_, all_;
  std::filesystem::path stderr_file_;
};

// Runs `nfield ARGS...` in `cwd` to its end; stderr is kept in `capture_dir`/stderr.txt.
inline Outcome run_nfield(const std::vector<std::string>& args, const std::filesystem::path& cwd,
                          const std::filesystem::path& capture_dir) {
  std::filesystem::create_directories(capture_dir);
  Child child(args, cwd, capture_dir / "stderr.txt");
  return child.finish();
}

inline std::string describe(const Outcome& o) {
  return "exit " + std::to_string(o.code) + (o.signaled ? " (signal)" : "") + "\n--- stdout:\n" +
         o.out + "--- stderr:\n" + o.err;
}

// Runs `nfield ARGS...` with stdout through a 4 KiB pipe and sends SIGINT once a progress
// line "step N/…" with N ≥ step has been read. The child writes some 95 bytes a step into
// a pipe read no further than that line, so it cannot get more than some 45 steps ahead.
// stopped_after: the step of that line (0 when none came); signalled: kill() succeeded.
struct Interrupted {
  Outcome outcome;
  long stopped_after = 0;
  bool signalled = false;
};
inline Interrupted interrupt_after_step(const std::vector<std::string>& args, const std::filesystem::path& cwd,
                                        const std::filesystem::path& stderr_file, long step) {
  Interrupted result;
  Child child(args, cwd, stderr_file, 4096);
  std::string line;
  while (child.read_line(line)) {
    long at = 0, total = 0;
    if (std::sscanf(line.c_str(), "step %ld/%ld", &at, &total) == 2 && at >= step) {
      result.stopped_after = at;
      break;
    }
  }
  if (result.stopped_after == 0) return result;
  result.signalled = kill(child.pid(), SIGINT) == 0;
  result.outcome = child.finish();
  return result;
}

}  // namespace nfield::apps::testing
