// Bit patterns of IEEE single-precision floats for tests that compare results
// bit for bit (memcpy: no aliasing UB; C++17 has no std::bit_cast).
#pragma once

#include <cstdint>
#include <cstring>

namespace uwbnav::test {

inline uint32_t float_bits(float v) {
  uint32_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

inline float float_from_bits(uint32_t b) {
  float v = 0.0F;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

}  // namespace uwbnav::test
