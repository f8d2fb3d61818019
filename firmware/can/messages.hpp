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

// Reconstructs a 64-bit time from its low 32 bits: the value congruent to
// t32_us (mod 2^32) nearest to ref_us (the receiver's clock). Exact while the
// sensor time is within +-35.7 min of ref_us; never negative.
uint64_t unwrap_time_us(uint32_t t32_us, uint64_t ref_us);

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

#if UWBNAV_COOP
// ---- Cooperative positioning (docs/can.md "Cooperative positioning") -------
//
// One vehicle state travels as a group of six frames with the same alive
// counter, in part order: Time, PosX, PosY, PosZ, Sigma, Corr. Two groups have
// this layout: UWBNAV_Coop* (0x110..0x115, this vehicle's state, sent) and
// V2X_Neighbour* (0x0C0..0x0C5, other vehicles' states relayed by the V2X
// gateway, received).
enum class CoopGroup : uint8_t {
  kOwn = 0,        // UWBNAV_Coop*
  kNeighbour = 1,  // V2X_Neighbour*
};

constexpr size_t kCoopFrames = 6;

// CAN id of part `part` (0..5) of a group.
constexpr uint32_t coop_id(CoopGroup g, size_t part) {
  return (g == CoopGroup::kOwn ? id_of(MsgId::kCoopTime) : id_of(MsgId::kNeighbourTime)) + static_cast<uint32_t>(part);
}

// The physical content of one group (what its six frames carry).
struct CoopParts {
  bool valid = false;        // Time: the sender's solution is usable (0: the receiver drops the state)
  bool cooperative = false;  // Time: the sender's estimate used neighbour ranges recently
  uint16_t vehicle_id = kNoVehicleId;  // Time: 0x8000 + the sender's coop.vehicle_id
  uint32_t t_sensor_us = 0;  // Time: low 32 bits of the time of validity [us]
  Vec3f pos_nav_m;           // PosX/PosY/PosZ: tag antenna [m]; x, y 1 mm +-2147 km, z 1 mm +-16777 m
  Vec3f vel_nav_mps{kNaNf, kNaNf, kNaNf};  // PosX/PosY/PosZ: tag velocity [m/s], 0.01, +-327.67; NaN = not reported
  Vec3f sigma_m{kNaNf, kNaNf, kNaNf};      // Sigma: 1-sigma [m], 1 mm, 0..65.535 (NaN: sent as the maximum, flagged)
  float corr_xy = 0.0F;      // Corr: correlation coefficients [-1, 1], 1/127
  float corr_xz = 0.0F;
  float corr_yz = 0.0F;
};

// Encodes part `part` (0..5) of `p` into `out` (id of the group's part, len 8;
// t_us untouched); returns the Saturated flag. decode_coop_part(): as the typed
// decode() (kInvalidArgument also for a part > 5 or another id) and, on kOk,
// fills only the fields of `p` that this part carries.
bool encode_coop_part(const CoopParts& p, CoopGroup g, size_t part, uint8_t counter, hal::CanFrame& out);
[[nodiscard]] Status decode_coop_part(const hal::CanFrame& f, CoopGroup g, size_t part, CoopParts& p,
                                      FrameMeta* meta = nullptr);

// NeighbourState -> group content: sigma = sqrt of the covariance diagonal,
// correlation = cov_ab / (sigma_a sigma_b) clamped to [-1, 1] (0 when a sigma is
// 0, NaN -> sent flagged when the off-diagonal is not finite); time truncated
// to its low 32 bits.
CoopParts coop_parts_from(const NeighbourState& s, bool valid);
// Group content -> NeighbourState: t_us unwrapped from the 32-bit time against
// now_us (unwrap_time_us), rx_t_us = now_us, covariance rebuilt as
// sigma_a * sigma_b * rho_ab (diagonal sigma^2). `valid` is not part of the state.
NeighbourState neighbour_state_from(const CoopParts& p, uint64_t now_us);

// All six frames of one state with the same alive counter (quantised like every
// signal: rounded half away from zero, clipped with the Saturated flag). Returns
// true when any frame carries the Saturated flag (receivers drop such a state).
bool encode_coop(const NeighbourState& s, CoopGroup g, uint8_t counter, hal::CanFrame (&out)[kCoopFrames],
                 bool valid = true);

struct CoopMeta {
  uint8_t counter = 0;     // alive counter shared by the six frames
  bool saturated = false;  // any frame flagged
  bool valid = false;      // the Valid signal
};

// Decodes a complete group (frames in part order). kOk: `out` holds the state
// (even when meta says saturated or not valid: the caller decides);
// kRejected also when the six counters differ; otherwise as decode().
[[nodiscard]] Status decode_coop(const hal::CanFrame (&in)[kCoopFrames], CoopGroup g, uint64_t now_us,
                                 NeighbourState& out, CoopMeta* meta = nullptr);
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
// ---- GNSS fixes (docs/can.md "GNSS fixes") ----------------------------------
//
// One receiver fix (GnssFix, already in the navigation frame) travels as five
// frames with the same alive counter, in part order: Time, PosX, PosY, PosZ,
// Sigma (GNSS_Fix*, 0x0D0..0x0D4, from the GNSS gateway, received).
constexpr size_t kGnssFrames = 5;

// CAN id of part `part` (0..4).
constexpr uint32_t gnss_id(size_t part) { return id_of(MsgId::kGnssFixTime) + static_cast<uint32_t>(part); }

// The physical content of one group (what its five frames carry).
struct GnssParts {
  uint8_t fix_type = 0;      // Time: NMEA GGA quality code 0..7 (GnssFixType values are valid, others refused)
  uint8_t num_sv = 0;        // Time: satellites used, 0 = not reported, saturates at 255
  uint32_t t_sensor_us = 0;  // Time: low 32 bits of the time of validity [us]
  Vec3f pos_nav_m;           // PosX/PosY/PosZ: antenna [m]; x, y 1 mm +-2147 km, z 1 mm +-16777 m
  Vec3f vel_nav_mps{kNaNf, kNaNf, kNaNf};  // PosX/PosY/PosZ: velocity [m/s], 0.01, +-327.67; NaN = not reported
  Vec3f sigma_m{kNaNf, kNaNf, kNaNf};      // Sigma: 1-sigma per axis [m], 5 mm, 0..20.475 (NaN or more: maximum, flagged)
  float vel_sigma_mps = kNaNf;             // Sigma: 1-sigma per velocity axis [m/s], 5 mm/s, NaN = not reported
};

// Encodes part `part` (0..4) of `p` into `out` (id gnss_id(part), len 8; t_us
// untouched); returns the Saturated flag. decode_gnss_part(): as the typed
// decode() (kInvalidArgument also for a part > 4 or another id) and, on kOk,
// fills only the fields of `p` that this part carries.
bool encode_gnss_part(const GnssParts& p, size_t part, uint8_t counter, hal::CanFrame& out);
[[nodiscard]] Status decode_gnss_part(const hal::CanFrame& f, size_t part, GnssParts& p, FrameMeta* meta = nullptr);

// GnssFix -> group content (time truncated to its low 32 bits).
GnssParts gnss_parts_from(const GnssFix& fix);
// Group content -> GnssFix: t_us unwrapped against now_us (unwrap_time_us),
// rx_t_us = now_us. kRejected (out untouched) when the fix type is 0 (no fix)
// or not a GnssFixType value (3, 6, 7).
[[nodiscard]] Status gnss_fix_from(const GnssParts& p, uint64_t now_us, GnssFix& out);

// All five frames of one fix with the same alive counter. Returns true when any
// frame carries the Saturated flag (receivers drop such a fix).
bool encode_gnss(const GnssFix& fix, uint8_t counter, hal::CanFrame (&out)[kGnssFrames]);
#endif  // UWBNAV_GNSS

}  // namespace uwbnav::can
