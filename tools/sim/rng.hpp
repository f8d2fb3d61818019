// Portable deterministic random numbers for the simulator: splitmix64 seeding,
// xoshiro256** generator, Box-Muller normals. Same seed -> same sequence on
// every platform with an IEEE-754 libm (no std::*_distribution, whose output is
// implementation-defined).
#pragma once

#include <cmath>
#include <cstdint>

namespace uwbnav::sim {

// splitmix64 step (Steele, Lea, Flood 2014); advances `state` and returns a mixed word.
inline uint64_t splitmix64(uint64_t& state) {
  state += 0x9E3779B97F4A7C15ULL;
  uint64_t z = state;
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

// Hashes up to three words into one seed (used to give every range slot its own stream).
inline uint64_t mix_seed(uint64_t a, uint64_t b, uint64_t c = 0) {
  uint64_t s = a;
  uint64_t h = splitmix64(s);
  s = h ^ b;
  h = splitmix64(s);
  s = h ^ c;
  return splitmix64(s);
}

// xoshiro256** (Blackman, Vigna 2018) with normal/exponential/log-normal helpers.
class Rng {
 public:
  explicit Rng(uint64_t seed) {
    uint64_t s = seed;
    for (uint64_t& w : s_) w = splitmix64(s);
  }

  uint64_t next_u64() {
    const uint64_t result = rotl(s_[1] * 5U, 7) * 9U;
    const uint64_t t = s_[1] << 17U;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11U) * 0x1.0p-53; }

  // Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  // Uniform integer in [0, n) for n > 0 (multiply-shift; bias < 2^-32 for our n).
  uint64_t below(uint64_t n) { return static_cast<uint64_t>(uniform() * static_cast<double>(n)); }

  // Standard normal by the Box-Muller transform; the second value is cached.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 2.0 * kPi * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

  // Exponential with the given mean.
  double exponential(double mean) {
    double u = uniform();
    while (u <= 0.0) u = uniform();
    return -mean * std::log(u);
  }

  // Log-normal with the given arithmetic mean and log-space standard deviation `shape`:
  // mu = ln(mean) - shape^2 / 2 so that E[x] = mean.
  double lognormal_mean(double mean, double shape) {
    if (mean <= 0.0) return 0.0;
    const double mu = std::log(mean) - 0.5 * shape * shape;
    return std::exp(mu + shape * normal());
  }

  static constexpr double kPi = 3.14159265358979323846;

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4] = {0, 0, 0, 0};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace uwbnav::sim
