// Uniform draws from the raw 64-bit output of std::mt19937_64, whose sequence
// the standard fixes, never std:: distributions, whose algorithms differ
// between standard libraries: a seed gives the same numbers everywhere.
#pragma once

#include <random>

namespace orchard {

// Uniform in [0, 1) with 53 random bits.
inline double Uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

// Uniform in [lo, hi).
inline double UniformIn(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * Uniform01(rng); }

}  // namespace orchard
