// The uwbnav CAN codec: a compact run-time layout derived at compile time from
// the message table (firmware/can/message_table.hpp, the source of
// docs/uwbnav.dbc), an Intel-order packer that saturates and flags out-of-range
// values, and typed encode/decode per message. No double at run time: physical
// values are float, raw values integers, and float <-> raw is exact.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "firmware/can/message_table.hpp"
#include "hal/hal.hpp"

namespace uwbnav::can {

// Run-time layout of one payload signal (table index >= kFirstPayloadSignal),
// derived from its SignalDef at compile time; messages.cpp checks with
// static_assert that 1 / factor and offset / factor are integers, so
//   raw = round half away from zero of (physical * inv_factor + raw_zero)
// is exactly the table's round((physical - offset) / factor).
struct SignalLayout {
  // Raw limits round((min|max - offset) / factor) of scaled signals (|raw| <= 2^24).
  // Count signals (factor 1, offset 0, min 0, max = field maximum: checked at
  // compile time) clip to the field maximum instead and store 0 here.
  int32_t raw_min;
  int32_t raw_max;
  uint16_t inv_factor;  // 1 / factor
  int16_t raw_zero;     // raw of physical 0: -offset / factor
  uint8_t start_bit;
  uint8_t bit_len;
  bool is_signed;
  NonFinite non_finite;
};

struct MessageLayout {
  uint16_t id;            // 11-bit CAN id
  uint16_t data_id;       // E2E data ID
  uint8_t dlc;            // bytes
  uint8_t first_signal;   // index of its first payload signal in the layout array
  uint8_t num_payload;    // signals after the E2E header
};

// Layout of a message of the table; nullptr from find_layout() for an unknown id.
const MessageLayout& layout_of(MsgId id);
const MessageLayout* find_layout(uint32_t id);
// Layout of signal `index` of message `m` (index as in MessageDef::signals,
// kFirstPayloadSignal <= index < kFirstPayloadSignal + m.num_payload).
const SignalLayout& signal_layout(const MessageLayout& m, uint8_t index);

// Physical value -> raw integer, clipped to the raw limits. Sets *flagged when
// the value was clipped or not finite (see NonFinite). Exact: no float rounding
// happens between the physical value and its rounded raw value.
int64_t raw_from_phys(const SignalLayout& s, float phys, bool* flagged);
// Angle [rad] -> raw: wrapped to [-pi, pi] first. Values in [-pi, pi] are used
// as they are; others are reduced modulo 2*pi in 2^-60 rad fixed point, then
// rounded exactly (error of the reduction < n * 2^-61 rad after n turns).
int64_t raw_from_angle(const SignalLayout& s, float angle_rad, bool* flagged);
// Count (factor 1, offset 0) -> raw, clipped to the field maximum.
int64_t raw_from_count(const SignalLayout& s, uint64_t count, bool* flagged);
// Raw -> physical: the float nearest to (raw - raw_zero) / inv_factor (one
// correctly rounded division); NaN for raw 0 of a kRawZeroNa signal.
float phys_from_raw(const SignalLayout& s, int64_t raw);
// Raw value of signal `s` in a payload, sign-extended for signed signals.
int64_t read_raw(const SignalLayout& s, const uint8_t* data);

// Writes/reads raw bits (Intel order) into/from an 8..64 byte payload.
void put_bits(uint8_t* data, uint8_t start_bit, uint8_t bit_len, uint64_t raw);
uint64_t get_bits(const uint8_t* data, uint8_t start_bit, uint8_t bit_len);

// ---- Typed messages (physical values, units in the names) -----------------

struct FrameMeta {
  uint8_t counter = 0;     // alive counter 0..14
  bool saturated = false;  // a signal of the frame was clipped / not finite at the sender
};

struct NavTimeMsg {
  uint64_t nav_t_us = 0;  // NavOutput::t_us of this output group [us], 48 bits
  NavMode mode = NavMode::kNone;  // source of the group's solution, 3 bits
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
struct AttitudeMsg {
  float heading_sigma_rad = kNaNf;  // 1-sigma of VelHdg heading [rad], 0.001, 0..4.095; NaN: not an estimate
  float roll_rad = 0.0F;            // [rad], 0.0001, wrapped to [-pi, pi]
  float pitch_rad = 0.0F;           // [rad], 0.0001, +-pi/2
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
bool encode(const AttitudeMsg& m, uint8_t counter, hal::CanFrame& out);
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
[[nodiscard]] Status decode(const hal::CanFrame& f, AttitudeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuTimeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuAccelMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilImuGyroMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilUwbRangeMsg& m, FrameMeta* meta = nullptr);
[[nodiscard]] Status decode(const hal::CanFrame& f, HilUwbTimeMsg& m, FrameMeta* meta = nullptr);

}  // namespace uwbnav::can
