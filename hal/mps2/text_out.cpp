// Semihosting text output (see text_out.hpp).
#include "hal/mps2/text_out.hpp"

#include <cstring>

#include "hal/mps2/semihost.hpp"

namespace uwbnav::mps2 {

void TextOut::put(char c) {
  if (len_ == kCapacity) flush();
  buf_[len_++] = c;
}

void TextOut::flush() {
  if (len_ == 0) return;
  buf_[len_] = '\0';
  semihost_write0(buf_);
  len_ = 0;
}

TextOut& TextOut::str(const char* s) {
  while (*s != '\0') put(*s++);
  return *this;
}

TextOut& TextOut::u64(uint64_t v) {
  char digits[20];
  size_t n = 0;
  do {
    digits[n++] = static_cast<char>('0' + v % 10U);
    v /= 10U;
  } while (v != 0);
  while (n > 0) put(digits[--n]);
  return *this;
}

TextOut& TextOut::i64(int64_t v) {
  if (v < 0) {
    put('-');
    return u64(0U - static_cast<uint64_t>(v));
  }
  return u64(static_cast<uint64_t>(v));
}

// v = m * 2^e exactly (m: 24-bit significand with the hidden bit); the scaled
// value m * 2^e * 10^decimals is formed in 64-bit integers and rounded half up.
TextOut& TextOut::fixed(float v, int decimals) {
  uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  const bool negative = (u >> 31) != 0;
  const uint32_t biased_exp = (u >> 23) & 0xFFU;
  const uint32_t frac = u & 0x7FFFFFU;
  if (biased_exp == 0xFFU) return str(frac != 0 ? "nan" : (negative ? "-inf" : "inf"));
  if (decimals < 0) decimals = 0;
  if (decimals > 9) decimals = 9;
  uint64_t scale = 1;
  for (int i = 0; i < decimals; ++i) scale *= 10U;
  const uint64_t m = biased_exp == 0 ? frac : (frac | 0x800000U);
  const int e = (biased_exp == 0 ? 1 : static_cast<int>(biased_exp)) - 127 - 23;
  uint64_t scaled = 0;  // |v| * 10^decimals, rounded
  bool overflow = false;
  if (e >= 0) {
    // |v| >= 2^23 here; above 2^31 the scaled value could overflow 64 bits.
    if (e > 7) {
      overflow = true;
    } else {
      scaled = (m << e) * scale;
    }
  } else if (-e < 64) {
    const uint64_t num = m * scale;  // < 2^24 * 10^9 < 2^54
    const unsigned shift = static_cast<unsigned>(-e);
    scaled = (num >> shift) + ((num >> (shift - 1)) & 1U);
  }
  if (overflow) return str(negative ? "-big" : "big");
  if (negative && scaled != 0) put('-');
  u64(scaled / scale);
  if (decimals > 0) {
    put('.');
    uint64_t rest = scaled % scale;
    char digits[9];
    for (int i = decimals - 1; i >= 0; --i) {
      digits[i] = static_cast<char>('0' + rest % 10U);
      rest /= 10U;
    }
    for (int i = 0; i < decimals; ++i) put(digits[i]);
  }
  return *this;
}

TextOut& TextOut::bits(float v) {
  uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  static constexpr char kHex[] = "0123456789abcdef";
  put('0');
  put('x');
  for (int shift = 28; shift >= 0; shift -= 4) put(kHex[(u >> shift) & 0xFU]);
  return *this;
}

void TextOut::endl() {
  put('\n');
  flush();
}

}  // namespace uwbnav::mps2
