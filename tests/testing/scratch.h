// SPDX-License-Identifier: MIT
//
// Per-test scratch folders under the build tree, emptied at the start of each test, and
// configs written into them.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

namespace nfield::testutil {

// BINARY_DIR/test_scratch/GROUP/SUITE.TEST, created if missing and kept as it is: for helpers
// that a test calls several times. One folder per test, never a shared /tmp name, so that
// two test runs side by side (two build trees, ctest -j) cannot overwrite each other's files.
inline std::filesystem::path test_folder(const std::string& group) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  std::replace(name.begin(), name.end(), '/', '_');
  const auto dir = std::filesystem::path(NFIELD_BINARY_DIR) / "test_scratch" / group / name;
  std::filesystem::create_directories(dir);
  return dir;
}

// The same folder, emptied.
inline std::filesystem::path scratch_dir(const std::string& group) {
  const auto dir = test_folder(group);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// `text` as NAME.yaml in a fresh scratch folder of `group`.
inline std::filesystem::path write_config(const std::string& group, const std::string& text,
                                          const std::string& name = "config") {
  const auto path = scratch_dir(group) / (name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

}  // namespace nfield::testutil
