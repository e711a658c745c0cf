// Deterministic random numbers and procedural noise for the synthetic orchard.
// Draws use only the raw 64-bit output of std::mt19937_64 (whose sequence the
// standard fixes), never std:: distributions (whose algorithms differ between
// standard libraries), so a seed gives the same scene everywhere.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "orchard/core/random.h"

namespace orchard::synth {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1) with 53 random bits.
  double Uniform() { return Uniform01(engine_); }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Integer in [lo, hi].
  int UniformInt(int lo, int hi) {
    return lo + static_cast<int>(std::floor(Uniform() * (hi - lo + 1)));
  }
  // Standard normal by Box-Muller (one value per call, the pair's cosine half).
  double Normal() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  double Normal(double mean, double sd) { return mean + sd * Normal(); }
  bool Bernoulli(double p) { return Uniform() < p; }
  std::uint64_t Bits() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

// A 64-bit mix (splitmix64 finaliser): seeds for sub-streams (side, frame).
inline std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
inline std::uint64_t SubSeed(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0) {
  return Mix64(Mix64(seed ^ Mix64(a + 1)) ^ Mix64(b + 0x51ed27ull));
}

// Hash of an integer lattice point to [0, 1).
inline float LatticeValue(int x, int y, int z, std::uint32_t seed) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 0x8da6b343u ^ static_cast<std::uint32_t>(y) * 0xd8163841u ^
                    static_cast<std::uint32_t>(z) * 0xcb1ab31fu ^ seed * 0x165667b1u;
  h ^= h >> 15;
  h *= 0x2c1b3c6du;
  h ^= h >> 12;
  h *= 0x297a2d39u;
  h ^= h >> 15;
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

inline float Smooth(float t) { return t * t * (3.0f - 2.0f * t); }

// Smooth value noise in [0, 1) on the unit lattice, 2D and 3D.
inline float ValueNoise2(float x, float y, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const float tx = Smooth(x - fx), ty = Smooth(y - fy);
  const float a = LatticeValue(ix, iy, 0, seed), b = LatticeValue(ix + 1, iy, 0, seed);
  const float c = LatticeValue(ix, iy + 1, 0, seed), d = LatticeValue(ix + 1, iy + 1, 0, seed);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

inline float ValueNoise3(float x, float y, float z, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy), iz = static_cast<int>(fz);
  const float tx = Smooth(x - fx), ty = Smooth(y - fy), tz = Smooth(z - fz);
  float v[2];
  for (int k = 0; k < 2; ++k) {
    const float a = LatticeValue(ix, iy, iz + k, seed), b = LatticeValue(ix + 1, iy, iz + k, seed);
    const float c = LatticeValue(ix, iy + 1, iz + k, seed), d = LatticeValue(ix + 1, iy + 1, iz + k, seed);
    const float ab = a + (b - a) * tx, cd = c + (d - c) * tx;
    v[k] = ab + (cd - ab) * ty;
  }
  return v[0] + (v[1] - v[0]) * tz;
}

}  // namespace orchard::synth
