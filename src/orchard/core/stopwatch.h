// Wall-clock seconds per stage of a pipeline (reported in its json outputs).
#pragma once

#include <chrono>

namespace orchard {

class Stopwatch {
 public:
  // Seconds since construction or the previous Lap().
  double Lap() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return seconds;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace orchard
