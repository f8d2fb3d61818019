// The uwbnav CAN message set: one constexpr table of messages and signals (the
// source docs/uwbnav.dbc is generated from), a generic Intel-order packer that
// saturates and flags out-of-range values, and typed encode/decode per message.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "hal/hal.hpp"

namespace uwbnav::can {

// 11-bit identifiers (docs/can.md). Outputs 0x100..0x105, HIL inputs 0x0A0..0x0B1.
enum class MsgId : uint16_t {
  kNavTime = 0x100,      // output: time of the solution the 10 ms group belongs to
  kPosXY = 0x101,        // output: horizontal position + status
  kPosZ = 0x102,         // output: vertical position/velocity + status + range counts
  kVelHdg = 0x103,       // output: horizontal velocity + heading
  kAccuracy = 0x104,     // output: 1-sigma x/y/z + xy correlation
  kDiag = 0x105,         // output: NLOS mask, overruns, input rejects, resets
  kHilImuTime = 0x0A0,   // HIL input: IMU sample timestamp
  kHilImuAccel = 0x0A1,  // HIL input: IMU specific force
  kHilImuGyro = 0x0A2,   // HIL input: IMU angular rate
  kHilUwbRange = 0x0B0,  // HIL input: UWB range, anchor, tag
  kHilUwbTime = 0x0B1,   // HIL input: UWB range timestamp + channel powers
};

constexpr uint32_t id_of(MsgId m) { return static_cast<uint32_t>(m); }

// What a signal encodes when its physical value is NaN/Inf.
enum class NonFinite : uint8_t {
  kZeroFlagged = 0,  // raw for physical 0 (clipped into range), Saturated flag set
  kMaxFlagged,       // raw maximum (e.g. an unknown sigma is "worst"), Saturated flag set
  kRawZeroNa,        // raw 0 is the "not available" code; no flag; decodes to NaN
};

struct ValueName {
  int value;
  const char* name;
};

// One signal, Intel (little-endian) byte order: start_bit is the LSB position,
// bit index = byte * 8 + bit-in-byte. physical = raw * factor + offset.
// Round half away from zero (std::llround) in a constant expression: v minus
// its truncation is exact in double for |v| < 2^52.
constexpr int64_t round_half_away(double v) {
  const auto t = static_cast<int64_t>(v);
  const double frac = v - static_cast<double>(t);
  return frac >= 0.5 ? t + 1 : (frac <= -0.5 ? t - 1 : t);
}

struct SignalDef {
  const char* name;
  uint8_t start_bit;
  uint8_t bit_len;
  bool is_signed;
  double factor;
  double offset;
  double min;  // physical limits; encoding clips to them and sets the Saturated flag
  double max;
  const char* unit;
  const char* comment;
  NonFinite non_finite;
  const ValueName* values;  // value table (DBC VAL_), nullptr when none
  uint8_t num_values;
  // Raw limits llround((min|max - offset) / factor), computed with the table
  // at compile time: the encoder would otherwise divide in double (a library
  // call on a single-precision FPU) twice per signal and frame.
  int64_t raw_min = round_half_away((min - offset) / factor);
  int64_t raw_max = round_half_away((max - offset) / factor);
};

struct MessageDef {
  uint32_t id;
  const char* name;
  uint8_t dlc;           // bytes
  uint16_t data_id;      // E2E data ID (DBC attribute E2EDataID)
  uint16_t cycle_ms;     // nominal cycle (DBC GenMsgCycleTime), 0 = event driven
  bool from_uwbnav;      // transmitter: true = UWBNAV node, false = HIL_RIG
  const char* comment;
  const SignalDef* signals;
  uint8_t num_signals;
};

// Every message starts with the same three header signals at these indices.
constexpr uint8_t kSigCrc = 0;        // bits 0..7
constexpr uint8_t kSigCounter = 1;    // bits 8..11
constexpr uint8_t kSigSaturated = 2;  // bit 15
constexpr uint8_t kMaxSignals = 8;

extern const MessageDef kMessages[];
extern const size_t kNumMessages;

const MessageDef* find_message(uint32_t id);

// Clips/quantizes one physical value to the signal's raw integer.
// Sets *flagged when the value was clipped or not finite (see NonFinite).
int64_t to_raw(const SignalDef& s, double phys, bool* flagged);
double to_phys(const SignalDef& s, int64_t raw);

// Writes/reads raw bits (Intel order) into/from an 8..64 byte payload.
void put_bits(uint8_t* data, uint8_t start_bit, uint8_t bit_len, uint64_t raw);
uint64_t get_bits(const uint8_t* data, uint8_t start_bit, uint8_t bit_len);

// Packs phys[i] for every non-header signal i of `m` (phys[0..2] ignored),
// sets the Saturated flag when any value was clipped, then the alive counter
// and the CRC. Returns the Saturated flag.
bool pack_message(const MessageDef& m, const double* phys, uint8_t counter, hal::CanFrame& out);

// Unpacks every signal of `m` (header included) to physical values.
// Does not check the CRC (see E2eReceiver / decode_*).
void unpack_message(const MessageDef& m, const hal::CanFrame& f, double* phys);

// ---- Typed messages (physical values, units in the names) -----------------

struct FrameMeta {
  uint8_t counter = 0;     // alive counter 0..14
  bool saturated = false;  // a signal of the frame was clipped / not finite at the sender
};

struct NavTimeMsg {
  uint64_t nav_t_us = 0;  // NavOutput::t_us of this output group [us], 48 bits
};
struct PosXYMsg {
  NavStatus status = NavStatus::kInitialising;
  float x_nav_m = 0.0F;  // [m], 1 mm
  float y_nav_m = 0.0F;
};
struct PosZMsg {
  NavStatus status = NavStatus::kInitialising;
  float z_nav_m = 0.0F;     // [m], 1 mm, +-32.767 m
  float vz_nav_mps = 0.0F;  // [m/s], 0.01 m/s
  uint16_t ranges_used = 0;      // saturates at 255
  uint16_t ranges_rejected = 0;  // saturates at 255
};
struct VelHdgMsg {
  float vx_nav_mps = 0.0F;  // [m/s], 0.01 m/s, +-327.67
  float vy_nav_mps = 0.0F;
  float heading_rad = 0.0F;  // wrapped to [-pi, pi], 0.0001 rad
};
struct AccuracyMsg {
  float sigma_x_m = 0.0F;  // 1-sigma [m], 5 mm steps, 0..20.475 m
  float sigma_y_m = 0.0F;
  float sigma_z_m = 0.0F;
  float corr_xy = 0.0F;    // correlation coefficient [-1, 1], 0.001
};
struct DiagMsg {
  uint16_t nlos_mask = 0;       // bit i: anchor index i (SiteConfig::anchors[i]) judged NLOS
  uint32_t resets = 0;          // saturates at 7
  uint64_t overruns = 0;        // saturates at 65535
  uint32_t input_rejects = 0;   // saturates at 65535
};
struct HilImuTimeMsg {
  uint32_t t_sensor_us = 0;  // low 32 bits of the sample's t_us (wraps every 71.6 min)
};
struct HilImuAccelMsg {
  Vec3f accel_body_mps2;  // 0.005 m/s^2, +-163.84
};
struct HilImuGyroMsg {
  Vec3f gyro_body_radps;  // 0.001 rad/s, +-32.768
};
struct HilUwbRangeMsg {
  uint16_t anchor_id = 0;
  uint8_t tag_id = 0;
  float range_m = 0.0F;  // 1 mm, +-8388.607 m
};
struct HilUwbTimeMsg {
  uint32_t t_sensor_us = 0;      // low 32 bits of the range's t_us
  float fp_power_dbm = kNaNf;    // 0.5 dB, -127.5..-0.5, NaN = not available
  float rx_power_dbm = kNaNf;
};

// encode(): fills `out` (id, len 8, flags 0, data; t_us untouched) and returns
// the Saturated flag. decode(): kInvalidArgument for another id or length,
// kRejected for a CRC mismatch, kOutOfRange for counter 15; values filled on kOk.
bool encode(const NavTimeMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const PosXYMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const PosZMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const VelHdgMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const AccuracyMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const DiagMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const HilImuTimeMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const HilImuAccelMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const HilImuGyroMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const HilUwbRangeMsg& m, uint8_t counter, hal::CanFrame& out);
bool encode(const HilUwbTimeMsg& m, uint8_t counter, hal::CanFrame& out);

[[nodiscard]] Status decode(const hal::CanFrame& f, NavTimeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, PosXYMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, PosZMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, VelHdgMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, AccuracyMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, DiagMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuTimeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuAccelMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuGyroMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilUwbRangeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilUwbTimeMsg& m, FrameMeta* meta = nullptr);

// Wraps an angle to [-pi, pi] [rad].
double wrap_pi(double angle_rad);

}  // namespace uwbnav::can
