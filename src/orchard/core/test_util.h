// Helpers shared by the stage tests (header-only; included by *_test.cc only).
#pragma once

#include <filesystem>
#include <string>

#include <unistd.h>

namespace orchard::test {

// An empty folder for one test: <tmp>/orchard_<name>_<pid>. The pid keeps
// tests that ctest runs in parallel processes out of each other's way.
inline std::filesystem::path FreshTempDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("orchard_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace orchard::test
