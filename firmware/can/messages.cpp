// The CAN codec: the run-time signal layout derived at compile time from the
// message table (firmware/can/message_table.hpp), exact float <-> raw
// conversion in integer arithmetic, Intel-order packing with saturation, and the
// typed encode/decode functions. No double and no table string reaches the image.
#include "firmware/can/messages.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "firmware/can/e2e.hpp"

namespace uwbnav::can {
namespace {

static_assert(std::numeric_limits<float>::is_iec559, "raw_from_phys decodes IEEE-754 binary32");

// ---- Compile-time derivation of the run-time layout ----------------------

constexpr double kPi = 3.14159265358979323846;
constexpr int64_t kScaledRawLimit = int64_t{1} << 24;  // raw (and raw - raw_zero) exact in float
#if UWBNAV_CAN_WIDE
// Wide signals (the cooperative positions, 32 bit): raw - raw_zero up to 2^31,
// decoded by an exact integer division (quotient_nearest) instead of in float.
constexpr int64_t kWideRawLimit = int64_t{1} << 31;
#endif

constexpr double abs_d(double v) { return v < 0.0 ? -v : v; }

constexpr int64_t inv_factor_of(const SignalDef& s) { return round_half_away(1.0 / s.factor); }
constexpr int64_t raw_zero_of(const SignalDef& s) {
  return round_half_away(-s.offset * static_cast<double>(inv_factor_of(s)));
}
constexpr int64_t raw_of(const SignalDef& s, double phys) { return round_half_away((phys - s.offset) / s.factor); }
constexpr int64_t field_min(const SignalDef& s) { return s.is_signed ? -(int64_t{1} << (s.bit_len - 1)) : 0; }
constexpr int64_t field_max(const SignalDef& s) {
  return s.is_signed ? (int64_t{1} << (s.bit_len - 1)) - 1 : (int64_t{1} << s.bit_len) - 1;
}

// 'c': an unsigned integer count, encoded as it is and clipped to the field maximum.
constexpr bool is_count(const SignalDef& s) {
  return s.factor == 1.0 && s.offset == 0.0 && s.min == 0.0 && !s.is_signed && s.bit_len <= 53 &&
         s.max == static_cast<double>(field_max(s));
}

// A "not reported" code outside the signal's clipping range (kRawMinNa: the
// field minimum, below the raw value of min) never collides with a value.
constexpr bool na_code_ok(const SignalDef& s) {
#if UWBNAV_CAN_WIDE
  if (s.non_finite == NonFinite::kRawMinNa) return s.is_signed && raw_of(s, s.min) > field_min(s);
#endif
  static_cast<void>(s);
  return true;
}

// 1/factor and offset/factor are integers (so the integer formula of
// SignalLayout is exact) and every raw value of the field minus raw_zero lies
// within +-limit.
constexpr bool is_scaled_within(const SignalDef& s, int64_t limit) {
  const int64_t inv = inv_factor_of(s);
  const int64_t zero = raw_zero_of(s);
  const double zero_exact = -s.offset * static_cast<double>(inv);
  return inv >= 1 && inv <= 65535 && abs_d(1.0 / s.factor - static_cast<double>(inv)) <= 1e-9 * static_cast<double>(inv) &&
         abs_d(zero_exact - static_cast<double>(zero)) <= 1e-9 && zero >= -32768 && zero <= 32767 &&
         raw_of(s, s.min) <= raw_of(s, s.max) && raw_of(s, s.min) >= field_min(s) && raw_of(s, s.max) <= field_max(s) &&
         field_min(s) - zero >= -limit && field_max(s) - zero <= limit && na_code_ok(s);
}

// 'p': a scaled physical value whose raw values minus raw_zero are all exact
// in float (so decoding is one correctly rounded float division).
constexpr bool is_scaled(const SignalDef& s) { return is_scaled_within(s, kScaledRawLimit); }

// 'w': a wide scaled value (at most 32 bits, |raw - raw_zero| up to 2^31):
// encoded like 'p', decoded by an exact integer division (quotient_nearest).
constexpr bool is_wide(const SignalDef& s) {
#if UWBNAV_CAN_WIDE
  return !is_scaled(s) && s.bit_len <= 32 && is_scaled_within(s, kWideRawLimit);
#else
  static_cast<void>(s);
  return false;
#endif
}

// 'a': a scaled angle [rad] with offset 0 whose raw limits hold every wrapped angle.
constexpr bool is_angle(const SignalDef& s) {
  const int64_t pi_raw = round_half_away(kPi * static_cast<double>(inv_factor_of(s)));
  return is_scaled(s) && s.offset == 0.0 && raw_of(s, s.max) >= pi_raw && raw_of(s, s.min) <= -pi_raw;
}

constexpr bool header_ok(const MessageDef& m) {
  const SignalDef* s = m.signals;
  return m.num_signals > kFirstPayloadSignal && m.num_signals <= kMaxSignals && m.dlc == 8 && m.id <= 0x7FFU &&
         s[kSigCrc].start_bit == 0 && s[kSigCrc].bit_len == 8 && s[kSigCounter].start_bit == 8 &&
         s[kSigCounter].bit_len == 4 && s[kSigSaturated].start_bit == 15 && s[kSigSaturated].bit_len == 1;
}

constexpr size_t index_of(MsgId id) {
  size_t i = 0;
  while (i < kNumMessages && kMessages[i].id != id_of(id)) ++i;
  return i;
}

// True when the payload signals of `id` are, in order, of the kinds in `kinds`
// ('c' count, 'p' scaled, 'a' angle): ties each typed encode/decode below to the table.
constexpr bool kinds_are(MsgId id, const char* kinds) {
  const size_t i = index_of(id);
  if (i >= kNumMessages || !header_ok(kMessages[i])) return false;
  const MessageDef& m = kMessages[i];
  uint8_t k = kFirstPayloadSignal;
  for (; kinds[k - kFirstPayloadSignal] != '\0'; ++k) {
    if (k >= m.num_signals) return false;
    const SignalDef& s = m.signals[k];
    const char c = kinds[k - kFirstPayloadSignal];
    if (!((c == 'c' && is_count(s)) || (c == 'p' && is_scaled(s)) || (c == 'w' && is_wide(s)) ||
          (c == 'a' && is_angle(s)))) {
      return false;
    }
  }
  return k == m.num_signals;
}

constexpr size_t count_payload_signals() {
  size_t n = 0;
  for (const MessageDef& m : kMessages) n += m.num_signals - kFirstPayloadSignal;
  return n;
}

constexpr size_t kNumPayloadSignals = count_payload_signals();

struct Layouts {
  MessageLayout messages[kNumMessages];
  SignalLayout signals[kNumPayloadSignals];
};

constexpr SignalLayout layout_from(const SignalDef& s) {
  SignalLayout l{};
  const bool scaled = is_scaled(s) || is_wide(s);
  l.raw_min = scaled ? static_cast<int32_t>(raw_of(s, s.min)) : 0;
  l.raw_max = scaled ? static_cast<int32_t>(raw_of(s, s.max)) : 0;
  l.inv_factor = static_cast<uint16_t>(inv_factor_of(s));
  l.raw_zero = static_cast<int16_t>(raw_zero_of(s));
  l.start_bit = s.start_bit;
  l.bit_len = s.bit_len;
  l.is_signed = s.is_signed;
  l.non_finite = s.non_finite;
  return l;
}

constexpr Layouts make_layouts() {
  Layouts l{};
  size_t k = 0;
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    l.messages[i] = MessageLayout{static_cast<uint16_t>(m.id), m.data_id, m.dlc, static_cast<uint8_t>(k),
                                  static_cast<uint8_t>(m.num_signals - kFirstPayloadSignal)};
    for (uint8_t j = kFirstPayloadSignal; j < m.num_signals; ++j) l.signals[k++] = layout_from(m.signals[j]);
  }
  return l;
}

// The only table the firmware reads at run time (8 B per message, 16 B per signal).
constexpr Layouts kLayouts = make_layouts();

template <MsgId kId>
const MessageLayout& layout() {
  constexpr size_t i = index_of(kId);
  static_assert(i < kNumMessages, "message missing from kMessages");
  return kLayouts.messages[i];
}

// ---- Exact float <-> raw --------------------------------------------------

// |v| = mantissa * 2^exponent for a finite float (subnormals included).
struct FloatParts {
  uint32_t mantissa;  // < 2^24
  int exponent;       // -149..104
  bool negative;
};

FloatParts split(float v) {
  uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  const uint32_t biased = (bits >> 23) & 0xFFU;
  const uint32_t fraction = bits & 0x7FFFFFU;
  FloatParts p{};
  p.negative = (bits >> 31) != 0;
  p.mantissa = biased == 0 ? fraction : (fraction | 0x800000U);
  p.exponent = (biased == 0 ? 1 : static_cast<int>(biased)) - 150;
  return p;
}

// Round half away from zero of y / 2^shift, 1 <= shift <= 62, |y| < 2^62.
int64_t shift_round(int64_t y, int shift) {
  const uint64_t mag = y < 0 ? 0U - static_cast<uint64_t>(y) : static_cast<uint64_t>(y);
  const auto q = static_cast<int64_t>((mag + (uint64_t{1} << (shift - 1))) >> shift);
  return y < 0 ? -q : q;
}

int64_t clip(const SignalLayout& s, int64_t raw, bool* flagged) {
  if (raw < s.raw_min) {
    *flagged = true;
    return s.raw_min;
  }
  if (raw > s.raw_max) {
    *flagged = true;
    return s.raw_max;
  }
  return raw;
}

// 2*pi in units of 2^-60 rad, rounded to nearest (error 0.38 units < 2^-61 rad).
constexpr uint64_t kTwoPiQ60 = 7244019458077122842ULL;
// The largest float below pi: every float in [-kPiBelowF, kPiBelowF] is inside [-pi, pi].
constexpr float kPiBelowF = 3.14159250F;
static_assert(static_cast<double>(kPiBelowF) < kPi && static_cast<double>(kPiBelowF) + 0x1p-22 > kPi,
              "kPiBelowF must be the float just below pi (ulp 2^-22 in [2, 4))");

#if UWBNAV_CAN_WIDE
// The float nearest to n / d (ties to even), for a wide signal's
// raw - raw_zero = n (|n| <= 2^31) and d = 1 / factor: the integer quotient to
// 47+ bits with a sticky remainder, rounded once to 24 bits. Exact like the
// float division of the narrow signals, which cannot be used here because n
// itself may not be a float.
float quotient_nearest(int64_t n, uint32_t d) {
  if (n == 0) return 0.0F;
  const bool negative = n < 0;
  uint64_t m = negative ? 0U - static_cast<uint64_t>(n) : static_cast<uint64_t>(n);
  int shift = 0;
  while ((m >> 62) == 0) {  // normalise: bit 62 is the top bit
    m <<= 1;
    ++shift;
  }
  const uint64_t q = m / d;  // >= 2^62 / 2^16: at least 47 significant bits
  const bool sticky = m % d != 0;
  int top = 62;
  while ((q >> top) == 0) --top;
  int drop = top - 23;  // keep 24 significant bits
  uint64_t keep = q >> drop;
  const uint64_t rest = q & ((uint64_t{1} << drop) - 1U);
  const uint64_t half = uint64_t{1} << (drop - 1);
  if (rest > half || (rest == half && (sticky || (keep & 1U) != 0))) ++keep;
  if (keep == (uint64_t{1} << 24)) {
    keep >>= 1;
    ++drop;
  }
  // value = keep * 2^(drop - shift), keep in [2^23, 2^24): a normal float
  // (|n / d| >= 2^-16), biased exponent drop - shift + 150.
  const uint32_t bits = (negative ? 0x80000000U : 0U) |
                        (static_cast<uint32_t>(drop - shift + 150) << 23) | (static_cast<uint32_t>(keep) & 0x7FFFFFU);
  float v = 0.0F;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}
#endif

}  // namespace

const MessageLayout& layout_of(MsgId id) { return *find_layout(id_of(id)); }

const MessageLayout* find_layout(uint32_t id) {
  for (const MessageLayout& m : kLayouts.messages) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

const SignalLayout& signal_layout(const MessageLayout& m, uint8_t index) {
  return kLayouts.signals[m.first_signal + index - kFirstPayloadSignal];
}

int64_t raw_from_phys(const SignalLayout& s, float phys, bool* flagged) {
  if (!std::isfinite(phys)) {
    switch (s.non_finite) {
      case NonFinite::kRawZeroNa:
        return 0;
      case NonFinite::kMaxFlagged:
        *flagged = true;
        return s.raw_max;
#if UWBNAV_CAN_WIDE
      case NonFinite::kRawMinNa:
        return -(int64_t{1} << (s.bit_len - 1));
#endif
      case NonFinite::kZeroFlagged:
        break;
    }
    *flagged = true;
    return clip(s, s.raw_zero, flagged);
  }
  // phys * inv_factor + raw_zero = +-mantissa * inv_factor * 2^exponent + raw_zero:
  // an integer times a power of two, rounded by an exact shift.
  const FloatParts p = split(phys);
  const auto scaled = static_cast<int64_t>(uint64_t{p.mantissa} * s.inv_factor);  // < 2^40
  const int64_t signed_scaled = p.negative ? -scaled : scaled;
  int64_t raw = s.raw_zero;
  if (p.exponent >= 0) {
    // mantissa >= 2^23 here: beyond 2^20 the value exceeds every raw limit (2^24, wide 2^31).
    if (p.exponent > 20) return clip(s, p.negative ? INT64_MIN / 2 : INT64_MAX / 2, flagged);
    raw = signed_scaled * (int64_t{1} << p.exponent) + s.raw_zero;
  } else if (p.exponent >= -41) {
    // Below 2^-41 the scaled value is < 2^40 * 2^-42 = 1/4 and rounds to raw_zero.
    raw = shift_round(signed_scaled + s.raw_zero * (int64_t{1} << -p.exponent), -p.exponent);
  }
  return clip(s, raw, flagged);
}

int64_t raw_from_angle(const SignalLayout& s, float angle_rad, bool* flagged) {
  if (!std::isfinite(angle_rad) || std::fabs(angle_rad) <= kPiBelowF) return raw_from_phys(s, angle_rad, flagged);
  // |angle| > pi: a normal float m * 2^e with e >= -22. x = |angle| mod 2*pi in
  // 2^-60 rad, by doubling m * 2^-22 (< 4 < 2*pi, exact in Q60) modulo 2*pi.
  const FloatParts p = split(angle_rad);
  uint64_t x = uint64_t{p.mantissa} << 38;
  for (int e = -22; e < p.exponent; ++e) {
    x <<= 1;  // x < 2*pi * 2^60 < 2^63: no overflow
    if (x >= kTwoPiQ60) x -= kTwoPiQ60;
  }
  const bool above_pi = x > kTwoPiQ60 / 2;
  const uint64_t mag = above_pi ? kTwoPiQ60 - x : x;  // |wrapped angle| in Q60, <= pi
  const bool negative = p.negative != above_pi;
  // Round half away of mag * inv_factor / 2^60 without a 128-bit product:
  // floor((hi * 2^32 + lo) / 2^60) = floor((hi + floor(lo / 2^32)) / 2^28).
  const uint64_t lo = (mag & 0xFFFFFFFFU) * s.inv_factor + (uint64_t{1} << 59);
  const auto q = static_cast<int64_t>(((mag >> 32) * s.inv_factor + (lo >> 32)) >> 28);
  return clip(s, negative ? -q : q, flagged);
}

int64_t raw_from_count(const SignalLayout& s, uint64_t count, bool* flagged) {
  const uint64_t max = (uint64_t{1} << s.bit_len) - 1U;  // count signals are <= 53 bits wide
  if (count > max) {
    *flagged = true;
    return static_cast<int64_t>(max);
  }
  return static_cast<int64_t>(count);
}

float phys_from_raw(const SignalLayout& s, int64_t raw) {
  if (s.non_finite == NonFinite::kRawZeroNa && raw == 0) return std::numeric_limits<float>::quiet_NaN();
#if UWBNAV_CAN_WIDE
  if (s.non_finite == NonFinite::kRawMinNa && raw == -(int64_t{1} << (s.bit_len - 1))) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  if (raw - s.raw_zero > kScaledRawLimit || raw - s.raw_zero < -kScaledRawLimit) {
    return quotient_nearest(raw - s.raw_zero, s.inv_factor);  // wide signal
  }
#endif
  // |raw - raw_zero| <= 2^24 for scaled signals: exact in float.
  return static_cast<float>(static_cast<int32_t>(raw - s.raw_zero)) / static_cast<float>(s.inv_factor);
}

int64_t read_raw(const SignalLayout& s, const uint8_t* data) {
  const uint64_t raw = get_bits(data, s.start_bit, s.bit_len);
  if (s.is_signed && s.bit_len < 64 && ((raw >> (s.bit_len - 1)) & 1U) != 0) {
    return static_cast<int64_t>(raw | ~((uint64_t{1} << s.bit_len) - 1U));
  }
  return static_cast<int64_t>(raw);
}

// Byte by byte: each step writes the bits of one payload byte, at most 9 steps
// per signal instead of one per bit (the loop runs for every signal of every
// frame sent, each cycle).
void put_bits(uint8_t* data, uint8_t start_bit, uint8_t bit_len, uint64_t raw) {
  unsigned bit = start_bit;
  unsigned done = 0;
  while (done < bit_len) {
    const unsigned offset = bit % 8U;
    const unsigned left = static_cast<unsigned>(bit_len) - done;
    const unsigned n = (8U - offset < left) ? 8U - offset : left;
    const auto mask = static_cast<uint8_t>(((1U << n) - 1U) << offset);
    const uint64_t source = done < 64U ? raw >> done : 0U;  // bits past 64 are zero
    const auto value = static_cast<uint8_t>(static_cast<unsigned>(source << offset) & mask);
    data[bit / 8U] = static_cast<uint8_t>((data[bit / 8U] & ~mask) | value);
    bit += n;
    done += n;
  }
}

uint64_t unwrap_time_us(uint32_t t32_us, uint64_t ref_us) {
  const auto delta = static_cast<int32_t>(t32_us - static_cast<uint32_t>(ref_us));
  if (delta < 0 && static_cast<uint64_t>(-static_cast<int64_t>(delta)) > ref_us) return t32_us;
  return static_cast<uint64_t>(static_cast<int64_t>(ref_us) + delta);
}

uint64_t get_bits(const uint8_t* data, uint8_t start_bit, uint8_t bit_len) {
  uint64_t raw = 0;
  unsigned bit = start_bit;
  unsigned done = 0;
  while (done < bit_len && done < 64U) {
    const unsigned offset = bit % 8U;
    const unsigned left = static_cast<unsigned>(bit_len) - done;
    const unsigned n = (8U - offset < left) ? 8U - offset : left;
    const unsigned byte_bits = (static_cast<unsigned>(data[bit / 8U]) >> offset) & ((1U << n) - 1U);
    raw |= static_cast<uint64_t>(byte_bits) << done;
    bit += n;
    done += n;
  }
  return raw;
}

namespace {

// Packs the payload signals of one message in table order, then the Saturated
// flag, the alive counter and the CRC.
class Packer {
 public:
  Packer(const MessageLayout& m, hal::CanFrame& out) : m_(m), next_(&kLayouts.signals[m.first_signal]), out_(out) {
    out.id = m.id;
    out.len = m.dlc;
    out.flags = 0;
    std::memset(out.data, 0, sizeof out.data);
  }
  void phys(float v) { put(raw_from_phys(*next_, v, &saturated_)); }
  void angle(float v) { put(raw_from_angle(*next_, v, &saturated_)); }
  void count(uint64_t v) { put(raw_from_count(*next_, v, &saturated_)); }
  bool finish(uint8_t counter) {
    put_bits(out_.data, 15, 1, saturated_ ? 1U : 0U);  // kSigSaturated
    e2e_protect(m_.data_id, counter, out_.data, out_.len);
    return saturated_;
  }

 private:
  void put(int64_t raw) {
    const uint64_t mask = (uint64_t{1} << next_->bit_len) - 1U;
    put_bits(out_.data, next_->start_bit, next_->bit_len, static_cast<uint64_t>(raw) & mask);
    ++next_;
  }

  const MessageLayout& m_;
  const SignalLayout* next_;
  hal::CanFrame& out_;
  bool saturated_ = false;
};

// Checks one received frame (id, length, CRC, counter) and reads its payload
// signals in table order.
class Unpacker {
 public:
  Unpacker(const MessageLayout& m, const hal::CanFrame& f) : m_(m), next_(&kLayouts.signals[m.first_signal]), f_(f) {}

  Status check(FrameMeta* meta) const {
    if (f_.id != m_.id || f_.len != m_.dlc ||
        (f_.flags & (hal::CanFrame::kFlagExtended | hal::CanFrame::kFlagError)) != 0) {
      return Status::kInvalidArgument;
    }
    if (e2e_crc(m_.data_id, f_.data, f_.len) != f_.data[kCrcByte]) return Status::kRejected;
    const uint8_t counter = f_.data[kCounterByte] & kCounterMask;
    if (counter > kAliveCounterMax) return Status::kOutOfRange;
    if (meta != nullptr) {
      meta->counter = counter;
      meta->saturated = (f_.data[kCounterByte] & 0x80U) != 0;  // kSigSaturated, bit 15
    }
    return Status::kOk;
  }
  float phys() {
    const SignalLayout& s = *next_++;
    return phys_from_raw(s, read_raw(s, f_.data));
  }
  uint64_t count() { return static_cast<uint64_t>(read_raw(*next_++, f_.data)); }

 private:

  const MessageLayout& m_;
  const SignalLayout* next_;
  const hal::CanFrame& f_;
};

// Payload kinds per message, in table order: the typed functions below call
// Packer/Unpacker in exactly this order.
static_assert(kinds_are(MsgId::kNavTime, "cc"));
static_assert(kinds_are(MsgId::kPosXY, "cpp"));
static_assert(kinds_are(MsgId::kPosZ, "cppcc"));
static_assert(kinds_are(MsgId::kVelHdg, "ppa"));
static_assert(kinds_are(MsgId::kAccuracy, "pppp"));
static_assert(kinds_are(MsgId::kDiag, "cccc"));
static_assert(kinds_are(MsgId::kAttitude, "pap"));
static_assert(kinds_are(MsgId::kHilImuTime, "c"));
static_assert(kinds_are(MsgId::kHilImuAccel, "ppp"));
static_assert(kinds_are(MsgId::kHilImuGyro, "ppp"));
static_assert(kinds_are(MsgId::kHilUwbRange, "ccp"));
static_assert(kinds_are(MsgId::kHilUwbTime, "cpp"));
#if UWBNAV_COOP
static_assert(kinds_are(MsgId::kCoopTime, "cccc"));
static_assert(kinds_are(MsgId::kCoopPosX, "wp"));
static_assert(kinds_are(MsgId::kCoopPosY, "wp"));
static_assert(kinds_are(MsgId::kCoopPosZ, "pp"));
static_assert(kinds_are(MsgId::kCoopSigma, "ppp"));
static_assert(kinds_are(MsgId::kCoopCorr, "ppp"));

// The two cooperative groups have the identical layout, part by part, and
// their ids are consecutive in part order (coop_id()).
constexpr bool same_layout(MsgId a, MsgId b) {
  const MessageDef& x = kMessages[index_of(a)];
  const MessageDef& y = kMessages[index_of(b)];
  if (x.num_signals != y.num_signals || x.dlc != y.dlc) return false;
  for (uint8_t k = 0; k < x.num_signals; ++k) {
    const SignalDef& p = x.signals[k];
    const SignalDef& q = y.signals[k];
    if (p.start_bit != q.start_bit || p.bit_len != q.bit_len || p.is_signed != q.is_signed || p.factor != q.factor ||
        p.offset != q.offset || p.min != q.min || p.max != q.max || p.non_finite != q.non_finite) {
      return false;
    }
  }
  return true;
}
constexpr MsgId kCoopParts[2][kCoopFrames] = {
    {MsgId::kCoopTime, MsgId::kCoopPosX, MsgId::kCoopPosY, MsgId::kCoopPosZ, MsgId::kCoopSigma, MsgId::kCoopCorr},
    {MsgId::kNeighbourTime, MsgId::kNeighbourPosX, MsgId::kNeighbourPosY, MsgId::kNeighbourPosZ,
     MsgId::kNeighbourSigma, MsgId::kNeighbourCorr}};
constexpr bool coop_groups_consistent() {
  for (size_t k = 0; k < kCoopFrames; ++k) {
    if (!same_layout(kCoopParts[0][k], kCoopParts[1][k])) return false;
    if (id_of(kCoopParts[0][k]) != coop_id(CoopGroup::kOwn, k)) return false;
    if (id_of(kCoopParts[1][k]) != coop_id(CoopGroup::kNeighbour, k)) return false;
  }
  return true;
}
static_assert(coop_groups_consistent(), "UWBNAV_Coop* and V2X_Neighbour* must share one layout");

// Index of each group part in kLayouts.messages.
constexpr size_t kCoopIndex[2][kCoopFrames] = {
    {index_of(MsgId::kCoopTime), index_of(MsgId::kCoopPosX), index_of(MsgId::kCoopPosY), index_of(MsgId::kCoopPosZ),
     index_of(MsgId::kCoopSigma), index_of(MsgId::kCoopCorr)},
    {index_of(MsgId::kNeighbourTime), index_of(MsgId::kNeighbourPosX), index_of(MsgId::kNeighbourPosY),
     index_of(MsgId::kNeighbourPosZ), index_of(MsgId::kNeighbourSigma), index_of(MsgId::kNeighbourCorr)}};

const MessageLayout& coop_layout(CoopGroup g, size_t part) {
  return kLayouts.messages[kCoopIndex[static_cast<size_t>(g)][part]];
}


// Correlation coefficient of a covariance entry, clamped to [-1, 1]; 0 when a
// sigma is 0 or not finite (the sigma itself is then sent flagged), NaN (sent
// flagged) when the entry is not finite.
float correlation(float cov, float sigma_a, float sigma_b) {
  if (!std::isfinite(cov)) return std::numeric_limits<float>::quiet_NaN();
  const float den = sigma_a * sigma_b;
  if (!(den > 0.0F) || !std::isfinite(den)) return 0.0F;
  return std::fmin(std::fmax(cov / den, -1.0F), 1.0F);
}
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
static_assert(kinds_are(MsgId::kGnssFixTime, "ccc"));
static_assert(kinds_are(MsgId::kGnssFixPosX, "wp"));
static_assert(kinds_are(MsgId::kGnssFixPosY, "wp"));
static_assert(kinds_are(MsgId::kGnssFixPosZ, "pp"));
static_assert(kinds_are(MsgId::kGnssFixSigma, "pppp"));
constexpr bool gnss_ids_consecutive() {
  const MsgId parts[kGnssFrames] = {MsgId::kGnssFixTime, MsgId::kGnssFixPosX, MsgId::kGnssFixPosY,
                                    MsgId::kGnssFixPosZ, MsgId::kGnssFixSigma};
  for (size_t k = 0; k < kGnssFrames; ++k) {
    if (id_of(parts[k]) != gnss_id(k)) return false;
  }
  return true;
}
static_assert(gnss_ids_consecutive(), "GNSS_Fix* ids are consecutive in part order (gnss_id())");
constexpr size_t kGnssIndex[kGnssFrames] = {index_of(MsgId::kGnssFixTime), index_of(MsgId::kGnssFixPosX),
                                            index_of(MsgId::kGnssFixPosY), index_of(MsgId::kGnssFixPosZ),
                                            index_of(MsgId::kGnssFixSigma)};
const MessageLayout& gnss_layout(size_t part) { return kLayouts.messages[kGnssIndex[part]]; }
#endif  // UWBNAV_GNSS

#if UWBNAV_CAN_WIDE
float component(const Vec3f& v, size_t axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }
void set_component(Vec3f& v, size_t axis, float value) {
  if (axis == 0) {
    v.x = value;
  } else if (axis == 1) {
    v.y = value;
  } else {
    v.z = value;
  }
}
#endif

static_assert(kNumMessages == 12 + (UWBNAV_COOP ? 12 : 0) + (UWBNAV_GNSS ? 5 : 0),
              "a new message needs its kinds_are() line and typed encode/decode");

NavStatus status_from(uint64_t v) { return static_cast<NavStatus>(v & 0x3U); }

}  // namespace

bool encode(const NavTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kNavTime>(), out);
  p.count(static_cast<uint8_t>(m.mode));
  p.count(m.nav_t_us);
  return p.finish(counter);
}

bool encode(const PosXYMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kPosXY>(), out);
  p.count(static_cast<uint8_t>(m.status));
  p.phys(m.x_nav_m);
  p.phys(m.y_nav_m);
  return p.finish(counter);
}

bool encode(const PosZMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kPosZ>(), out);
  p.count(static_cast<uint8_t>(m.status));
  p.phys(m.z_nav_m);
  p.phys(m.vz_nav_mps);
  p.count(m.ranges_used);
  p.count(m.ranges_rejected);
  return p.finish(counter);
}

bool encode(const VelHdgMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kVelHdg>(), out);
  p.phys(m.vx_nav_mps);
  p.phys(m.vy_nav_mps);
  p.angle(m.heading_rad);
  return p.finish(counter);
}

bool encode(const AccuracyMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kAccuracy>(), out);
  p.phys(m.sigma_x_m);
  p.phys(m.sigma_y_m);
  p.phys(m.sigma_z_m);
  p.phys(m.corr_xy);
  return p.finish(counter);
}

bool encode(const AttitudeMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kAttitude>(), out);
  p.phys(m.heading_sigma_rad);
  p.angle(m.roll_rad);
  p.phys(m.pitch_rad);
  return p.finish(counter);
}

bool encode(const DiagMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kDiag>(), out);
  p.count(m.resets);
  p.count(m.nlos_mask);
  p.count(m.overruns);
  p.count(m.input_rejects);
  return p.finish(counter);
}

bool encode(const HilImuTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kHilImuTime>(), out);
  p.count(m.t_sensor_us);
  return p.finish(counter);
}

bool encode(const HilImuAccelMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kHilImuAccel>(), out);
  p.phys(m.accel_body_mps2.x);
  p.phys(m.accel_body_mps2.y);
  p.phys(m.accel_body_mps2.z);
  return p.finish(counter);
}

bool encode(const HilImuGyroMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kHilImuGyro>(), out);
  p.phys(m.gyro_body_radps.x);
  p.phys(m.gyro_body_radps.y);
  p.phys(m.gyro_body_radps.z);
  return p.finish(counter);
}

bool encode(const HilUwbRangeMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kHilUwbRange>(), out);
  p.count(m.anchor_id);
  p.count(m.tag_id);
  p.phys(m.range_m);
  return p.finish(counter);
}

bool encode(const HilUwbTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  Packer p(layout<MsgId::kHilUwbTime>(), out);
  p.count(m.t_sensor_us);
  p.phys(m.fp_power_dbm);
  p.phys(m.rx_power_dbm);
  return p.finish(counter);
}

Status decode(const hal::CanFrame& f, NavTimeMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kNavTime>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    const uint64_t mode = u.count();
    m.mode = static_cast<NavMode>(mode <= static_cast<uint64_t>(NavMode::kLsFix) ? mode : 0U);
    m.nav_t_us = u.count();
  }
  return s;
}

Status decode(const hal::CanFrame& f, PosXYMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kPosXY>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.status = status_from(u.count());
    m.x_nav_m = u.phys();
    m.y_nav_m = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, PosZMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kPosZ>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.status = status_from(u.count());
    m.z_nav_m = u.phys();
    m.vz_nav_mps = u.phys();
    m.ranges_used = static_cast<uint16_t>(u.count());
    m.ranges_rejected = static_cast<uint16_t>(u.count());
  }
  return s;
}

Status decode(const hal::CanFrame& f, VelHdgMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kVelHdg>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.vx_nav_mps = u.phys();
    m.vy_nav_mps = u.phys();
    m.heading_rad = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, AccuracyMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kAccuracy>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.sigma_x_m = u.phys();
    m.sigma_y_m = u.phys();
    m.sigma_z_m = u.phys();
    m.corr_xy = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, AttitudeMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kAttitude>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.heading_sigma_rad = u.phys();
    m.roll_rad = u.phys();
    m.pitch_rad = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, DiagMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kDiag>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.resets = static_cast<uint32_t>(u.count());
    m.nlos_mask = static_cast<uint16_t>(u.count());
    m.overruns = u.count();
    m.input_rejects = static_cast<uint32_t>(u.count());
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilImuTimeMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kHilImuTime>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) m.t_sensor_us = static_cast<uint32_t>(u.count());
  return s;
}

Status decode(const hal::CanFrame& f, HilImuAccelMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kHilImuAccel>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.accel_body_mps2.x = u.phys();
    m.accel_body_mps2.y = u.phys();
    m.accel_body_mps2.z = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilImuGyroMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kHilImuGyro>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.gyro_body_radps.x = u.phys();
    m.gyro_body_radps.y = u.phys();
    m.gyro_body_radps.z = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilUwbRangeMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kHilUwbRange>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.anchor_id = static_cast<uint16_t>(u.count());
    m.tag_id = static_cast<uint8_t>(u.count());
    m.range_m = u.phys();
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilUwbTimeMsg& m, FrameMeta* meta) {
  Unpacker u(layout<MsgId::kHilUwbTime>(), f);
  const Status s = u.check(meta);
  if (s == Status::kOk) {
    m.t_sensor_us = static_cast<uint32_t>(u.count());
    m.fp_power_dbm = u.phys();
    m.rx_power_dbm = u.phys();
  }
  return s;
}

#if UWBNAV_COOP
bool encode_coop_part(const CoopParts& p, CoopGroup g, size_t part, uint8_t counter, hal::CanFrame& out) {
  if (part >= kCoopFrames) part = kCoopFrames - 1;  // callers pass 0..5
  Packer pk(coop_layout(g, part), out);
  switch (part) {
    case 0:
      pk.count(p.valid ? 1U : 0U);
      pk.count(p.cooperative ? 1U : 0U);
      pk.count(p.vehicle_id);
      pk.count(p.t_sensor_us);
      break;
    case 1:
    case 2:
    case 3:
      pk.phys(component(p.pos_nav_m, part - 1));
      pk.phys(component(p.vel_nav_mps, part - 1));
      break;
    case 4:
      pk.phys(p.sigma_m.x);
      pk.phys(p.sigma_m.y);
      pk.phys(p.sigma_m.z);
      break;
    default:
      pk.phys(p.corr_xy);
      pk.phys(p.corr_xz);
      pk.phys(p.corr_yz);
      break;
  }
  return pk.finish(counter);
}

Status decode_coop_part(const hal::CanFrame& f, CoopGroup g, size_t part, CoopParts& p, FrameMeta* meta) {
  if (part >= kCoopFrames) return Status::kInvalidArgument;
  Unpacker u(coop_layout(g, part), f);
  const Status s = u.check(meta);
  if (s != Status::kOk) return s;
  switch (part) {
    case 0:
      p.valid = u.count() != 0;
      p.cooperative = u.count() != 0;
      p.vehicle_id = static_cast<uint16_t>(u.count());
      p.t_sensor_us = static_cast<uint32_t>(u.count());
      break;
    case 1:
    case 2:
    case 3:
      set_component(p.pos_nav_m, part - 1, u.phys());
      set_component(p.vel_nav_mps, part - 1, u.phys());
      break;
    case 4:
      p.sigma_m.x = u.phys();
      p.sigma_m.y = u.phys();
      p.sigma_m.z = u.phys();
      break;
    default:
      p.corr_xy = u.phys();
      p.corr_xz = u.phys();
      p.corr_yz = u.phys();
      break;
  }
  return Status::kOk;
}

CoopParts coop_parts_from(const NeighbourState& s, bool valid) {
  CoopParts p;
  p.valid = valid;
  p.cooperative = s.cooperative;
  p.vehicle_id = s.vehicle_id;
  p.t_sensor_us = static_cast<uint32_t>(s.t_us);
  p.pos_nav_m = s.pos_nav_m;
  p.vel_nav_mps = s.vel_nav_mps;
  const float* c = s.cov_pos_m2;  // xx, xy, xz, yy, yz, zz
  p.sigma_m = Vec3f{std::sqrt(c[0]), std::sqrt(c[3]), std::sqrt(c[5])};  // negative or NaN: NaN, sent flagged
  p.corr_xy = correlation(c[1], p.sigma_m.x, p.sigma_m.y);
  p.corr_xz = correlation(c[2], p.sigma_m.x, p.sigma_m.z);
  p.corr_yz = correlation(c[4], p.sigma_m.y, p.sigma_m.z);
  return p;
}

NeighbourState neighbour_state_from(const CoopParts& p, uint64_t now_us) {
  NeighbourState s;
  s.t_us = unwrap_time_us(p.t_sensor_us, now_us);
  s.rx_t_us = now_us;
  s.vehicle_id = p.vehicle_id;
  s.pos_nav_m = p.pos_nav_m;
  s.vel_nav_mps = p.vel_nav_mps;
  s.cooperative = p.cooperative;
  const Vec3f& sg = p.sigma_m;
  s.cov_pos_m2[0] = sg.x * sg.x;
  s.cov_pos_m2[1] = p.corr_xy * sg.x * sg.y;
  s.cov_pos_m2[2] = p.corr_xz * sg.x * sg.z;
  s.cov_pos_m2[3] = sg.y * sg.y;
  s.cov_pos_m2[4] = p.corr_yz * sg.y * sg.z;
  s.cov_pos_m2[5] = sg.z * sg.z;
  return s;
}

bool encode_coop(const NeighbourState& s, CoopGroup g, uint8_t counter, hal::CanFrame (&out)[kCoopFrames], bool valid) {
  const CoopParts p = coop_parts_from(s, valid);
  bool saturated = false;
  for (size_t k = 0; k < kCoopFrames; ++k) saturated = encode_coop_part(p, g, k, counter, out[k]) || saturated;
  return saturated;
}

Status decode_coop(const hal::CanFrame (&in)[kCoopFrames], CoopGroup g, uint64_t now_us, NeighbourState& out,
                   CoopMeta* meta) {
  CoopParts p;
  CoopMeta m;
  for (size_t k = 0; k < kCoopFrames; ++k) {
    FrameMeta fm;
    const Status s = decode_coop_part(in[k], g, k, p, &fm);
    if (s != Status::kOk) return s;
    if (k > 0 && fm.counter != m.counter) return Status::kRejected;
    m.counter = fm.counter;
    m.saturated = m.saturated || fm.saturated;
  }
  m.valid = p.valid;
  out = neighbour_state_from(p, now_us);
  if (meta != nullptr) *meta = m;
  return Status::kOk;
}
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
bool encode_gnss_part(const GnssParts& p, size_t part, uint8_t counter, hal::CanFrame& out) {
  if (part >= kGnssFrames) part = kGnssFrames - 1;  // callers pass 0..4
  Packer pk(gnss_layout(part), out);
  switch (part) {
    case 0:
      pk.count(p.fix_type);
      pk.count(p.num_sv);
      pk.count(p.t_sensor_us);
      break;
    case 1:
    case 2:
    case 3:
      pk.phys(component(p.pos_nav_m, part - 1));
      pk.phys(component(p.vel_nav_mps, part - 1));
      break;
    default:
      pk.phys(p.sigma_m.x);
      pk.phys(p.sigma_m.y);
      pk.phys(p.sigma_m.z);
      pk.phys(p.vel_sigma_mps);
      break;
  }
  return pk.finish(counter);
}

Status decode_gnss_part(const hal::CanFrame& f, size_t part, GnssParts& p, FrameMeta* meta) {
  if (part >= kGnssFrames) return Status::kInvalidArgument;
  Unpacker u(gnss_layout(part), f);
  const Status s = u.check(meta);
  if (s != Status::kOk) return s;
  switch (part) {
    case 0:
      p.fix_type = static_cast<uint8_t>(u.count());
      p.num_sv = static_cast<uint8_t>(u.count());
      p.t_sensor_us = static_cast<uint32_t>(u.count());
      break;
    case 1:
    case 2:
    case 3:
      set_component(p.pos_nav_m, part - 1, u.phys());
      set_component(p.vel_nav_mps, part - 1, u.phys());
      break;
    default:
      p.sigma_m.x = u.phys();
      p.sigma_m.y = u.phys();
      p.sigma_m.z = u.phys();
      p.vel_sigma_mps = u.phys();
      break;
  }
  return Status::kOk;
}

GnssParts gnss_parts_from(const GnssFix& fix) {
  GnssParts p;
  p.fix_type = static_cast<uint8_t>(fix.fix);
  p.num_sv = fix.num_sv;
  p.t_sensor_us = static_cast<uint32_t>(fix.t_us);
  p.pos_nav_m = fix.pos_nav_m;
  p.vel_nav_mps = fix.vel_nav_mps;
  p.sigma_m = fix.pos_sigma_m;
  p.vel_sigma_mps = fix.vel_sigma_mps;
  return p;
}

Status gnss_fix_from(const GnssParts& p, uint64_t now_us, GnssFix& out) {
  GnssFixType type = GnssFixType::kNone;
  switch (p.fix_type) {
    case static_cast<uint8_t>(GnssFixType::kSingle):
      type = GnssFixType::kSingle;
      break;
    case static_cast<uint8_t>(GnssFixType::kDgnss):
      type = GnssFixType::kDgnss;
      break;
    case static_cast<uint8_t>(GnssFixType::kRtkFixed):
      type = GnssFixType::kRtkFixed;
      break;
    case static_cast<uint8_t>(GnssFixType::kRtkFloat):
      type = GnssFixType::kRtkFloat;
      break;
    default:
      return Status::kRejected;  // 0 no fix, 3/6/7 not a fix type of GnssFix
  }
  GnssFix f;
  f.t_us = unwrap_time_us(p.t_sensor_us, now_us);
  f.rx_t_us = now_us;
  f.pos_nav_m = p.pos_nav_m;
  f.pos_sigma_m = p.sigma_m;
  f.vel_nav_mps = p.vel_nav_mps;
  f.vel_sigma_mps = p.vel_sigma_mps;
  f.fix = type;
  f.num_sv = p.num_sv;
  out = f;
  return Status::kOk;
}

bool encode_gnss(const GnssFix& fix, uint8_t counter, hal::CanFrame (&out)[kGnssFrames]) {
  const GnssParts p = gnss_parts_from(fix);
  bool saturated = false;
  for (size_t k = 0; k < kGnssFrames; ++k) saturated = encode_gnss_part(p, k, counter, out[k]) || saturated;
  return saturated;
}
#endif  // UWBNAV_GNSS

}  // namespace uwbnav::can
