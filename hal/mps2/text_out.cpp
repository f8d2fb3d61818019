// Semihosting text output (see text_out.hpp).
#include "hal/mps2/text_out.hpp"

#include <cstring>

#include "firmware/text_format.hpp"
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
  char text[kU64TextMax];
  (void)format_u64(text, sizeof text, v);
  return str(text);
}

TextOut& TextOut::i64(int64_t v) {
  if (v < 0) {
    put('-');
    return u64(0U - static_cast<uint64_t>(v));
  }
  return u64(static_cast<uint64_t>(v));
}

TextOut& TextOut::fixed(float v, int decimals) {
  char text[kFixedTextMax];
  (void)format_fixed(text, sizeof text, v, decimals);
  return str(text);
}

TextOut& TextOut::bits(float v) {
  uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  static constexpr char kHex[] = "0123456789abcdef";
  char text[11] = "0x";
  for (int i = 0; i < 8; ++i) text[2 + i] = kHex[(u >> (28 - 4 * i)) & 0xFU];
  return str(text);
}

void TextOut::endl() {
  put('\n');
  flush();
}

}  // namespace uwbnav::mps2
