// The uwbnav CAN message table (source of docs/uwbnav.dbc) and its Intel-order
// packer/unpacker with saturation, plus the typed encode/decode functions.
#include "firmware/can/messages.hpp"

#include <cmath>

#include "firmware/can/e2e.hpp"

namespace uwbnav::can {
namespace {

constexpr double kPi = 3.14159265358979323846;

constexpr ValueName kStatusValues[] = {
    {0, "initialising"}, {1, "valid"}, {2, "degraded"}, {3, "invalid"}};

constexpr ValueName kPowerValues[] = {{0, "not_available"}};

// Common E2E header of every frame: CRC (byte 0), alive counter (byte 1 bits
// 0..3), Saturated flag (byte 1 bit 7). Bits 12..14 are message specific.
#define UWBNAV_CAN_HEADER(P)                                                                            \
  {P "_CRC", 0, 8, false, 1.0, 0.0, 0.0, 255.0, "", "CRC-8 SAE J1850 over E2EDataID (low byte, high byte) and bytes 1..7", \
   NonFinite::kZeroFlagged, nullptr, 0},                                                                \
  {P "_AliveCounter", 8, 4, false, 1.0, 0.0, 0.0, 14.0, "", "alive counter 0..14, +1 per transmission, 15 never sent", \
   NonFinite::kZeroFlagged, nullptr, 0},                                                                \
  {P "_Saturated", 15, 1, false, 1.0, 0.0, 0.0, 1.0, "",                                                \
   "1 = a signal of this frame was clipped to its range or was not finite at the sender",               \
   NonFinite::kZeroFlagged, nullptr, 0}

constexpr SignalDef kNavTimeSignals[] = {
    UWBNAV_CAN_HEADER("NavTime"),
    {"NavTime_Us", 16, 48, false, 1.0, 0.0, 0.0, 281474976710655.0, "us",
     "estimator time of the solution carried by the frames of this 10 ms group (same alive counter)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kPosXYSignals[] = {
    UWBNAV_CAN_HEADER("PosXY"),
    {"PosXY_Status", 12, 2, false, 1.0, 0.0, 0.0, 3.0, "", "navigation solution status",
     NonFinite::kZeroFlagged, kStatusValues, 4},
    {"PosX", 16, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "body origin x in the anchor (navigation) frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"PosY", 40, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "body origin y in the anchor (navigation) frame",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kPosZSignals[] = {
    UWBNAV_CAN_HEADER("PosZ"),
    {"PosZ_Status", 12, 2, false, 1.0, 0.0, 0.0, 3.0, "", "navigation solution status",
     NonFinite::kZeroFlagged, kStatusValues, 4},
    {"PosZ", 16, 16, true, 0.001, 0.0, -32.768, 32.767, "m", "body origin z (up) in the anchor frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"VelZ", 32, 16, true, 0.01, 0.0, -327.68, 327.67, "m/s", "body origin velocity z (up), navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"RangesUsed", 48, 8, false, 1.0, 0.0, 0.0, 255.0, "", "UWB ranges fused since the previous output",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"RangesRejected", 56, 8, false, 1.0, 0.0, 0.0, 255.0, "", "UWB ranges rejected since the previous output",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kVelHdgSignals[] = {
    UWBNAV_CAN_HEADER("VelHdg"),
    {"VelX", 16, 16, true, 0.01, 0.0, -327.68, 327.67, "m/s", "body origin velocity x, navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"VelY", 32, 16, true, 0.01, 0.0, -327.68, 327.67, "m/s", "body origin velocity y, navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Heading", 48, 16, true, 0.0001, 0.0, -3.1416, 3.1416, "rad",
     "yaw of the body x axis from the navigation x axis, counter-clockwise positive",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kAccuracySignals[] = {
    UWBNAV_CAN_HEADER("Accuracy"),
    {"SigmaX", 16, 12, false, 0.005, 0.0, 0.0, 20.475, "m", "claimed 1-sigma of PosX (unknown: maximum)",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"SigmaY", 28, 12, false, 0.005, 0.0, 0.0, 20.475, "m", "claimed 1-sigma of PosY (unknown: maximum)",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"SigmaZ", 40, 12, false, 0.005, 0.0, 0.0, 20.475, "m", "claimed 1-sigma of PosZ (unknown: maximum)",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"CorrXY", 52, 12, true, 0.001, 0.0, -1.0, 1.0, "", "correlation coefficient of the x and y position errors",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kDiagSignals[] = {
    UWBNAV_CAN_HEADER("Diag"),
    {"Diag_Resets", 12, 3, false, 1.0, 0.0, 0.0, 7.0, "", "filter resets since start (saturates at 7)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"NlosMask", 16, 16, false, 1.0, 0.0, 0.0, 65535.0, "",
     "bit i = 1: the last range from anchor table index i was judged NLOS",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"LoopOverruns", 32, 16, false, 1.0, 0.0, 0.0, 65535.0, "", "10 ms cycles that overran since start (saturates)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"InputRejects", 48, 16, false, 1.0, 0.0, 0.0, 65535.0, "",
     "sensor frames rejected by input validation since start (saturates)", NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kHilImuTimeSignals[] = {
    UWBNAV_CAN_HEADER("ImuTime"),
    {"ImuTime_Us", 16, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",
     "sensor timestamp of the IMU sample, low 32 bits of the receiver time base (wraps every 71.6 min)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kHilImuAccelSignals[] = {
    UWBNAV_CAN_HEADER("ImuAccel"),
    {"AccelX", 16, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force x, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"AccelY", 32, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force y, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"AccelZ", 48, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force z, body frame FLU (+9.81 level at rest)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kHilImuGyroSignals[] = {
    UWBNAV_CAN_HEADER("ImuGyro"),
    {"GyroX", 16, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate x, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"GyroY", 32, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate y, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"GyroZ", 48, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate z, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kHilUwbRangeSignals[] = {
    UWBNAV_CAN_HEADER("UwbRange"),
    {"AnchorId", 16, 16, false, 1.0, 0.0, 0.0, 65535.0, "", "anchor id as surveyed (anchors.csv)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"TagId", 32, 8, false, 1.0, 0.0, 0.0, 255.0, "", "tag id on the vehicle (tags.csv)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Range", 40, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "two-way range, antenna to antenna (radios may report small negative values)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

constexpr SignalDef kHilUwbTimeSignals[] = {
    UWBNAV_CAN_HEADER("UwbTime"),
    {"UwbTime_Us", 16, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",
     "sensor timestamp of the range, low 32 bits of the receiver time base (wraps every 71.6 min)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"FpPower", 48, 8, false, 0.5, -128.0, -127.5, -0.5, "dBm", "first-path power, raw 0 = not available",
     NonFinite::kRawZeroNa, kPowerValues, 1},
    {"RxPower", 56, 8, false, 0.5, -128.0, -127.5, -0.5, "dBm", "total received power, raw 0 = not available",
     NonFinite::kRawZeroNa, kPowerValues, 1},
};

#undef UWBNAV_CAN_HEADER

template <size_t N>
constexpr uint8_t count_of(const SignalDef (&)[N]) {
  static_assert(N <= kMaxSignals, "raise kMaxSignals");
  return static_cast<uint8_t>(N);
}

// Data IDs: 0x1000 | CAN id (unique per message, fixed for the life of the layout).
constexpr uint16_t data_id_for(MsgId id) { return static_cast<uint16_t>(0x1000U | id_of(id)); }

}  // namespace

const MessageDef kMessages[] = {
    {id_of(MsgId::kNavTime), "UWBNAV_NavTime", 8, data_id_for(MsgId::kNavTime), 10, true,
     "Opens each 10 ms output group: the estimator time of the solution. PosXY, PosZ, VelHdg sent in the same cycle carry the same alive counter.",
     kNavTimeSignals, count_of(kNavTimeSignals)},
    {id_of(MsgId::kPosXY), "UWBNAV_PosXY", 8, data_id_for(MsgId::kPosXY), 10, true,
     "Horizontal position of the body origin in the anchor frame, 1 mm, and the solution status.",
     kPosXYSignals, count_of(kPosXYSignals)},
    {id_of(MsgId::kPosZ), "UWBNAV_PosZ", 8, data_id_for(MsgId::kPosZ), 10, true,
     "Vertical position and velocity, solution status, UWB ranges fused and rejected since the previous output.",
     kPosZSignals, count_of(kPosZSignals)},
    {id_of(MsgId::kVelHdg), "UWBNAV_VelHdg", 8, data_id_for(MsgId::kVelHdg), 10, true,
     "Horizontal velocity in the navigation frame and heading.", kVelHdgSignals, count_of(kVelHdgSignals)},
    {id_of(MsgId::kAccuracy), "UWBNAV_Accuracy", 8, data_id_for(MsgId::kAccuracy), 20, true,
     "Claimed 1-sigma position accuracy and x/y correlation (cycle: parameter can.accuracy_period_ms, default 20 ms).",
     kAccuracySignals, count_of(kAccuracySignals)},
    {id_of(MsgId::kDiag), "UWBNAV_Diag", 8, data_id_for(MsgId::kDiag), 100, true,
     "Diagnostics: per-anchor NLOS decisions, loop overruns, input rejects, filter resets.",
     kDiagSignals, count_of(kDiagSignals)},
    {id_of(MsgId::kHilImuTime), "HIL_ImuTime", 8, data_id_for(MsgId::kHilImuTime), 10, false,
     "HIL input, IMU sample part 1 of 3 (time). The three parts of one sample carry the same alive counter.",
     kHilImuTimeSignals, count_of(kHilImuTimeSignals)},
    {id_of(MsgId::kHilImuAccel), "HIL_ImuAccel", 8, data_id_for(MsgId::kHilImuAccel), 10, false,
     "HIL input, IMU sample part 2 of 3 (specific force).", kHilImuAccelSignals, count_of(kHilImuAccelSignals)},
    {id_of(MsgId::kHilImuGyro), "HIL_ImuGyro", 8, data_id_for(MsgId::kHilImuGyro), 10, false,
     "HIL input, IMU sample part 3 of 3 (angular rate).", kHilImuGyroSignals, count_of(kHilImuGyroSignals)},
    {id_of(MsgId::kHilUwbRange), "HIL_UwbRange", 8, data_id_for(MsgId::kHilUwbRange), 0, false,
     "HIL input, UWB range part 1 of 2 (anchor, tag, range). Both parts carry the same alive counter.",
     kHilUwbRangeSignals, count_of(kHilUwbRangeSignals)},
    {id_of(MsgId::kHilUwbTime), "HIL_UwbTime", 8, data_id_for(MsgId::kHilUwbTime), 0, false,
     "HIL input, UWB range part 2 of 2 (time, channel powers).", kHilUwbTimeSignals, count_of(kHilUwbTimeSignals)},
};

const size_t kNumMessages = sizeof(kMessages) / sizeof(kMessages[0]);

const MessageDef* find_message(uint32_t id) {
  for (size_t i = 0; i < kNumMessages; ++i) {
    if (kMessages[i].id == id) return &kMessages[i];
  }
  return nullptr;
}

int64_t to_raw(const SignalDef& s, double phys, bool* flagged) {
  const int64_t raw_min = s.raw_min;
  const int64_t raw_max = s.raw_max;
  if (!std::isfinite(phys)) {
    switch (s.non_finite) {
      case NonFinite::kRawZeroNa:
        return 0;
      case NonFinite::kMaxFlagged:
        *flagged = true;
        return raw_max;
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

double to_phys(const SignalDef& s, int64_t raw) {
  if (s.non_finite == NonFinite::kRawZeroNa && raw == 0) return std::nan("");
  return static_cast<double>(raw) * s.factor + s.offset;
}

void put_bits(uint8_t* data, uint8_t start_bit, uint8_t bit_len, uint64_t raw) {
  for (uint8_t i = 0; i < bit_len; ++i) {
    const unsigned bit = static_cast<unsigned>(start_bit) + i;
    const auto mask = static_cast<uint8_t>(1U << (bit % 8));
    if (((raw >> i) & 1U) != 0) {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] | mask);
    } else {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] & ~mask);
    }
  }
}

uint64_t get_bits(const uint8_t* data, uint8_t start_bit, uint8_t bit_len) {
  uint64_t raw = 0;
  for (uint8_t i = 0; i < bit_len; ++i) {
    const unsigned bit = static_cast<unsigned>(start_bit) + i;
    if (((data[bit / 8] >> (bit % 8)) & 1U) != 0) raw |= (uint64_t{1} << i);
  }
  return raw;
}

bool pack_message(const MessageDef& m, const double* phys, uint8_t counter, hal::CanFrame& out) {
  out.id = m.id;
  out.len = m.dlc;
  out.flags = 0;
  for (auto& b : out.data) b = 0;
  bool saturated = false;
  for (uint8_t i = kSigSaturated + 1; i < m.num_signals; ++i) {
    const SignalDef& s = m.signals[i];
    const int64_t raw = to_raw(s, phys[i], &saturated);
    const uint64_t mask = s.bit_len >= 64 ? ~uint64_t{0} : ((uint64_t{1} << s.bit_len) - 1U);
    put_bits(out.data, s.start_bit, s.bit_len, static_cast<uint64_t>(raw) & mask);
  }
  put_bits(out.data, m.signals[kSigSaturated].start_bit, 1, saturated ? 1U : 0U);
  e2e_protect(m.data_id, counter, out.data, out.len);
  return saturated;
}

void unpack_message(const MessageDef& m, const hal::CanFrame& f, double* phys) {
  for (uint8_t i = 0; i < m.num_signals; ++i) {
    const SignalDef& s = m.signals[i];
    uint64_t raw = get_bits(f.data, s.start_bit, s.bit_len);
    int64_t value = static_cast<int64_t>(raw);
    if (s.is_signed && s.bit_len < 64 && ((raw >> (s.bit_len - 1)) & 1U) != 0) {
      value = static_cast<int64_t>(raw | ~((uint64_t{1} << s.bit_len) - 1U));
    }
    phys[i] = to_phys(s, value);
  }
}

double wrap_pi(double angle_rad) {
  if (!std::isfinite(angle_rad)) return angle_rad;
  double a = std::fmod(angle_rad + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

namespace {

bool encode_values(MsgId id, const double* phys, uint8_t counter, hal::CanFrame& out) {
  return pack_message(*find_message(id_of(id)), phys, counter, out);
}

Status decode_values(const hal::CanFrame& f, MsgId id, double* phys, FrameMeta* meta) {
  const MessageDef& m = *find_message(id_of(id));
  if (f.id != m.id || f.len != m.dlc || (f.flags & (hal::CanFrame::kFlagExtended | hal::CanFrame::kFlagError)) != 0) {
    return Status::kInvalidArgument;
  }
  if (e2e_crc(m.data_id, f.data, f.len) != f.data[kCrcByte]) return Status::kRejected;
  const uint8_t counter = f.data[kCounterByte] & kCounterMask;
  if (counter > kAliveCounterMax) return Status::kOutOfRange;
  unpack_message(m, f, phys);
  if (meta != nullptr) {
    meta->counter = counter;
    meta->saturated = phys[kSigSaturated] != 0.0;
  }
  return Status::kOk;
}

float f32(double v) { return static_cast<float>(v); }
double f64(float v) { return static_cast<double>(v); }

NavStatus status_from(double v) { return static_cast<NavStatus>(static_cast<uint8_t>(v) & 0x3U); }

}  // namespace

bool encode(const NavTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.nav_t_us)};
  return encode_values(MsgId::kNavTime, v, counter, out);
}

bool encode(const PosXYMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.status), f64(m.x_nav_m), f64(m.y_nav_m)};
  return encode_values(MsgId::kPosXY, v, counter, out);
}

bool encode(const PosZMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.status), f64(m.z_nav_m), f64(m.vz_nav_mps),
                      static_cast<double>(m.ranges_used), static_cast<double>(m.ranges_rejected)};
  return encode_values(MsgId::kPosZ, v, counter, out);
}

bool encode(const VelHdgMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, f64(m.vx_nav_mps), f64(m.vy_nav_mps), wrap_pi(f64(m.heading_rad))};
  return encode_values(MsgId::kVelHdg, v, counter, out);
}

bool encode(const AccuracyMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, f64(m.sigma_x_m), f64(m.sigma_y_m), f64(m.sigma_z_m), f64(m.corr_xy)};
  return encode_values(MsgId::kAccuracy, v, counter, out);
}

bool encode(const DiagMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.resets), static_cast<double>(m.nlos_mask),
                      static_cast<double>(m.overruns), static_cast<double>(m.input_rejects)};
  return encode_values(MsgId::kDiag, v, counter, out);
}

bool encode(const HilImuTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.t_sensor_us)};
  return encode_values(MsgId::kHilImuTime, v, counter, out);
}

bool encode(const HilImuAccelMsg& m, uint8_t counter, hal::CanFrame& out) {
  const Vec3f& a = m.accel_body_mps2;
  const double v[] = {0, 0, 0, f64(a.x), f64(a.y), f64(a.z)};
  return encode_values(MsgId::kHilImuAccel, v, counter, out);
}

bool encode(const HilImuGyroMsg& m, uint8_t counter, hal::CanFrame& out) {
  const Vec3f& g = m.gyro_body_radps;
  const double v[] = {0, 0, 0, f64(g.x), f64(g.y), f64(g.z)};
  return encode_values(MsgId::kHilImuGyro, v, counter, out);
}

bool encode(const HilUwbRangeMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.anchor_id), static_cast<double>(m.tag_id), f64(m.range_m)};
  return encode_values(MsgId::kHilUwbRange, v, counter, out);
}

bool encode(const HilUwbTimeMsg& m, uint8_t counter, hal::CanFrame& out) {
  const double v[] = {0, 0, 0, static_cast<double>(m.t_sensor_us), f64(m.fp_power_dbm), f64(m.rx_power_dbm)};
  return encode_values(MsgId::kHilUwbTime, v, counter, out);
}

Status decode(const hal::CanFrame& f, NavTimeMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kNavTime, v, meta);
  if (s == Status::kOk) m.nav_t_us = static_cast<uint64_t>(v[3]);
  return s;
}

Status decode(const hal::CanFrame& f, PosXYMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kPosXY, v, meta);
  if (s == Status::kOk) {
    m.status = status_from(v[3]);
    m.x_nav_m = f32(v[4]);
    m.y_nav_m = f32(v[5]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, PosZMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kPosZ, v, meta);
  if (s == Status::kOk) {
    m.status = status_from(v[3]);
    m.z_nav_m = f32(v[4]);
    m.vz_nav_mps = f32(v[5]);
    m.ranges_used = static_cast<uint16_t>(v[6]);
    m.ranges_rejected = static_cast<uint16_t>(v[7]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, VelHdgMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kVelHdg, v, meta);
  if (s == Status::kOk) {
    m.vx_nav_mps = f32(v[3]);
    m.vy_nav_mps = f32(v[4]);
    m.heading_rad = f32(v[5]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, AccuracyMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kAccuracy, v, meta);
  if (s == Status::kOk) {
    m.sigma_x_m = f32(v[3]);
    m.sigma_y_m = f32(v[4]);
    m.sigma_z_m = f32(v[5]);
    m.corr_xy = f32(v[6]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, DiagMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kDiag, v, meta);
  if (s == Status::kOk) {
    m.resets = static_cast<uint32_t>(v[3]);
    m.nlos_mask = static_cast<uint16_t>(v[4]);
    m.overruns = static_cast<uint64_t>(v[5]);
    m.input_rejects = static_cast<uint32_t>(v[6]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilImuTimeMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kHilImuTime, v, meta);
  if (s == Status::kOk) m.t_sensor_us = static_cast<uint32_t>(v[3]);
  return s;
}

Status decode(const hal::CanFrame& f, HilImuAccelMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kHilImuAccel, v, meta);
  if (s == Status::kOk) m.accel_body_mps2 = Vec3f{f32(v[3]), f32(v[4]), f32(v[5])};
  return s;
}

Status decode(const hal::CanFrame& f, HilImuGyroMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kHilImuGyro, v, meta);
  if (s == Status::kOk) m.gyro_body_radps = Vec3f{f32(v[3]), f32(v[4]), f32(v[5])};
  return s;
}

Status decode(const hal::CanFrame& f, HilUwbRangeMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kHilUwbRange, v, meta);
  if (s == Status::kOk) {
    m.anchor_id = static_cast<uint16_t>(v[3]);
    m.tag_id = static_cast<uint8_t>(v[4]);
    m.range_m = f32(v[5]);
  }
  return s;
}

Status decode(const hal::CanFrame& f, HilUwbTimeMsg& m, FrameMeta* meta) {
  double v[kMaxSignals] = {};
  const Status s = decode_values(f, MsgId::kHilUwbTime, v, meta);
  if (s == Status::kOk) {
    m.t_sensor_us = static_cast<uint32_t>(v[3]);
    m.fp_power_dbm = f32(v[4]);
    m.rx_power_dbm = f32(v[5]);
  }
  return s;
}

}  // namespace uwbnav::can
