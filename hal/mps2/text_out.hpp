// Line-buffered text output over semihosting without stdio: integers and
// floats as text of firmware/text_format.hpp (exact, no double, no printf).
#pragma once

#include <cstddef>
#include <cstdint>

namespace uwbnav::mps2 {

class TextOut {
 public:
  TextOut& str(const char* s);
  TextOut& u64(uint64_t v);
  TextOut& i64(int64_t v);
  // printf "%.<decimals>f" of v (decimals 0..9): exact value rounded to nearest,
  // ties to even; "nan"/"inf" (with a sign when negative) when not finite.
  TextOut& fixed(float v, int decimals);
  // IEEE-754 bit pattern of `v` as 0x%08x (exact value for machine comparison).
  TextOut& bits(float v);
  // Terminates the line and writes it to the host console.
  void endl();

 private:
  void put(char c);
  void flush();

  static constexpr size_t kCapacity = 160;  // longest digest line, with margin
  char buf_[kCapacity + 1] = {};
  size_t len_ = 0;
};

}  // namespace uwbnav::mps2
