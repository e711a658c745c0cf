// Helpers shared by the stage tests (header-only; included by *_test.cc only).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "orchard/core/error.h"

namespace orchard::test {

// The folders FreshTempDir made in this process, removed when it exits
// (every run of the suite used to leave them behind) unless
// ORCHARD_KEEP_TEST_DIRS is set, for looking at a failed test's files.
inline std::vector<std::filesystem::path>& TempDirsToRemoveAtExit() {
  struct Registry {
    std::vector<std::filesystem::path> dirs;
    ~Registry() {
      if (std::getenv("ORCHARD_KEEP_TEST_DIRS")) return;
      std::error_code ec;
      for (const std::filesystem::path& dir : dirs) std::filesystem::remove_all(dir, ec);
    }
  };
  static Registry registry;
  return registry.dirs;
}

// An empty folder for one test: <tmp>/orchard_<name>_<pid>. The pid keeps
// tests that ctest runs in parallel processes out of each other's way.
inline std::filesystem::path FreshTempDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("orchard_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  TempDirsToRemoveAtExit().push_back(dir);
  return dir;
}

// `f` throws an orchard::Error whose message contains `needle`.
inline void ExpectErrorContains(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one containing '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace orchard::test
