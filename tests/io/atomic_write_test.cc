// SPDX-License-Identifier: MIT
#include "io/atomic_write.h"

#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/io/io_test_paths.h"

namespace nfield::io {
namespace {
using testing::expect_error;
using testing::file_names;
using testing::read_text;
using testing::scratch_dir;
using testing::write_text;

TEST(AtomicWrite, WritesThroughATemporaryInTheSameFolder) {
  const auto dir = scratch_dir();
  std::filesystem::path used;
  write_atomically(dir / "a.txt", [&](const std::filesystem::path& tmp) {
    used = tmp;
    write_text(tmp, "new");
  });
  EXPECT_EQ(used.parent_path(), dir);
  EXPECT_EQ(used.extension(), ".txt");
  EXPECT_EQ(read_text(dir / "a.txt"), "new");
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"a.txt"});
}

TEST(AtomicWrite, FailureKeepsTheOldFileAndLeavesNoTemporary) {
  const auto dir = scratch_dir();
  write_text(dir / "a.txt", "old");
  expect_error<std::runtime_error>(
      [&] {
        write_atomically(dir / "a.txt", [](const std::filesystem::path& tmp) {
          write_text(tmp, "half");
          throw std::runtime_error("disk on fire");
        });
      },
      {"a.txt", "disk on fire"});
  EXPECT_EQ(read_text(dir / "a.txt"), "old");
  EXPECT_EQ(file_names(dir), std::vector<std::string>{"a.txt"});
}

TEST(AtomicWrite, MissingFolderOrNothingWrittenIsAnError) {
  const auto dir = scratch_dir();
  expect_error<std::runtime_error>(
      [&] { write_atomically(dir / "no" / "a.txt", [](const std::filesystem::path&) {}); },
      {"a.txt", "does not exist"});
  expect_error<std::runtime_error>(
      [&] { write_atomically(dir / "b.txt", [](const std::filesystem::path&) {}); },
      {"b.txt", "no file was written"});
}

}  // namespace
}  // namespace nfield::io
