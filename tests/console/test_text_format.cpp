// firmware/text_format: float text identical to the host's printf of the
// float's double value ("%.*f", "%.*g") over random and boundary floats,
// uint64 text, bounded buffers, the strict decimal parser against glibc's
// strtof, and a scan keeping float and long long conversions out of the
// firmware's printf formats (the board links an integer-only printf).
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/console/log.hpp"
#include "firmware/text_format.hpp"
#include "tests/float_bits.hpp"

namespace uwbnav {
namespace {

std::string fixed(float v, int decimals) {
  char buf[kFixedTextMax];
  const size_t n = format_fixed(buf, sizeof buf, v, decimals);
  EXPECT_LT(n, sizeof buf) << "kFixedTextMax too small";
  return buf;
}

std::string general(float v, int precision) {
  char buf[kGeneralTextMax];
  const size_t n = format_general(buf, sizeof buf, v, precision);
  EXPECT_LT(n, sizeof buf) << "kGeneralTextMax too small";
  return buf;
}

std::string host_fixed(float v, int decimals) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, static_cast<double>(v));
  return buf;
}

std::string host_general(float v, int precision) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.*g", precision, static_cast<double>(v));
  return buf;
}

// Random floats of three kinds: any bit pattern (all exponents, subnormals,
// nan, inf), console-sized values (uniform in +-1e4) and small positive values
// (log-uniform 1e-12..1e3, covariances).
std::vector<float> random_floats(size_t per_kind, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1e4F, 1e4F);
  std::uniform_real_distribution<float> log10_mag(-12.0F, 3.0F);
  std::vector<float> v;
  for (size_t i = 0; i < per_kind; ++i) {
    v.push_back(test::float_from_bits(static_cast<uint32_t>(rng())));
    v.push_back(uniform(rng));
    v.push_back(std::pow(10.0F, log10_mag(rng)));
  }
  return v;
}

// Floats where rounding decides: exact ties at 0..6 decimals (k/2 * 10^-d
// representable in binary), their neighbours one ulp either side, carries
// through nines, powers of two and of ten, integers around 2^24, 2^31, 2^32,
// 2^63, the extremes.
std::vector<float> boundary_floats() {
  std::vector<float> v = {0.0F, -0.0F, 0.5F, 1.5F, 2.5F, -2.5F, 0.125F, 0.375F, 0.0625F, 0.0005F, 9.9995F,
                          99.995F, 0.9995F, 999.9995F, 1e-5F, 9.5e-5F, 1e6F, 999999.5F, 123456.5F, 1e7F, 1e20F,
                          3.0e38F, FLT_MAX, -FLT_MAX, FLT_MIN, FLT_TRUE_MIN, -FLT_TRUE_MIN, FLT_EPSILON,
                          16777216.0F, 16777215.0F, 2147483648.0F, 2147483520.0F, 4294967296.0F, 4294967040.0F,
                          9223372036854775808.0F, 18446744073709551616.0F};
  for (int e = -149; e <= 127; ++e) v.push_back(std::ldexp(1.0F, e));
  for (int e = -45; e <= 38; ++e) v.push_back(std::pow(10.0F, static_cast<float>(e)));
  for (int n = 0; n < 2000; ++n) v.push_back(static_cast<float>(n) / 16.0F);  // ties at 1..4 decimals
  const size_t base = v.size();
  for (size_t i = 0; i < base; ++i) {
    v.push_back(std::nextafter(v[i], std::numeric_limits<float>::infinity()));
    v.push_back(std::nextafter(v[i], -std::numeric_limits<float>::infinity()));
  }
  return v;
}

TEST(TextFormat, FixedRoundsToNearestWithTiesToEvenOnTheExactBinaryValue) {
  EXPECT_EQ(fixed(0.0005F, 3), "0.001");  // 0.0005F is 0.000500000024...
  EXPECT_EQ(fixed(9.9995F, 3), "10.000");  // 9.99950027...: carry through the nines
  EXPECT_EQ(fixed(9.9994F, 3), "9.999");
  EXPECT_EQ(fixed(99.9999F, 2), "100.00");
  EXPECT_EQ(fixed(0.125F, 2), "0.12");  // exact tie: even
  EXPECT_EQ(fixed(0.375F, 2), "0.38");
  EXPECT_EQ(fixed(0.5F, 0), "0");
  EXPECT_EQ(fixed(1.5F, 0), "2");
  EXPECT_EQ(fixed(2.5F, 0), "2");
  EXPECT_EQ(fixed(-2.5F, 0), "-2");
  EXPECT_EQ(fixed(0.0004F, 3), "0.000");
  EXPECT_EQ(fixed(48.292F, 3), "48.292");
  EXPECT_EQ(fixed(-0.137F, 3), "-0.137");
  EXPECT_EQ(fixed(1000.0F, 3), "1000.000");
  EXPECT_EQ(fixed(3.0F, 2), "3.00");
}

TEST(TextFormat, FixedKeepsTheSignOfNegativeZeroAndOfNegativesRoundingToZero) {
  EXPECT_EQ(fixed(-0.0F, 3), "-0.000");
  EXPECT_EQ(fixed(-0.0001F, 3), "-0.000");
  EXPECT_EQ(fixed(-0.0001F, 0), "-0");
  EXPECT_EQ(fixed(0.0F, 0), "0");
}

TEST(TextFormat, FixedPrintsAllDigitsOfLargeValues) {
  EXPECT_EQ(fixed(2147483648.0F, 3), "2147483648.000");  // 2^31
  EXPECT_EQ(fixed(2147483520.0F, 1), "2147483520.0");    // largest float below 2^31
  EXPECT_EQ(fixed(-4294967296.0F, 0), "-4294967296");
  EXPECT_EQ(fixed(1e20F, 3), "100000002004087734272.000");
  EXPECT_EQ(fixed(FLT_MAX, 9), "340282346638528859811704183484516925440.000000000");
  EXPECT_EQ(fixed(-FLT_MAX, 0), "-340282346638528859811704183484516925440");
  EXPECT_EQ(fixed(FLT_TRUE_MIN, 9), "0.000000000");
}

TEST(TextFormat, NanAndInfinityAreSpelledAsPrintfDoes) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(fixed(inf, 3), "inf");
  EXPECT_EQ(fixed(-inf, 3), "-inf");
  EXPECT_EQ(fixed(nan, 3), "nan");
  EXPECT_EQ(fixed(-nan, 3), "-nan");
  EXPECT_EQ(general(inf, 6), "inf");
  EXPECT_EQ(general(-nan, 3), "-nan");
  EXPECT_EQ(fixed(test::float_from_bits(0x7F800001U), 1), "nan");  // signalling pattern
}

TEST(TextFormat, GeneralPicksFixedOrExponentFormAndDropsTrailingZeros) {
  EXPECT_EQ(general(5.0F, 6), "5");
  EXPECT_EQ(general(7.5F, 6), "7.5");
  EXPECT_EQ(general(0.0F, 6), "0");
  EXPECT_EQ(general(-0.0F, 6), "-0");
  EXPECT_EQ(general(2000.0F, 6), "2000");
  EXPECT_EQ(general(1e6F, 6), "1e+06");
  EXPECT_EQ(general(999999.5F, 6), "1e+06");  // rounding carries into the exponent form
  EXPECT_EQ(general(123456.5F, 6), "123456");  // tie: even
  EXPECT_EQ(general(0.0001F, 6), "0.0001");
  EXPECT_EQ(general(0.00009F, 6), "9e-05");
  EXPECT_EQ(general(0.000413F, 3), "0.000413");
  EXPECT_EQ(general(9.63e-05F, 3), "9.63e-05");
  EXPECT_EQ(general(1.1e-05F, 3), "1.1e-05");
  EXPECT_EQ(general(FLT_MAX, 9), "3.40282347e+38");
  EXPECT_EQ(general(FLT_TRUE_MIN, 5), "1.4013e-45");
  EXPECT_EQ(general(-1.0F / 3.0F, 9), "-0.333333343");
  EXPECT_EQ(general(0.2F, 0), "0.2");  // precision 0 means 1
}

TEST(TextFormat, FixedAgreesWithHostPrintfOnEveryBoundaryAndRandomFloat) {
  std::vector<float> values = boundary_floats();
  const std::vector<float> rnd = random_floats(40000, 20240601U);
  values.insert(values.end(), rnd.begin(), rnd.end());
  size_t compared = 0;
  for (const float v : values) {
    for (int d = 0; d <= kMaxFormatDecimals; ++d) {
      ASSERT_EQ(fixed(v, d), host_fixed(v, d)) << "bits 0x" << std::hex << test::float_bits(v) << std::dec << " decimals " << d;
      ++compared;
    }
  }
  std::printf("[ format   ] %%.Nf identical to glibc printf for %zu float/decimals pairs\n", compared);
}

TEST(TextFormat, GeneralAgreesWithHostPrintfOnEveryBoundaryAndRandomFloat) {
  std::vector<float> values = boundary_floats();
  const std::vector<float> rnd = random_floats(40000, 777U);
  values.insert(values.end(), rnd.begin(), rnd.end());
  size_t compared = 0;
  for (const float v : values) {
    for (int p = 1; p <= kMaxFormatPrecision; ++p) {
      ASSERT_EQ(general(v, p), host_general(v, p)) << "bits 0x" << std::hex << test::float_bits(v) << std::dec << " precision "
                                                   << p;
      ++compared;
    }
  }
  std::printf("[ format   ] %%.Ng identical to glibc printf for %zu float/precision pairs\n", compared);
}

TEST(TextFormat, DigitsOutsideTheSupportedRangeAreClamped) {
  EXPECT_EQ(fixed(1.25F, 12), fixed(1.25F, 9));
  EXPECT_EQ(fixed(1.75F, -3), "2");
  EXPECT_EQ(general(1.0F / 3.0F, 20), general(1.0F / 3.0F, 9));
}

TEST(TextFormat, TooSmallBufferKeepsAPrefixAndReportsTheFullLength) {
  char buf[8];
  std::memset(buf, 'x', sizeof buf);
  EXPECT_EQ(format_fixed(buf, 5, 123.456F, 3), 7U);  // "123.456" does not fit 4 characters + NUL
  EXPECT_STREQ(buf, "123.");
  EXPECT_EQ(format_fixed(buf, 8, 123.456F, 3), 7U);  // exactly fits
  EXPECT_STREQ(buf, "123.456");
  EXPECT_EQ(format_general(buf, 3, -1.5e-7F, 6), 8U);
  EXPECT_STREQ(buf, "-1");
  EXPECT_EQ(format_u64(buf, 1, 42U), 2U);
  EXPECT_STREQ(buf, "");
  buf[0] = 'x';
  EXPECT_EQ(format_fixed(buf, 0, 1.0F, 1), 3U);  // no room at all: nothing written
  EXPECT_EQ(buf[0], 'x');
}

TEST(TextFormat, U64MatchesToStringAcrossTheWholeRange) {
  std::mt19937_64 rng(99);
  std::vector<uint64_t> values = {0U, 9U, 10U, 4294967295ULL, 4294967296ULL, 10000000000000000000ULL,
                                  std::numeric_limits<uint64_t>::max()};
  for (int i = 0; i < 20000; ++i) values.push_back(rng() >> (rng() % 64));
  for (const uint64_t v : values) {
    char buf[kU64TextMax];
    const size_t n = format_u64(buf, sizeof buf, v);
    EXPECT_EQ(std::string(buf), std::to_string(v));
    EXPECT_EQ(n, std::to_string(v).size());
  }
}

TEST(TextFormat, LoggerStampsTimesBeyond32BitMicroseconds) {
  struct Capture final : LogSink {
    std::string line;
    void log_line(LogLevel, const char* text, size_t len) override { line.assign(text, len); }
  } sink;
  LogSink* saved_sink = logger().sink();
  const LogLevel saved_level = logger().level();
  const uint64_t saved_t_us = logger().time_us();
  logger().set_sink(&sink);
  logger().set_level(LogLevel::kInfo);
  logger().set_time_us(5000000000123ULL);  // 58 days
  UWBNAV_LOG_INFO("fmt", "x=%s", "1.5");
  logger().set_sink(saved_sink);
  logger().set_level(saved_level);
  logger().set_time_us(saved_t_us);
  EXPECT_EQ(sink.line, "log t_us=5000000000123 level=info mod=fmt msg=x=1.5");
}

// --- parser ------------------------------------------------------------------

float parsed(const char* text) {
  const Result<float> r = parse_decimal_float(text);
  EXPECT_TRUE(r.ok()) << text << ": " << status_name(r.status());
  return r.value();
}

// Distance in ulps between two finite floats of the same sign.
int64_t ulps(float a, float b) {
  return std::llabs(static_cast<int64_t>(test::float_bits(a) & 0x7FFFFFFFU) - static_cast<int64_t>(test::float_bits(b) & 0x7FFFFFFFU));
}

TEST(TextParse, AcceptsPlainDecimalForms) {
  EXPECT_EQ(parsed("7.5"), 7.5F);
  EXPECT_EQ(parsed("-7.5"), -7.5F);
  EXPECT_EQ(parsed("+3"), 3.0F);
  EXPECT_EQ(parsed("0.2"), 0.2F);
  EXPECT_EQ(parsed(".5"), 0.5F);
  EXPECT_EQ(parsed("5."), 5.0F);
  EXPECT_EQ(parsed("1e3"), 1000.0F);
  EXPECT_EQ(parsed("1E-3"), 0.001F);
  EXPECT_EQ(parsed("2.5e+2"), 250.0F);
  EXPECT_EQ(parsed("000123.4500"), 123.45F);
  EXPECT_EQ(parsed("16777217"), 16777216.0F);  // tie: even
  EXPECT_EQ(parsed("16777219"), 16777220.0F);  // tie: even (up)
  EXPECT_EQ(parsed("3.4028235e38"), FLT_MAX);
  EXPECT_EQ(parsed("1.17549435e-38"), FLT_MIN);
  EXPECT_EQ(parsed("1.4e-45"), FLT_TRUE_MIN);
  EXPECT_EQ(parsed("1e-46"), 0.0F);  // below half the smallest subnormal: zero, as strtof
  EXPECT_EQ(test::float_bits(parsed("-0")), 0x80000000U);
  EXPECT_EQ(parsed("0e999999"), 0.0F);
  EXPECT_EQ(parsed("0.000000000000000000000000000000000000000000000000000001e54"), 1.0F);
  EXPECT_EQ(parsed("123456789012345678901234567890"), std::strtof("123456789012345678901234567890", nullptr));
}

TEST(TextParse, RejectsGarbageAndOverflow) {
  for (const char* bad : {"", "-", "+", ".", "e5", "1e", "1e+", "1.2.3", "0x10", "1,5", " 1", "1 ", "inf", "nan",
                          "-inf", "1e5x", "5f", "--1", "+-1", "1..2", "1e2.5"}) {
    EXPECT_EQ(parse_decimal_float(bad).status(), Status::kInvalidArgument) << "'" << bad << "'";
  }
  for (const char* big : {"3.5e38", "1e39", "-1e39", "3.4028236e38", "1e999999", "99999999999999999999e30"}) {
    EXPECT_EQ(parse_decimal_float(big).status(), Status::kOutOfRange) << big;
  }
}

TEST(TextParse, ExactMidpointsBetweenFloatsRoundToEvenAsStrtof) {
  for (const char* tie : {"8388608.5", "8388609.5", "4194304.25", "4194304.75", "16777217", "16777219",
                          "167772190e-1", "33554434", "0.50000002980232238769531250", "1.5000000596046447753906250"}) {
    EXPECT_EQ(test::float_bits(parsed(tie)), test::float_bits(std::strtof(tie, nullptr))) << tie;
  }
  // Random midpoints m * 2^e (m odd, 25 bits) written out exactly in at most 19 digits.
  std::mt19937 rng(31337);
  for (int i = 0; i < 100000; ++i) {
    const double m = static_cast<double>((1U << 24) + 1U + 2U * (rng() % (1U << 23)));
    const int e = static_cast<int>(rng() % 54) - 16;  // m * 2^e < 10^19
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", e < 0 ? -e : 0, std::ldexp(m, e));
    ASSERT_EQ(test::float_bits(parsed(text)), test::float_bits(std::strtof(text, nullptr))) << text;
  }
}

TEST(TextParse, ShortDecimalsEqualHostStrtofBitForBit) {
  // Up to 9 significant digits, the point anywhere, exponents covering the
  // float range and beyond (underflow to zero, overflow).
  std::mt19937 rng(4242);
  size_t compared = 0;
  for (int i = 0; i < 200000; ++i) {
    const int digits = 1 + static_cast<int>(rng() % 9);
    std::string s = rng() % 2 ? "-" : "";
    const int point = static_cast<int>(rng() % static_cast<uint32_t>(digits + 1));
    for (int k = 0; k < digits; ++k) {
      if (k == point) s += '.';
      s += static_cast<char>('0' + rng() % 10);
    }
    s += "e" + std::to_string(static_cast<int>(rng() % 100) - 55);
    const float want = std::strtof(s.c_str(), nullptr);
    const Result<float> got = parse_decimal_float(s.c_str());
    if (std::isinf(want)) {
      EXPECT_EQ(got.status(), Status::kOutOfRange) << s;
      continue;
    }
    ASSERT_TRUE(got.ok()) << s;
    ASSERT_EQ(test::float_bits(got.value()), test::float_bits(want)) << s;
    ++compared;
  }
  std::printf("[ parse    ] identical to glibc strtof for %zu random short decimals\n", compared);
}

TEST(TextParse, PrintedFloatsReadBackExactly) {
  std::mt19937 rng(17);
  for (int i = 0; i < 200000; ++i) {
    const float v = test::float_from_bits(static_cast<uint32_t>(rng()));
    if (!std::isfinite(v)) continue;
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", static_cast<double>(v));
    ASSERT_EQ(test::float_bits(parsed(text)), test::float_bits(v)) << text;
  }
}

// Midpoint between the positive normal float with bits `u` and the next one, as a double (exact).
double midpoint_above(uint32_t u) {
  return (static_cast<double>(test::float_from_bits(u)) + static_cast<double>(test::float_from_bits(u + 1U))) / 2.0;
}

TEST(TextParse, LongDecimalsNearMidpointsMatchStrtofUnlessCloserThan2PowMinus58) {
  std::mt19937 rng(5);
  // 2^-50 (relative) away from a midpoint, 30 digits: identical.
  for (int i = 0; i < 50000; ++i) {
    const uint32_t u = 0x00800000U + rng() % (0x7F7FFFFFU - 0x00800000U);
    const double mid = midpoint_above(u);
    const double off = std::ldexp(mid, -50) * (rng() % 2 ? 1.0 : -1.0);
    char text[64];
    std::snprintf(text, sizeof text, "%.29e", mid + off);
    ASSERT_EQ(test::float_bits(parsed(text)), test::float_bits(std::strtof(text, nullptr))) << text;
  }
  // The midpoint itself in 17 to 40 digits (decimal rounding leaves it a hair
  // off, > 19 digits are held as 19): within 1 ulp, and counted.
  size_t differing = 0;
  size_t compared = 0;
  for (int i = 0; i < 50000; ++i) {
    const uint32_t u = 0x00800000U + rng() % (0x7F7FFFFFU - 0x00800000U);
    char text[64];
    std::snprintf(text, sizeof text, "%.*e", static_cast<int>(16 + rng() % 24), midpoint_above(u));
    const float want = std::strtof(text, nullptr);
    const float got = parsed(text);
    ASSERT_LE(ulps(got, want), 1) << text;
    differing += got != want ? 1U : 0U;
    ++compared;
  }
  EXPECT_EQ(parsed("1.000000059604644775390625"), 1.0F);  // the tie 1 + 2^-24 written out: even
  EXPECT_LE(ulps(parsed("1.0000000596046447753906250001"), 1.00000012F), 1);
  std::printf("[ parse    ] decimals at float midpoints: %zu of %zu differ from glibc strtof by 1 ulp\n", differing,
              compared);
}

// --- firmware printf formats ------------------------------------------------------

// String literals of a C++ source, comments and character literals skipped.
std::vector<std::string> string_literals(const std::string& src) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < src.size()) {
    if (src.compare(i, 2, "//") == 0) {
      i = src.find('\n', i);
      if (i == std::string::npos) break;
    } else if (src.compare(i, 2, "/*") == 0) {
      i = src.find("*/", i + 2);
      if (i == std::string::npos) break;
      i += 2;
    } else if (src[i] == '\'' || src[i] == '"') {
      const char quote = src[i++];
      std::string lit;
      while (i < src.size() && src[i] != quote) {
        if (src[i] == '\\' && i + 1 < src.size()) lit += src[i++];
        lit += src[i++];
      }
      ++i;
      if (quote == '"') out.push_back(lit);
    } else {
      ++i;
    }
  }
  return out;
}

// True when a printf format converts a float (%f %e %g %a) or a long long (%lld %llu %jd ...).
// Walks the conversion specifications: flags, width, precision, length, conversion.
bool converts_float_or_long_long(const std::string& format) {
  const auto is_digit = [](char c) { return c >= '0' && c <= '9'; };
  size_t i = 0;
  const size_t n = format.size();
  while (i < n) {
    if (format[i++] != '%') continue;
    if (i < n && format[i] == '%') {  // "%%" is a literal percent sign
      ++i;
      continue;
    }
    while (i < n && std::string("-+ #0'").find(format[i]) != std::string::npos) ++i;
    if (i < n && format[i] == '*') {
      ++i;
    } else {
      while (i < n && is_digit(format[i])) ++i;
    }
    if (i < n && format[i] == '.') {
      ++i;
      if (i < n && format[i] == '*') {
        ++i;
      } else {
        while (i < n && is_digit(format[i])) ++i;
      }
    }
    std::string length;
    for (const char* m : {"hh", "ll", "h", "l", "L", "j", "z", "t", "q"}) {
      if (format.compare(i, std::strlen(m), m) == 0) {
        length = m;
        break;
      }
    }
    i += length.size();
    if (i >= n) break;
    const char conv = format[i++];
    if (std::string("fFeEgGaA").find(conv) != std::string::npos) return true;
    const bool wide = length == "ll" || length == "L" || length == "j" || length == "q";
    if (wide && std::string("diouxX").find(conv) != std::string::npos) return true;
  }
  return false;
}

TEST(FirmwareFormats, NoPrintfFormatInFirmwareOrMps2ConvertsFloatsOrLongLong) {
  // picolibc's integer-only printf (the MPS2 image) prints neither: floats and
  // 64-bit values must go through firmware/text_format.hpp.
  const std::filesystem::path root(UWBNAV_SOURCE_DIR);
  size_t files = 0;
  for (const char* dir : {"firmware", "hal/mps2"}) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / dir)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".cpp" && ext != ".hpp") continue;
      std::ifstream in(entry.path());
      std::stringstream ss;
      ss << in.rdbuf();
      ++files;
      for (const std::string& lit : string_literals(ss.str())) {
        EXPECT_FALSE(converts_float_or_long_long(lit)) << entry.path() << ": \"" << lit << "\"";
      }
    }
  }
  EXPECT_GT(files, 10U);
}

TEST(FirmwareFormats, TheScanFindsFloatAndLongLongConversionsInStringLiteralsOnly) {
  const std::vector<std::string> lits = string_literals("a(\"x=%.3f\"); // \"%g\"\n b('\"'); c(\"%llu %s\");");
  ASSERT_EQ(lits.size(), 2U);
  EXPECT_EQ(lits[0], "x=%.3f");
  EXPECT_EQ(lits[1], "%llu %s");
  for (const char* bad : {"%f", "%.3f", "x=%-8.2e", "%g", "%.*g", "%*.*f", "%%%f", "%lf", "%A", "%llu", "%lld", "%08llx", "%jd", "%Lf"}) {
    EXPECT_TRUE(converts_float_or_long_long(bad)) << bad;
  }
  for (const char* fine : {"%s", "%lu", "%-58s", "0x%08lx", "%u", "%d", "100%% done", "%%f", "%zu", "%c"}) {
    EXPECT_FALSE(converts_float_or_long_long(fine)) << fine;
  }
}

}  // namespace
}  // namespace uwbnav
