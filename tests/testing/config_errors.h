// SPDX-License-Identifier: MIT
//
// Loading a bad config must fail with one io::ConfigError located at the offending key:
// file, line, column (1-based, as printed), key path and a part of the message.
#pragma once

#include <gtest/gtest.h>

#include <exception>
#include <filesystem>
#include <string>

#include "io/config.h"
#include "solvers/run/run.h"

namespace nfield::testutil {

struct Located {
  int line, column;
  std::string key_path, part;
};

inline void expect_located_error(const std::filesystem::path& config, const Located& want) {
  try {
    solvers::load_run(config, {});
    ADD_FAILURE() << "no error for " << config;
  } catch (const io::ConfigError& e) {
    EXPECT_EQ(e.file(), config.string());
    EXPECT_EQ(e.line(), want.line) << e.what();
    EXPECT_EQ(e.column(), want.column) << e.what();
    EXPECT_EQ(e.key_path(), want.key_path) << e.what();
    EXPECT_NE(std::string(e.what()).find(want.part), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ConfigError: " << e.what();
  }
}

}  // namespace nfield::testutil
