// Number text of the firmware without printf floats or long long: a float as
// "%.Nf" or "%.Ng" text, a uint64_t as decimal text, and a strict decimal
// parser for console input. Integer arithmetic on the float's bits only (no
// double, no libc float conversion), so the MPS2 image links picolibc's
// integer-only printf (hal/mps2/CMakeLists.txt); the console, the logger and
// the MPS2 digest print every float and 64-bit count through these.
//
// Output is the same text glibc's printf gives for static_cast<double>(v):
// the float's exact binary value rounded to the requested digits, ties to even
// ("%.2f" of 0.125 is "0.12", of 0.375 is "0.38"); "nan", "-nan", "inf",
// "-inf"; negative zero and negative values that round to zero keep the sign
// ("-0.000"). tests/console/test_text_format.cpp compares with the host's
// snprintf over random floats.
//
// Buffers work like snprintf: at most cap - 1 characters and a NUL are
// written, the return value is the length of the whole text, and the text was
// truncated if and only if that length is >= cap.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"

namespace uwbnav {

constexpr int kMaxFormatDecimals = 9;   // format_fixed: decimals are clamped to 0..9
constexpr int kMaxFormatPrecision = 9;  // format_general: significant digits are clamped to 1..9
// Buffer sizes (with the NUL) that always hold the whole text:
constexpr size_t kFixedTextMax = 1 + 39 + 1 + kMaxFormatDecimals + 1;  // "-" 39 digits of FLT_MAX "." 9 decimals
constexpr size_t kGeneralTextMax = 16;                                 // "-1.23456789e-45", "-0.000123456789"
constexpr size_t kU64TextMax = 21;                                     // 18446744073709551615

// printf "%.<decimals>f" of v.
size_t format_fixed(char* out, size_t cap, float v, int decimals);

// printf "%.<precision>g" of v (precision 0 means 1, as in printf): `precision`
// significant digits, exponent form (e+NN / e-NN) when the decimal exponent is
// < -4 or >= precision, trailing zeros and a trailing point removed.
size_t format_general(char* out, size_t cap, float v, int precision);

// printf "%llu" of v.
size_t format_u64(char* out, size_t cap, uint64_t v);

// Strict decimal number: [+|-] (digits [. [digits]] | . digits) [(e|E) [+|-] digits],
// i.e. at least one mantissa digit, nothing before or after (no spaces, hex, inf or nan).
// kInvalidArgument when malformed, kOutOfRange when the magnitude rounds above
// FLT_MAX; values at or below half the smallest subnormal become +-0 (as strtof).
// Rounding is to nearest, ties to even. A value d * 10^k with d of at most 19
// digits and -18 <= k <= 18 (every plain console number) is converted exactly,
// identical to glibc's strtof. Longer inputs or larger exponents go through a
// 64-bit intermediate with a relative error below 2^-58: the result then
// equals strtof's unless the decimal value lies that close to the midpoint
// between two floats, and is always within 1 ulp of it.
Result<float> parse_decimal_float(const char* text);

}  // namespace uwbnav
