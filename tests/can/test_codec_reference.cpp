// The float/integer CAN codec against the double-precision formula it replaced
// (round((phys - offset) / factor) in double, wrap_pi in double, raw * factor +
// offset in double): raw bits, Saturated flags and decoded floats must be
// identical for every signal of the message set.
//
// Where float could legitimately differ, and why the set is empty here:
// - Scaled signals: the new path computes round_half_away(p * inv + raw_zero)
//   exactly in integers. With offset 0 the old double quotient p / factor
//   equals that exact value x whenever the stored factor is within 2^-54
//   (relative) of 1/inv: x = p * inv has <= 40 significant bits, so it is a
//   double at least 2^-40 below the top of its binade, and x / (1 + d) with
//   |d| <= 2^-54 is closer to x than half an ulp of x. The one signal pair
//   with an offset (power: factor 0.5, exact) only rounds p + 128, which
//   cannot cross a half raw step (a float that close to a tie has no bits
//   that far below itself). The first test checks the factor precondition;
//   the others check the consequence on limits, just outside, every exact
//   +-0.5 raw tie, non-finite, subnormal and random values.
// - Decoding: (raw - raw_zero) / inv in float is correctly rounded; the old
//   double result differs from the exact quotient by ~1e-16 relative, and an
//   exact quotient is never closer than 3e-12 (relative) to a float rounding
//   boundary (k / inv is either a float or not dyadic), so both give the same
//   float. Checked for every raw value of every scaled signal.
// - Heading: in [-pi, pi] the old double wrap returned the float unchanged
//   wherever the rounding could notice (checked exhaustively on all ties and
//   on random values); outside, both wrap to within 1e-11 raw LSB of the true
//   angle (old: double rounding of a + pi, fmod by the double 2*pi; new: 2^-60
//   fixed point), so they can only disagree when the wrapped angle is within
//   that distance of a half LSB. The test allows exactly those cases (none
//   occur on the values tested) and, for |angle| >= 2^24 rad where a float
//   angle carries no fractional turn information, only requires an in-range,
//   unflagged raw value.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"
#include "tests/float_bits.hpp"

namespace uwbnav::can {
namespace {

// ---- The reference: the double-precision codec as it was ------------------

int64_t ref_raw_limit(const SignalDef& s, double phys) { return std::llround((phys - s.offset) / s.factor); }

int64_t ref_to_raw(const SignalDef& s, double phys, bool* flagged) {
  const int64_t raw_min = ref_raw_limit(s, s.min);
  const int64_t raw_max = ref_raw_limit(s, s.max);
  if (!std::isfinite(phys)) {
    switch (s.non_finite) {
      case NonFinite::kRawZeroNa:
        return 0;
      case NonFinite::kMaxFlagged:
        *flagged = true;
        return raw_max;
#if UWBNAV_COOP
      case NonFinite::kRawMinNa:
        return -(int64_t{1} << (s.bit_len - 1));
#endif
      case NonFinite::kZeroFlagged:
        break;
    }
    *flagged = true;
    phys = 0.0;
  }
  const double r = std::round((phys - s.offset) / s.factor);
  if (r < static_cast<double>(raw_min)) {
    *flagged = true;
    return raw_min;
  }
  if (r > static_cast<double>(raw_max)) {
    *flagged = true;
    return raw_max;
  }
  return static_cast<int64_t>(r);
}

double ref_to_phys(const SignalDef& s, int64_t raw) {
  if (s.non_finite == NonFinite::kRawZeroNa && raw == 0) return std::nan("");
#if UWBNAV_COOP
  if (s.non_finite == NonFinite::kRawMinNa && raw == -(int64_t{1} << (s.bit_len - 1))) return std::nan("");
#endif
  return static_cast<double>(raw) * s.factor + s.offset;
}

constexpr double kPi = 3.14159265358979323846;

double ref_wrap_pi(double angle_rad) {
  if (!std::isfinite(angle_rad)) return angle_rad;
  double a = std::fmod(angle_rad + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

// pack_message() as it was: every payload signal from a double, then the flag and E2E.
bool ref_pack(const MessageDef& m, const double* phys, uint8_t counter, hal::CanFrame& out) {
  out.id = m.id;
  out.len = m.dlc;
  out.flags = 0;
  for (auto& b : out.data) b = 0;
  bool saturated = false;
  for (uint8_t i = kFirstPayloadSignal; i < m.num_signals; ++i) {
    const SignalDef& s = m.signals[i];
    const int64_t raw = ref_to_raw(s, phys[i], &saturated);
    put_bits(out.data, s.start_bit, s.bit_len, static_cast<uint64_t>(raw) & ((uint64_t{1} << s.bit_len) - 1U));
  }
  put_bits(out.data, m.signals[kSigSaturated].start_bit, 1, saturated ? 1U : 0U);
  e2e_protect(m.data_id, counter, out.data, out.len);
  return saturated;
}

// ---- Helpers ---------------------------------------------------------------

bool is_count(const SignalDef& s) { return s.factor == 1.0 && s.offset == 0.0 && s.min == 0.0 && !s.is_signed; }

struct Signal {
  const MessageDef* msg;
  const SignalDef* def;
  const SignalLayout* layout;
  std::string name() const { return std::string(msg->name) + "." + def->name; }
};

std::vector<Signal> scaled_signals() {
  std::vector<Signal> out;
  for (const MessageDef& m : kMessages) {
    const MessageLayout& l = *find_layout(m.id);
    for (uint8_t k = kFirstPayloadSignal; k < m.num_signals; ++k) {
      if (!is_count(m.signals[k])) out.push_back({&m, &m.signals[k], &signal_layout(l, k)});
    }
  }
  return out;
}

Signal heading_signal() {
  for (const Signal& s : scaled_signals()) {
    if (std::string(s.def->name) == "Heading") return s;
  }
  return {};
}

// Physical values that probe one scaled signal: specials, limits and their
// neighbours, every exactly representable +-0.5 raw tie in (and just outside)
// range with its float neighbours, near-ties of random raw values, random
// values in 1.5x the range and random bit patterns.
std::vector<float> probe_values(const Signal& s, std::mt19937& rng) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<float> v = {0.0F, -0.0F, std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                          std::numeric_limits<float>::min(), -std::numeric_limits<float>::min(),
                          std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(), kInf, -kInf,
                          std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN(),
                          1e-30F, -1e-30F, 1e30F, -1e30F, 8388608.0F, -8388608.0F, 16777216.0F, 3.0e7F};
  const double lo = s.def->min - 2.0 * s.def->factor;
  const double hi = s.def->max + 2.0 * s.def->factor;
  auto with_neighbours = [&v](float x, int n) {
    float up = x;
    float down = x;
    v.push_back(x);
    for (int i = 0; i < n; ++i) {
      up = std::nextafter(up, std::numeric_limits<float>::infinity());
      down = std::nextafter(down, -std::numeric_limits<float>::infinity());
      v.push_back(up);
      v.push_back(down);
    }
  };
  for (const double edge : {s.def->min, s.def->max, s.def->min - s.def->factor, s.def->max + s.def->factor,
                            s.def->min - 0.5 * s.def->factor, s.def->max + 0.5 * s.def->factor,
                            s.def->min + 0.5 * s.def->factor, s.def->max - 0.5 * s.def->factor}) {
    with_neighbours(static_cast<float>(edge), 4);
  }
  // Exact ties: p * inv + raw_zero = k + 1/2 needs p = odd * 2^-(1 + v2(inv)).
  // Every one of them for ordinary signals; for the wide ones (cooperative
  // positions, +-2147 km) those within +-2^16 m, near the limits and 10^6 random
  // ones (above 2^20 m a float holds no tie at all: its ulp exceeds the step).
  int twos = 1;
  for (unsigned inv = s.layout->inv_factor; inv % 2 == 0; inv /= 2) ++twos;
  const double step = std::ldexp(1.0, -twos);
  auto ties_in = [&](double a, double b) {
    for (double p = std::ceil(a / step) * step; p <= b; p += step) {
      if (std::fmod(std::fabs(p) / step, 2.0) == 1.0) with_neighbours(static_cast<float>(p), 1);
    }
  };
  if ((hi - lo) / step <= 4.0e7) {
    ties_in(lo, hi);
  } else {
    ties_in(-65536.0, 65536.0);
    ties_in(lo, lo + 4096.0 * step);
    ties_in(hi - 4096.0 * step, hi);
    std::uniform_real_distribution<double> anywhere(lo, hi);
    for (int i = 0; i < 1000000; ++i) {
      const double p = (2.0 * std::floor(anywhere(rng) / (2.0 * step)) + 1.0) * step;
      with_neighbours(static_cast<float>(p), 1);
    }
  }
  std::uniform_int_distribution<int64_t> raw(s.layout->raw_min, s.layout->raw_max);
  for (int i = 0; i < 20000; ++i) {
    with_neighbours(static_cast<float>((static_cast<double>(raw(rng)) + 0.5) * s.def->factor + s.def->offset), 2);
  }
  std::uniform_real_distribution<float> wide(static_cast<float>(1.5 * lo), static_cast<float>(1.5 * hi));
  std::uniform_int_distribution<uint32_t> any;
  for (int i = 0; i < 100000; ++i) {
    v.push_back(wide(rng));
    v.push_back(test::float_from_bits(any(rng)));
  }
  return v;
}

// ---- Tests -----------------------------------------------------------------

TEST(CanCodecReference, EveryTableFactorIsWithinTwoToTheMinus54OfOneOverAnInteger) {
  // Precondition of the exactness argument above. fma rounds factor * inv - 1
  // once, from the exact product, so the tiny difference is measured exactly
  // enough (to 2^-53 of itself).
  for (const Signal& s : scaled_signals()) {
    const double rel = std::fma(s.def->factor, static_cast<double>(s.layout->inv_factor), -1.0);
    EXPECT_LE(std::fabs(rel), 0x1p-54) << s.name() << " inv " << s.layout->inv_factor << " rel " << rel;
    // offset / factor is the integer -raw_zero.
    EXPECT_EQ(s.def->offset * s.layout->inv_factor, -static_cast<double>(s.layout->raw_zero)) << s.name();
  }
}

TEST(CanCodecReference, EveryScaledSignalEncodesBitIdenticalToTheDoubleFormula) {
  std::mt19937 rng(20240611);
  size_t tested = 0;
  for (const Signal& s : scaled_signals()) {
    if (std::string(s.def->name) == "Heading") continue;  // encoded through raw_from_angle, next test
    size_t mismatches = 0;
    for (const float p : probe_values(s, rng)) {
      bool flag_new = false;
      bool flag_ref = false;
      const int64_t raw_new = raw_from_phys(*s.layout, p, &flag_new);
      const int64_t raw_ref = ref_to_raw(*s.def, static_cast<double>(p), &flag_ref);
      ++tested;
      if (raw_new != raw_ref || flag_new != flag_ref) {
        if (++mismatches <= 5) {
          ADD_FAILURE() << s.name() << " phys " << p << " (0x" << std::hex << test::float_bits(p) << std::dec << "): raw "
                        << raw_new << " flag " << flag_new << ", double formula " << raw_ref << " flag " << flag_ref;
        }
      }
    }
    EXPECT_EQ(mismatches, 0U) << s.name();
  }
  EXPECT_GT(tested, 5000000U);
}

TEST(CanCodecReference, HeadingEncodesBitIdenticalToTheDoubleWrap) {
  const Signal h = heading_signal();
  ASSERT_NE(h.def, nullptr);
  const double inv = h.layout->inv_factor;
  size_t exact = 0;
  size_t near_tie = 0;
  size_t mismatches = 0;
  auto check = [&](float a) {
    bool flag_new = false;
    bool flag_ref = false;
    const int64_t raw_new = raw_from_angle(*h.layout, a, &flag_new);
    const double wrapped = ref_wrap_pi(static_cast<double>(a));
    const int64_t raw_ref = ref_to_raw(*h.def, wrapped, &flag_ref);
    ASSERT_EQ(flag_new, flag_ref) << a;
    if (!std::isfinite(a)) {
      EXPECT_EQ(raw_new, raw_ref);
      return;
    }
    EXPECT_FALSE(flag_new) << "a wrapped angle never saturates: " << a;
    ASSERT_GE(raw_new, h.layout->raw_min);
    ASSERT_LE(raw_new, h.layout->raw_max);
    if (std::fabs(a) >= 0x1p24F) return;  // no fractional turn left in the float: any in-range raw is right
    if (raw_new == raw_ref) {
      ++exact;
      return;
    }
    // Allowed only where the double reference itself was within its own error
    // ((|a| + 8) * 2^-50 rad) of a half LSB, and then by one LSB.
    const double unrounded = wrapped * inv;
    const double to_tie = std::fabs(unrounded - std::floor(unrounded) - 0.5);
    const double old_error = (std::fabs(static_cast<double>(a)) + 8.0) * 0x1p-50 * inv;
    if (to_tie <= old_error && std::llabs(raw_new - raw_ref) == 1) {
      ++near_tie;
    } else if (++mismatches <= 5) {
      ADD_FAILURE() << "heading " << a << " (0x" << std::hex << test::float_bits(a) << std::dec << "): raw " << raw_new
                    << ", double wrap " << raw_ref;
    }
  };
  // Every float with pi < |a| <= 3 pi (all headings off by one turn), exhaustively.
  for (uint32_t b = test::float_bits(3.14159274F); b <= test::float_bits(static_cast<float>(3.0 * kPi)); ++b) {
    check(test::float_from_bits(b));
    check(-test::float_from_bits(b));
  }
  // Every +-0.5 LSB tie inside [-pi, pi] (a = odd / 32) with its neighbours.
  for (int j = -101; j <= 101; j += 2) {
    const float a = static_cast<float>(j) / 32.0F;
    check(a);
    check(std::nextafter(a, 4.0F));
    check(std::nextafter(a, -4.0F));
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> in_range(-3.1415927F, 3.1415927F);
  std::uniform_real_distribution<float> turns(-1000.0F, 1000.0F);
  std::uniform_int_distribution<uint32_t> any;
  for (int i = 0; i < 1000000; ++i) {
    check(in_range(rng));
    check(turns(rng));
    check(test::float_from_bits(any(rng)));
  }
  for (const float a : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                        -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::max(),
                        -std::numeric_limits<float>::max(), 3.14159274F, -3.14159274F, 3.1415925F, -3.1415925F}) {
    check(a);
  }
  EXPECT_EQ(mismatches, 0U);
  EXPECT_EQ(near_tie, 0U) << "allowed, but none expected on these values";
  EXPECT_GT(exact, 25000000U);
}

TEST(CanCodecReference, EveryRawValueDecodesToTheSameFloatAsTheDoubleFormula) {
  for (const Signal& s : scaled_signals()) {
    const int64_t lo = s.def->is_signed ? -(int64_t{1} << (s.def->bit_len - 1)) : 0;
    const int64_t hi = s.def->is_signed ? (int64_t{1} << (s.def->bit_len - 1)) - 1 : (int64_t{1} << s.def->bit_len) - 1;
    if (hi - lo > (int64_t{1} << 26)) continue;  // wide signals: next test
    size_t mismatches = 0;
    for (int64_t raw = lo; raw <= hi; ++raw) {
      const float got = phys_from_raw(*s.layout, raw);
      const auto want = static_cast<float>(ref_to_phys(*s.def, raw));
      if (test::float_bits(got) != test::float_bits(want) && !(std::isnan(got) && std::isnan(want)) && ++mismatches <= 5) {
        ADD_FAILURE() << s.name() << " raw " << raw << ": " << got << " vs double formula " << want;
      }
    }
    EXPECT_EQ(mismatches, 0U) << s.name();
  }
}

#if UWBNAV_COOP
// Wide signals (32-bit cooperative positions, |raw| up to 2^31, not all exact in
// float) decode by an exact integer division: the float nearest to raw / inv,
// ties to even. The reference is the double quotient rounded to float, which is
// that float (the double quotient is exact at a tie; elsewhere within 2^-53
// relative, while k / 1000 is at least 2^-33 relative from a tie). The double
// product raw * factor of the old formula could only differ at exact ties (|value|
// in [2^21, 2^22) m, raw an odd multiple of 125: all of them are checked), and
// then the new result must be the even neighbour.
TEST(CanCodecReference, WideSignalsDecodeToTheNearestFloatTiesToEven) {
  std::mt19937 rng(31);
  size_t wide = 0;
  for (const Signal& s : scaled_signals()) {
    if (s.def->bit_len <= 26) continue;
    ++wide;
    const int64_t lo = -(int64_t{1} << (s.def->bit_len - 1));
    const int64_t hi = (int64_t{1} << (s.def->bit_len - 1)) - 1;
    const double inv = s.layout->inv_factor;
    size_t mismatches = 0;
    size_t ties = 0;
    auto check = [&](int64_t raw) {
      const float got = phys_from_raw(*s.layout, raw);
      const auto want = static_cast<float>(static_cast<double>(raw - s.layout->raw_zero) / inv);
      if (test::float_bits(got) != test::float_bits(want) && ++mismatches <= 5) {
        ADD_FAILURE() << s.name() << " raw " << raw << ": " << got << " vs nearest float " << want;
      }
      const auto old = static_cast<float>(ref_to_phys(*s.def, raw));
      if (test::float_bits(old) != test::float_bits(got)) {
        // Only an exact tie between two floats may differ: got is then even.
        const double exact = static_cast<double>(raw) / inv;
        const double gap = std::fabs(static_cast<double>(old) - static_cast<double>(got));
        EXPECT_EQ(std::fabs(exact - static_cast<double>(got)), gap / 2.0) << s.name() << " raw " << raw;
        EXPECT_EQ(test::float_bits(got) & 1U, 0U) << s.name() << " raw " << raw;
        ++ties;
      }
    };
    for (int64_t raw = -(int64_t{1} << 20); raw <= (int64_t{1} << 20); ++raw) check(raw);
    // Around 2^24, where decoding switches from the float division to the integer one.
    for (int64_t raw = (int64_t{1} << 24) - (int64_t{1} << 20); raw <= (int64_t{1} << 24) + (int64_t{1} << 22); ++raw) {
      check(raw);
      check(-raw);
    }
    for (int64_t raw = lo; raw < lo + 100000; ++raw) check(raw);
    for (int64_t raw = hi - 100000; raw <= hi; ++raw) check(raw);
    std::uniform_int_distribution<int64_t> any(lo, hi);
    for (int i = 0; i < 5000000; ++i) check(any(rng));
    // Every exact tie above 2^21 m: raw = 125 * odd with |raw| / 1000 in [2^21, 2^22).
    for (int64_t k = 2097152000 / 125 + 1; k * 125 <= hi; k += 2) {
      check(k * 125);
      check(-k * 125);
    }
    EXPECT_EQ(mismatches, 0U) << s.name();
    EXPECT_LE(ties, 300000U) << s.name();  // old formula off only at ties (none expected: its product lands on them)
  }
  EXPECT_EQ(wide, (UWBNAV_COOP ? 4U : 0U) + (UWBNAV_GNSS ? 2U : 0U)) << "Coop_PosX/Y, Neighbour_PosX/Y, Gnss_PosX/Y";
}
#endif

// Typed encode() against the old packer fed the old double values, frame by
// frame; time and counter signals at and beyond their field limits.
TEST(CanCodecReference, TypedFramesAreBitIdenticalToTheDoublePacker) {
  std::mt19937 rng(99);
  std::uniform_int_distribution<uint32_t> any;
  std::uniform_real_distribution<float> unit(-1.2F, 1.2F);
  const float kNan = std::numeric_limits<float>::quiet_NaN();
  // Mostly in range, sometimes out of range, NaN or an arbitrary bit pattern.
  auto value = [&](double scale) {
    const uint32_t pick = any(rng) % 16;
    if (pick == 0) return kNan;
    if (pick == 1) return test::float_from_bits(any(rng));
    return unit(rng) * static_cast<float>(scale);
  };
  const uint64_t counts[] = {0, 1, 3, 4, 7, 8, 255, 256, 65535, 65536, 0xFFFFFFFFULL, 0x100000000ULL,
                             (uint64_t{1} << 48) - 1, uint64_t{1} << 48, ~uint64_t{0}};
  auto count = [&]() { return any(rng) % 4 == 0 ? counts[any(rng) % 15] : uint64_t{any(rng)} % 300; };
  auto same = [](const MessageDef* m, const double* v, bool sat, const hal::CanFrame& f, uint8_t counter) {
    hal::CanFrame ref;
    const bool ref_sat = ref_pack(*m, v, counter, ref);
    EXPECT_EQ(sat, ref_sat) << m->name;
    EXPECT_EQ(f.id, ref.id);
    EXPECT_EQ(f.len, ref.len);
    EXPECT_EQ(std::memcmp(f.data, ref.data, sizeof f.data), 0) << m->name;
  };
  auto f64 = [](float x) { return static_cast<double>(x); };
  for (int i = 0; i < 20000; ++i) {
    const auto counter = static_cast<uint8_t>(i % 15);
    hal::CanFrame f;
    const NavTimeMsg nt{count() * 4099U, static_cast<NavMode>(any(rng) % 6)};
    const double nt_v[] = {0, 0, 0, static_cast<double>(nt.mode), static_cast<double>(nt.nav_t_us)};
    same(find_message(id_of(MsgId::kNavTime)), nt_v, encode(nt, counter, f), f, counter);

    const PosXYMsg xy{static_cast<NavStatus>(any(rng) % 4), value(9000), value(9000)};
    const double xy_v[] = {0, 0, 0, static_cast<double>(xy.status), f64(xy.x_nav_m), f64(xy.y_nav_m)};
    same(find_message(id_of(MsgId::kPosXY)), xy_v, encode(xy, counter, f), f, counter);

    const PosZMsg z{static_cast<NavStatus>(any(rng) % 4), value(40), value(400), static_cast<uint16_t>(count()),
                    static_cast<uint16_t>(count())};
    const double z_v[] = {0, 0, 0, static_cast<double>(z.status), f64(z.z_nav_m), f64(z.vz_nav_mps),
                          static_cast<double>(z.ranges_used), static_cast<double>(z.ranges_rejected)};
    same(find_message(id_of(MsgId::kPosZ)), z_v, encode(z, counter, f), f, counter);

    // Headings beyond 2^24 rad have no defined wrap (see the heading test): not compared here.
    float heading = value(10);
    if (std::isfinite(heading) && std::fabs(heading) >= 0x1p24F) heading = unit(rng) * 10.0F;
    const VelHdgMsg vh{value(400), value(400), heading};
    const double vh_v[] = {0, 0, 0, f64(vh.vx_nav_mps), f64(vh.vy_nav_mps), ref_wrap_pi(f64(vh.heading_rad))};
    same(find_message(id_of(MsgId::kVelHdg)), vh_v, encode(vh, counter, f), f, counter);

    const AccuracyMsg acc{value(25), value(25), value(25), value(1.1)};
    const double acc_v[] = {0, 0, 0, f64(acc.sigma_x_m), f64(acc.sigma_y_m), f64(acc.sigma_z_m), f64(acc.corr_xy)};
    same(find_message(id_of(MsgId::kAccuracy)), acc_v, encode(acc, counter, f), f, counter);

    const DiagMsg dg{static_cast<uint16_t>(count()), static_cast<uint32_t>(count()), count(),
                     static_cast<uint32_t>(count())};
    const double dg_v[] = {0, 0, 0, static_cast<double>(dg.resets), static_cast<double>(dg.nlos_mask),
                           static_cast<double>(dg.overruns), static_cast<double>(dg.input_rejects)};
    same(find_message(id_of(MsgId::kDiag)), dg_v, encode(dg, counter, f), f, counter);

    const HilImuTimeMsg it{any(rng)};
    const double it_v[] = {0, 0, 0, static_cast<double>(it.t_sensor_us)};
    same(find_message(id_of(MsgId::kHilImuTime)), it_v, encode(it, counter, f), f, counter);
    HilImuTimeMsg it_back;
    ASSERT_EQ(decode(f, it_back), Status::kOk);
    EXPECT_EQ(it_back.t_sensor_us, it.t_sensor_us) << "32-bit timestamps decode exactly";

    const HilImuAccelMsg ia{Vec3f{value(200), value(200), value(200)}};
    const double ia_v[] = {0, 0, 0, f64(ia.accel_body_mps2.x), f64(ia.accel_body_mps2.y), f64(ia.accel_body_mps2.z)};
    same(find_message(id_of(MsgId::kHilImuAccel)), ia_v, encode(ia, counter, f), f, counter);

    const HilImuGyroMsg ig{Vec3f{value(40), value(40), value(40)}};
    const double ig_v[] = {0, 0, 0, f64(ig.gyro_body_radps.x), f64(ig.gyro_body_radps.y), f64(ig.gyro_body_radps.z)};
    same(find_message(id_of(MsgId::kHilImuGyro)), ig_v, encode(ig, counter, f), f, counter);

    const HilUwbRangeMsg ur{static_cast<uint16_t>(any(rng)), static_cast<uint8_t>(any(rng)), value(9000)};
    const double ur_v[] = {0, 0, 0, static_cast<double>(ur.anchor_id), static_cast<double>(ur.tag_id), f64(ur.range_m)};
    same(find_message(id_of(MsgId::kHilUwbRange)), ur_v, encode(ur, counter, f), f, counter);

    const HilUwbTimeMsg ut{any(rng), value(140) - 64.0F, value(140) - 64.0F};
    const double ut_v[] = {0, 0, 0, static_cast<double>(ut.t_sensor_us), f64(ut.fp_power_dbm), f64(ut.rx_power_dbm)};
    same(find_message(id_of(MsgId::kHilUwbTime)), ut_v, encode(ut, counter, f), f, counter);

#if UWBNAV_COOP
    for (const CoopGroup g : {CoopGroup::kOwn, CoopGroup::kNeighbour}) {
      CoopParts cp;
      cp.valid = any(rng) % 2 == 0;
      cp.cooperative = any(rng) % 3 == 0;
      cp.vehicle_id = static_cast<uint16_t>(any(rng));
      cp.t_sensor_us = any(rng);
      cp.pos_nav_m = Vec3f{value(2.0e6), value(2.0e6), value(15000)};
      cp.vel_nav_mps = Vec3f{value(300), value(300), value(300)};
      cp.sigma_m = Vec3f{value(60), value(60), value(60)};
      cp.corr_xy = value(1.0);
      cp.corr_xz = value(1.0);
      cp.corr_yz = value(1.0);
      const double parts[kCoopFrames][7] = {
          {0, 0, 0, cp.valid ? 1.0 : 0.0, cp.cooperative ? 1.0 : 0.0, static_cast<double>(cp.vehicle_id),
           static_cast<double>(cp.t_sensor_us)},
          {0, 0, 0, f64(cp.pos_nav_m.x), f64(cp.vel_nav_mps.x)},
          {0, 0, 0, f64(cp.pos_nav_m.y), f64(cp.vel_nav_mps.y)},
          {0, 0, 0, f64(cp.pos_nav_m.z), f64(cp.vel_nav_mps.z)},
          {0, 0, 0, f64(cp.sigma_m.x), f64(cp.sigma_m.y), f64(cp.sigma_m.z)},
          {0, 0, 0, f64(cp.corr_xy), f64(cp.corr_xz), f64(cp.corr_yz)}};
      for (size_t k = 0; k < kCoopFrames; ++k) {
        const MessageDef* m = find_message(coop_id(g, k));
        ASSERT_NE(m, nullptr);
        same(m, parts[k], encode_coop_part(cp, g, k, counter, f), f, counter);
      }
    }
#endif
  }
  hal::CanFrame f;
  NavTimeMsg t;
  for (const uint64_t us : {uint64_t{0}, (uint64_t{1} << 48) - 1, (uint64_t{1} << 53) + 1}) {
    encode(NavTimeMsg{us}, 0, f);
    ASSERT_EQ(decode(f, t), Status::kOk);
    EXPECT_EQ(t.nav_t_us, std::min(us, (uint64_t{1} << 48) - 1)) << "48-bit time decodes exactly";
  }
}

}  // namespace
}  // namespace uwbnav::can
