// Float and 64-bit integer text, strict decimal parsing (see text_format.hpp).
//
// Formatting expands the float exactly: |v| = m * 2^e (m < 2^24) is the
// integer m * 2^e when e >= 0, and m * 5^-e * 10^e when e < 0, so its decimal
// digits are those of an integer, computed in limbs of 10^8 (at most 112
// digits, for the smallest subnormal). Rounding to the requested digits then
// works on exact decimal digits, ties to even.
#include "firmware/text_format.hpp"

#include <cstring>

namespace uwbnav {
namespace {

constexpr uint32_t kLimbBase = 100000000U;  // one limb holds 8 decimal digits
constexpr size_t kLimbDigits = 8;
constexpr size_t kMaxLimbs = 14;            // 2^24 * 5^149 < 10^112
constexpr size_t kMaxDigits = kMaxLimbs * kLimbDigits;

// snprintf-style bounded output: counts every character, stores what fits.
class Writer {
 public:
  Writer(char* out, size_t cap) : out_(out), cap_(cap) {}
  void put(char c) {
    if (len_ + 1 < cap_) out_[len_] = c;
    ++len_;
  }
  void put(const char* s) {
    while (*s != '\0') put(*s++);
  }
  void digit(int d) { put(static_cast<char>('0' + d)); }
  size_t finish() {
    if (cap_ > 0) out_[len_ < cap_ ? len_ : cap_ - 1] = '\0';
    return len_;
  }

 private:
  char* out_;
  size_t cap_;
  size_t len_ = 0;
};

// IEEE-754 binary32 fields of v: |v| = m * 2^e when finite.
struct FloatBits {
  bool negative = false;
  bool nan = false;
  bool inf = false;
  uint32_t m = 0;  // significand with the hidden bit (< 2^24)
  int e = 0;       // binary exponent of the significand's last bit
};

FloatBits split(float v) {
  uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  FloatBits b;
  b.negative = (u >> 31) != 0;
  const uint32_t biased = (u >> 23) & 0xFFU;
  const uint32_t frac = u & 0x7FFFFFU;
  if (biased == 0xFFU) {
    b.nan = frac != 0;
    b.inf = frac == 0;
    return b;
  }
  b.m = biased == 0 ? frac : (frac | 0x800000U);
  b.e = (biased == 0 ? 1 : static_cast<int>(biased)) - 127 - 23;
  return b;
}

// Exact decimal digits: value = 0.d[0] d[1] ... d[n-1] * 10^point, d[0] != 0
// and d[n-1] != 0 (n == 0 for zero).
struct Digits {
  uint8_t d[kMaxDigits];
  int n = 0;
  int point = 0;
};

// limbs (little-endian, base 10^8) *= factor; factor * (10^8 - 1) + factor < 2^32.
void mul_limbs(uint32_t* limb, size_t* used, uint32_t factor) {
  uint32_t carry = 0;
  for (size_t i = 0; i < *used; ++i) {
    const uint32_t t = limb[i] * factor + carry;
    limb[i] = t % kLimbBase;
    carry = t / kLimbBase;
  }
  if (carry != 0) limb[(*used)++] = carry;
}

void expand(uint32_t m, int e, Digits* x) {
  x->n = 0;
  x->point = 0;
  if (m == 0) return;
  uint32_t limb[kMaxLimbs] = {m};  // m < 2^24 < 10^8: one limb
  size_t used = 1;
  int exp10 = 0;  // value = limbs * 10^exp10
  if (e >= 0) {
    for (int left = e; left > 0; left -= 5) mul_limbs(limb, &used, left >= 5 ? 32U : 1U << left);
  } else {
    for (int left = -e; left > 0; left -= 2) mul_limbs(limb, &used, left >= 2 ? 25U : 5U);
    exp10 = e;
  }
  // Most significant limb without leading zeros, then 8 digits per limb.
  uint8_t top[kLimbDigits];
  size_t top_n = 0;
  for (uint32_t t = limb[used - 1]; t != 0; t /= 10U) top[top_n++] = static_cast<uint8_t>(t % 10U);
  int n = 0;
  while (top_n > 0) x->d[n++] = top[--top_n];
  for (size_t i = used - 1; i-- > 0;) {
    uint32_t t = limb[i];
    for (int k = static_cast<int>(kLimbDigits) - 1; k >= 0; --k) {
      x->d[n + k] = static_cast<uint8_t>(t % 10U);
      t /= 10U;
    }
    n += static_cast<int>(kLimbDigits);
  }
  x->point = n + exp10;
  while (n > 0 && x->d[n - 1] == 0) --n;
  x->n = n;
}

// Keeps the first `keep` digits (any int), rounding the exact value to
// nearest, ties to even.
void round_digits(Digits* x, int keep) {
  if (keep >= x->n) return;
  if (keep < 0) {  // value < 10^point <= a tenth of the last kept place
    x->n = 0;
    return;
  }
  const int r = x->d[keep];
  const bool rest = keep + 1 < x->n;  // d[n-1] != 0
  const bool odd = keep > 0 && (x->d[keep - 1] & 1U) != 0;
  x->n = keep;
  if (r > 5 || (r == 5 && (rest || odd))) {
    int i = keep - 1;
    while (i >= 0 && x->d[i] == 9) --i;
    if (i < 0) {  // 9...9 (or nothing kept) rounds up to the next power of ten
      x->d[0] = 1;
      x->n = 1;
      ++x->point;
      return;
    }
    ++x->d[i];
    x->n = i + 1;
  }
  while (x->n > 0 && x->d[x->n - 1] == 0) --x->n;
}

int digit_at(const Digits& x, int i) { return i >= 0 && i < x.n ? x.d[i] : 0; }

// "nan"/"inf" with the sign; false for finite values.
bool put_special(Writer* w, const FloatBits& b) {
  if (!b.nan && !b.inf) return false;
  if (b.negative) w->put('-');
  w->put(b.nan ? "nan" : "inf");
  return true;
}

int clamp(int v, int lo, int hi) { return v < lo ? lo : (v > hi ? hi : v); }

// --- parsing ---------------------------------------------------------------

constexpr int kMaxParseDigits = 19;  // significant digits held exactly (< 2^64)
constexpr int kPow10Chunk = 18;      // 10^18 < 2^60: the bit-serial division stays in 64 bits
constexpr int kExpSaturation = 100000;

// Leading zero bits of v != 0.
int clz64(uint64_t v) { return __builtin_clzll(v); }

uint64_t pow10_u64(int k) {
  uint64_t p = 1;
  for (int i = 0; i < k; ++i) p *= 10U;
  return p;
}

// 128-bit product of two 64-bit numbers from 32x32->64 multiplies.
void mul_64x64(uint64_t a, uint64_t b, uint64_t* hi, uint64_t* lo) {
  const uint64_t a0 = a & 0xFFFFFFFFU;
  const uint64_t a1 = a >> 32;
  const uint64_t b0 = b & 0xFFFFFFFFU;
  const uint64_t b1 = b >> 32;
  const uint64_t p00 = a0 * b0;
  const uint64_t p01 = a0 * b1;
  const uint64_t p10 = a1 * b0;
  const uint64_t p11 = a1 * b1;
  const uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFU) + (p10 & 0xFFFFFFFFU);
  *lo = (mid << 32) | (p00 & 0xFFFFFFFFU);
  *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

// Working value mant * 2^bexp with mant normalised (bit 63 set); `inexact`:
// the true value is above it (bits dropped or a factor truncated).
struct Wide {
  uint64_t mant = 0;
  int bexp = 0;
  bool inexact = false;
};

// w *= f * 2^f_exp, truncated to 64 bits.
void mul_wide(Wide* w, uint64_t f, int f_exp) {
  uint64_t hi = 0;
  uint64_t lo = 0;
  mul_64x64(w->mant, f, &hi, &lo);
  const int s = clz64(hi);  // hi != 0: mant >= 2^63 and f >= 2
  w->mant = s == 0 ? hi : ((hi << s) | (lo >> (64 - s)));
  if ((lo << s) != 0) w->inexact = true;
  w->bexp += f_exp + 64 - s;
}

// num / d (num != 0, d < 2^60) truncated to 64 significant bits by long
// division; inexact when a remainder is left.
Wide divide(uint64_t num, uint64_t d) {
  uint64_t q = num / d;
  uint64_t r = num % d;
  int bexp = 0;
  while (q == 0) {  // num < d: skip the leading zero bits of the fraction
    r <<= 1;
    --bexp;
    if (r >= d) {
      r -= d;
      q = 1;
    }
  }
  while ((q >> 63) == 0) {
    r <<= 1;
    --bexp;
    q <<= 1;
    if (r >= d) {
      r -= d;
      q |= 1U;
    }
  }
  Wide w;
  w.mant = q;
  w.bexp = bexp;
  w.inexact = r != 0;
  return w;
}

float float_from_bits(uint32_t u) {
  float f = 0.0F;
  std::memcpy(&f, &u, sizeof f);
  return f;
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

size_t format_fixed(char* out, size_t cap, float v, int decimals) {
  Writer w(out, cap);
  const FloatBits b = split(v);
  if (put_special(&w, b)) return w.finish();
  decimals = clamp(decimals, 0, kMaxFormatDecimals);
  if (b.negative) w.put('-');
  Digits x;
  expand(b.m, b.e, &x);
  round_digits(&x, x.point + decimals);
  if (x.point <= 0) {
    w.put('0');
  } else {
    for (int i = 0; i < x.point; ++i) w.digit(digit_at(x, i));
  }
  if (decimals > 0) w.put('.');
  for (int j = 0; j < decimals; ++j) w.digit(digit_at(x, x.point + j));
  return w.finish();
}

size_t format_general(char* out, size_t cap, float v, int precision) {
  Writer w(out, cap);
  const FloatBits b = split(v);
  if (put_special(&w, b)) return w.finish();
  precision = clamp(precision, 1, kMaxFormatPrecision);
  if (b.negative) w.put('-');
  Digits x;
  expand(b.m, b.e, &x);
  if (x.n == 0) {
    w.put('0');
    return w.finish();
  }
  round_digits(&x, precision);
  const int exp10 = x.point - 1;  // of the rounded value
  if (exp10 < -4 || exp10 >= precision) {
    w.digit(x.d[0]);
    if (x.n > 1) w.put('.');
    for (int i = 1; i < x.n; ++i) w.digit(x.d[i]);
    w.put(exp10 < 0 ? "e-" : "e+");
    const int a = exp10 < 0 ? -exp10 : exp10;  // <= 45
    w.digit(a / 10);
    w.digit(a % 10);
  } else if (x.point <= 0) {
    w.put("0.");
    for (int i = x.point; i < 0; ++i) w.put('0');
    for (int i = 0; i < x.n; ++i) w.digit(x.d[i]);
  } else {
    for (int i = 0; i < x.point; ++i) w.digit(digit_at(x, i));
    if (x.n > x.point) w.put('.');
    for (int i = x.point; i < x.n; ++i) w.digit(x.d[i]);
  }
  return w.finish();
}

size_t format_u64(char* out, size_t cap, uint64_t v) {
  char rev[kU64TextMax];
  size_t n = 0;
  // 32-bit divisions while the value fits (no 64-bit division helper).
  while (v > 0xFFFFFFFFU) {
    rev[n++] = static_cast<char>('0' + v % 10U);
    v /= 10U;
  }
  auto v32 = static_cast<uint32_t>(v);
  do {
    rev[n++] = static_cast<char>('0' + v32 % 10U);
    v32 /= 10U;
  } while (v32 != 0);
  Writer w(out, cap);
  while (n > 0) w.put(rev[--n]);
  return w.finish();
}

Result<float> parse_decimal_float(const char* text) {
  const char* p = text;
  const bool negative = *p == '-';
  if (*p == '+' || *p == '-') ++p;
  uint64_t sig = 0;        // first kMaxParseDigits significant digits
  int sig_digits = 0;
  int exp10 = 0;           // value = sig * 10^exp10 (before the exponent part)
  bool dropped = false;    // a non-zero digit beyond the held ones
  bool any_digit = false;
  bool fraction = false;
  for (;; ++p) {
    if (*p == '.' && !fraction) {
      fraction = true;
      continue;
    }
    if (!is_digit(*p)) break;
    any_digit = true;
    const auto d = static_cast<uint32_t>(*p - '0');
    if (sig_digits < kMaxParseDigits) {
      if (sig != 0 || d != 0) {
        sig = sig * 10U + d;
        ++sig_digits;
      }
      if (fraction) --exp10;
    } else {
      if (!fraction) ++exp10;
      if (d != 0) dropped = true;
    }
  }
  if (!any_digit) return Status::kInvalidArgument;
  if (*p == 'e' || *p == 'E') {
    ++p;
    const bool exp_negative = *p == '-';
    if (*p == '+' || *p == '-') ++p;
    if (!is_digit(*p)) return Status::kInvalidArgument;
    int e = 0;
    for (; is_digit(*p); ++p) {
      if (e < kExpSaturation) e = e * 10 + (*p - '0');
    }
    exp10 += exp_negative ? -e : e;
  }
  if (*p != '\0') return Status::kInvalidArgument;

  const uint32_t sign = negative ? 0x80000000U : 0U;
  // sig < 10^19: above 10^39 the value exceeds FLT_MAX, below 10^-47 it is
  // under half the smallest subnormal (2^-150 ~ 7e-46).
  if (sig == 0 || exp10 < -66) return float_from_bits(sign);
  if (exp10 > 39) return Status::kOutOfRange;

  // sig * 10^exp10: exact products and one exact quotient (with a sticky
  // remainder) for |exp10| <= 18; beyond, factors 10^-18 truncated to 64 bits.
  Wide w;
  if (exp10 < 0) {
    const int k = -exp10 < kPow10Chunk ? -exp10 : kPow10Chunk;
    w = divide(sig, pow10_u64(k));
    exp10 += k;
  } else {
    const int lz = clz64(sig);
    w.mant = sig << lz;
    w.bexp = -lz;
  }
  if (dropped) w.inexact = true;
  while (exp10 > 0) {
    const int k = exp10 < kPow10Chunk ? exp10 : kPow10Chunk;
    mul_wide(&w, pow10_u64(k), 0);
    exp10 -= k;
  }
  while (exp10 < 0) {
    const int k = -exp10 < kPow10Chunk ? -exp10 : kPow10Chunk;
    const Wide inv = divide(1U, pow10_u64(k));
    mul_wide(&w, inv.mant, inv.bexp);
    w.inexact = true;  // the truncated factor is below 10^-k
    exp10 += k;
  }

  // value in [2^ex, 2^(ex+1)); keep 24 bits (fewer for subnormals).
  int ex = w.bexp + 63;
  if (ex > 127) return Status::kOutOfRange;
  const int drop = ex >= -126 ? 40 : 40 + (-126 - ex);
  if (drop > 64) return float_from_bits(sign);  // below 2^-150: rounds to zero
  uint64_t kept = drop == 64 ? 0 : w.mant >> drop;
  const bool half = ((w.mant >> (drop - 1)) & 1U) != 0;
  const bool rest = w.inexact || (w.mant << (65 - drop)) != 0;
  if (half && (rest || (kept & 1U) != 0)) ++kept;
  if (ex < -126) return float_from_bits(sign | static_cast<uint32_t>(kept));  // subnormal, or 2^-126 after rounding
  if (kept == (1ULL << 24)) {
    kept >>= 1;
    ++ex;
    if (ex > 127) return Status::kOutOfRange;
  }
  return float_from_bits(sign | (static_cast<uint32_t>(ex + 127) << 23) | (static_cast<uint32_t>(kept) & 0x7FFFFFU));
}

}  // namespace uwbnav
