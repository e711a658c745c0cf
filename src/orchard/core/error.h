// Errors: every failure a user can cause (bad input, bad options) is an
// orchard::Error with a one-line message; the `orchard` program prints it and
// exits non-zero. Programming errors may still assert.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace orchard {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

namespace internal {
template <typename... Args>
std::string Concat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}
}  // namespace internal

// Throws orchard::Error with the arguments streamed into one message.
template <typename... Args>
[[noreturn]] void Fail(const Args&... args) {
  throw Error(internal::Concat(args...));
}

}  // namespace orchard

// For Options::Check(): ORCHARD_CHECK_OPTION(radius > 0, "radius must be positive, got ", radius);
#define ORCHARD_CHECK_OPTION(cond, ...)                                     \
  do {                                                                      \
    if (!(cond)) ::orchard::Fail("invalid option: ", __VA_ARGS__);          \
  } while (0)
