// Test helpers for the data tests: a fresh temporary folder per test, small
// file writers, and a matcher for error messages.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace testing_data {

namespace fs = std::filesystem;

// A folder removed when the test ends.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            (std::string("orchard_data_") + info->test_suite_name() + "_" + info->name() + "_" +
             std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

inline void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline void WriteBlankImage(const fs::path& path, int width, int height) {
  fs::create_directories(path.parent_path());
  cv::imwrite(path.string(), cv::Mat(height, width, CV_8UC3, cv::Scalar(40, 90, 30)));
}

// The orchard::Error message `f` throws, or "" when it throws nothing.
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const orchard::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace testing_data
}  // namespace orchard
