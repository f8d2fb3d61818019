// The uwbnav CAN message set: ids, the one documented table of messages and
// signals (names, units, comments, physical scaling in double) that
// docs/uwbnav.dbc is generated from, and the DBC-side lookup. The firmware never
// reads this table at run time: firmware/can/messages.cpp derives its compact
// run-time layout from it at compile time, so the strings and doubles are only
// emitted where the host (DBC generator, tests, tools) odr-uses them.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/params.hpp"  // UWBNAV_COOP, UWBNAV_GNSS

// Wide (32-bit position) signals and "not reported" codes: used by the
// cooperative groups and the GNSS fix group, compiled when either is.
#define UWBNAV_CAN_WIDE (UWBNAV_COOP || UWBNAV_GNSS)

namespace uwbnav::can {

// 11-bit identifiers (docs/can.md). Outputs 0x100..0x106, HIL inputs 0x0A0..0x0B1;
// with cooperative positioning (UWBNAV_COOP) this vehicle's state 0x110..0x115
// and neighbour states from the V2X gateway 0x0C0..0x0C5; with GNSS fusion
// (UWBNAV_GNSS) receiver fixes from the GNSS gateway 0x0D0..0x0D4.
enum class MsgId : uint16_t {
  kNavTime = 0x100,      // output: time of the solution the 10 ms group belongs to
  kPosXY = 0x101,        // output: horizontal position + status
  kPosZ = 0x102,         // output: vertical position/velocity + status + range counts
  kVelHdg = 0x103,       // output: horizontal velocity + heading
  kAccuracy = 0x104,     // output: 1-sigma x/y/z + xy correlation
  kDiag = 0x105,         // output: NLOS mask, overruns, input rejects, resets
  kAttitude = 0x106,     // output: heading 1-sigma, roll, pitch
  kHilImuTime = 0x0A0,   // HIL input: IMU sample timestamp
  kHilImuAccel = 0x0A1,  // HIL input: IMU specific force
  kHilImuGyro = 0x0A2,   // HIL input: IMU angular rate
  kHilUwbRange = 0x0B0,  // HIL input: UWB range, anchor, tag
  kHilUwbTime = 0x0B1,   // HIL input: UWB range timestamp + channel powers
#if UWBNAV_COOP
  // Cooperative positioning (issue 16 item 1): one vehicle state in six frames
  // with the same alive counter; the two groups have the identical layout.
  kCoopTime = 0x110,       // output: this vehicle's state, part 1 (id, time of validity, flags)
  kCoopPosX = 0x111,       // output: part 2 (tag x, vx)
  kCoopPosY = 0x112,       // output: part 3 (tag y, vy)
  kCoopPosZ = 0x113,       // output: part 4 (tag z, vz)
  kCoopSigma = 0x114,      // output: part 5 (position 1-sigmas)
  kCoopCorr = 0x115,       // output: part 6 (position correlations)
  kNeighbourTime = 0x0C0,  // input from the V2X gateway: another vehicle's state, part 1
  kNeighbourPosX = 0x0C1,  // input: part 2
  kNeighbourPosY = 0x0C2,  // input: part 3
  kNeighbourPosZ = 0x0C3,  // input: part 4
  kNeighbourSigma = 0x0C4, // input: part 5
  kNeighbourCorr = 0x0C5,  // input: part 6
#endif
#if UWBNAV_GNSS
  // GNSS fusion (issue 16 item 2): one receiver fix in five frames with the same alive counter.
  kGnssFixTime = 0x0D0,   // input from the GNSS gateway: fix type, satellites, time of validity
  kGnssFixPosX = 0x0D1,   // input: antenna x, vx
  kGnssFixPosY = 0x0D2,   // input: antenna y, vy
  kGnssFixPosZ = 0x0D3,   // input: antenna z, vz
  kGnssFixSigma = 0x0D4,  // input: position and velocity 1-sigmas
#endif
};

constexpr uint32_t id_of(MsgId m) { return static_cast<uint32_t>(m); }

// What a signal encodes when its physical value is NaN/Inf.
enum class NonFinite : uint8_t {
  kZeroFlagged = 0,  // raw for physical 0 (clipped into range), Saturated flag set
  kMaxFlagged,       // raw maximum (e.g. an unknown sigma is "worst"), Saturated flag set
  kRawZeroNa,        // raw 0 is the "not available" code; no flag; decodes to NaN
#if UWBNAV_CAN_WIDE
  kRawMinNa,         // the field minimum (e.g. int16 0x8000) is the "not reported" code; no flag; decodes to
                     // NaN. The signal's min lies above it, so clipping never produces the code.
#endif
};

struct ValueName {
  int value;
  const char* name;
};

// Round half away from zero (std::llround) in a constant expression: v minus
// its truncation is exact in double for |v| < 2^52.
constexpr int64_t round_half_away(double v) {
  const auto t = static_cast<int64_t>(v);
  const double frac = v - static_cast<double>(t);
  return frac >= 0.5 ? t + 1 : (frac <= -0.5 ? t - 1 : t);
}

// One signal, Intel (little-endian) byte order: start_bit is the LSB position,
// bit index = byte * 8 + bit-in-byte. physical = raw * factor + offset; raw =
// round half away from zero of (physical - offset) / factor, clipped to the raw
// values of min and max (docs/can.md). The run-time codec works from the
// SignalLayout derived from this entry (firmware/can/messages.hpp).
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
};

struct MessageDef {
  uint32_t id;
  const char* name;
  uint8_t dlc;           // bytes
  uint16_t data_id;      // E2E data ID (DBC attribute E2EDataID)
  uint16_t cycle_ms;     // nominal cycle (DBC GenMsgCycleTime), 0 = event driven
  const char* transmitter;  // DBC node sending it (BO_)
  const char* receivers;    // DBC nodes receiving its signals (SG_), comma separated
  const char* comment;
  const SignalDef* signals;
  uint8_t num_signals;
};

// Every message starts with the same three header signals at these indices.
constexpr uint8_t kSigCrc = 0;        // bits 0..7
constexpr uint8_t kSigCounter = 1;    // bits 8..11
constexpr uint8_t kSigSaturated = 2;  // bit 15
constexpr uint8_t kFirstPayloadSignal = 3;  // first signal after the header
constexpr uint8_t kMaxSignals = 8;

// DBC nodes (BU_).
inline constexpr const char* kNodeUwbnav = "UWBNAV";
inline constexpr const char* kNodeHilRig = "HIL_RIG";
inline constexpr const char* kNodeV2xGw = "V2X_GW";
inline constexpr const char* kNodeGnssGw = "GNSS_GW";
inline constexpr const char* kOutputReceivers = "VEHICLE,HIL_RIG";

// ---- The table (single source of truth; docs/can.md, docs/uwbnav.dbc) ---------

namespace table {

inline constexpr ValueName kStatusValues[] = {
    {0, "initialising"}, {1, "valid"}, {2, "degraded"}, {3, "invalid"}};

// NavMode (estimator/types.hpp): where the solution of the group comes from.
inline constexpr ValueName kModeValues[] = {{0, "none"},       {1, "inertial"},   {2, "uwb_only"},
                                            {3, "aligning"},   {4, "recovering"}, {5, "ls_fix"}};

inline constexpr ValueName kPowerValues[] = {{0, "not_available"}};

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

inline constexpr SignalDef kNavTimeSignals[] = {
    UWBNAV_CAN_HEADER("NavTime"),
    {"NavTime_Mode", 12, 3, false, 1.0, 0.0, 0.0, 7.0, "",
     "source of the solution of this 10 ms group: 0 none (no estimate: position not published), 1 inertial, "
     "2 uwb_only, 3 aligning, 4 recovering (ranges-only while the IMU filter re-acquires its heading), 5 ls_fix",
     NonFinite::kZeroFlagged, kModeValues, 6},
    {"NavTime_Us", 16, 48, false, 1.0, 0.0, 0.0, 281474976710655.0, "us",
     "estimator time of the solution carried by the frames of this 10 ms group (same alive counter)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kPosXYSignals[] = {
    UWBNAV_CAN_HEADER("PosXY"),
    {"PosXY_Status", 12, 2, false, 1.0, 0.0, 0.0, 3.0, "", "navigation solution status",
     NonFinite::kZeroFlagged, kStatusValues, 4},
    {"PosX", 16, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "body origin x in the anchor (navigation) frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"PosY", 40, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "body origin y in the anchor (navigation) frame",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kPosZSignals[] = {
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

inline constexpr SignalDef kVelHdgSignals[] = {
    UWBNAV_CAN_HEADER("VelHdg"),
    {"VelX", 16, 16, true, 0.01, 0.0, -327.68, 327.67, "m/s", "body origin velocity x, navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"VelY", 32, 16, true, 0.01, 0.0, -327.68, 327.67, "m/s", "body origin velocity y, navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Heading", 48, 16, true, 0.0001, 0.0, -3.1416, 3.1416, "rad",
     "yaw of the body x axis from the navigation x axis, counter-clockwise positive",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kAccuracySignals[] = {
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

inline constexpr SignalDef kDiagSignals[] = {
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

inline constexpr SignalDef kAttitudeSignals[] = {
    UWBNAV_CAN_HEADER("Attitude"),
    {"HeadingSigma", 16, 12, false, 0.001, 0.0, 0.0, 4.095, "rad",
     "claimed 1-sigma of VelHdg Heading; maximum (with Saturated) while the heading is not an estimate",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"Roll", 28, 16, true, 0.0001, 0.0, -3.1416, 3.1416, "rad", "roll of the body frame (FLU) from the navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Pitch", 44, 16, true, 0.0001, 0.0, -1.5708, 1.5708, "rad",
     "pitch of the body frame (FLU) from the navigation frame, nose down positive about body y",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kHilImuTimeSignals[] = {
    UWBNAV_CAN_HEADER("ImuTime"),
    {"ImuTime_Us", 16, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",
     "sensor timestamp of the IMU sample, low 32 bits of the receiver time base (wraps every 71.6 min)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kHilImuAccelSignals[] = {
    UWBNAV_CAN_HEADER("ImuAccel"),
    {"AccelX", 16, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force x, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"AccelY", 32, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force y, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"AccelZ", 48, 16, true, 0.005, 0.0, -163.84, 163.835, "m/s^2", "specific force z, body frame FLU (+9.81 level at rest)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kHilImuGyroSignals[] = {
    UWBNAV_CAN_HEADER("ImuGyro"),
    {"GyroX", 16, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate x, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"GyroY", 32, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate y, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"GyroZ", 48, 16, true, 0.001, 0.0, -32.768, 32.767, "rad/s", "angular rate z, body frame FLU",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kHilUwbRangeSignals[] = {
    UWBNAV_CAN_HEADER("UwbRange"),
    {"AnchorId", 16, 16, false, 1.0, 0.0, 0.0, 65535.0, "", "anchor id as surveyed (anchors.csv)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"TagId", 32, 8, false, 1.0, 0.0, 0.0, 255.0, "", "tag id on the vehicle (tags.csv)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Range", 40, 24, true, 0.001, 0.0, -8388.608, 8388.607, "m", "two-way range, antenna to antenna (radios may report small negative values)",
     NonFinite::kZeroFlagged, nullptr, 0},
};

inline constexpr SignalDef kHilUwbTimeSignals[] = {
    UWBNAV_CAN_HEADER("UwbTime"),
    {"UwbTime_Us", 16, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",
     "sensor timestamp of the range, low 32 bits of the receiver time base (wraps every 71.6 min)",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"FpPower", 48, 8, false, 0.5, -128.0, -127.5, -0.5, "dBm", "first-path power, raw 0 = not available",
     NonFinite::kRawZeroNa, kPowerValues, 1},
    {"RxPower", 56, 8, false, 0.5, -128.0, -127.5, -0.5, "dBm", "total received power, raw 0 = not available",
     NonFinite::kRawZeroNa, kPowerValues, 1},
};

#if UWBNAV_COOP
// Cooperative positioning (docs/can.md "Cooperative positioning"): one vehicle
// state in six frames, the same layout for this vehicle's output (UWBNAV_Coop*,
// signals Coop_*) and the neighbour states the V2X gateway relays
// (V2X_Neighbour*, signals Neighbour_*). M: header prefix, S: signal prefix.
inline constexpr ValueName kCoopValidValues[] = {{0, "not_valid"}, {1, "valid"}};
inline constexpr ValueName kNotReportedValues[] = {{-32768, "not_reported"}};

#define UWBNAV_COOP_TIME_SIGNALS(M, S)                                                                   \
  UWBNAV_CAN_HEADER(M "Time"),                                                                         \
  {S "_Valid", 12, 1, false, 1.0, 0.0, 0.0, 1.0, "",                                                   \
   "1 = the sender's solution is usable (status valid or degraded); 0 = do not use (a gateway may withdraw a vehicle): the receiver drops the state", \
   NonFinite::kZeroFlagged, kCoopValidValues, 2},                                                      \
  {S "_Cooperative", 13, 1, false, 1.0, 0.0, 0.0, 1.0, "",                                             \
   "1 = the sender's own estimate used ranges to other vehicles recently (coop.dependent_hold): it is not independent of them", \
   NonFinite::kZeroFlagged, nullptr, 0},                                                               \
  {S "_VehicleId", 16, 16, false, 1.0, 0.0, 0.0, 65535.0, "",                                          \
   "sending vehicle: 32768 + its coop.vehicle_id (32769..65534); its tag answers ranges with this id",  \
   NonFinite::kZeroFlagged, nullptr, 0},                                                               \
  {S "_TimeUs", 32, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",                                      \
   "time of validity of the state, low 32 bits of the common us time base (wraps every 71.6 min)",       \
   NonFinite::kZeroFlagged, nullptr, 0}

#define UWBNAV_COOP_AXIS_SIGNALS(M, S, AXIS, WHAT)                                                       \
  UWBNAV_CAN_HEADER(M "Pos" AXIS),                                                                     \
  {S "_Pos" AXIS, 16, 32, true, 0.001, 0.0, -2147483.648, 2147483.647, "m",                            \
   "tag antenna " WHAT " in the navigation frame", NonFinite::kZeroFlagged, nullptr, 0},                \
  {S "_Vel" AXIS, 48, 16, true, 0.01, 0.0, -327.67, 327.67, "m/s",                                     \
   "tag velocity " WHAT ", navigation frame; raw -32768 = not reported", NonFinite::kRawMinNa,          \
   kNotReportedValues, 1}

#define UWBNAV_COOP_Z_SIGNALS(M, S)                                                                      \
  UWBNAV_CAN_HEADER(M "PosZ"),                                                                         \
  {S "_PosZ", 16, 25, true, 0.001, 0.0, -16777.216, 16777.215, "m",                                    \
   "tag antenna z (up) in the navigation frame", NonFinite::kZeroFlagged, nullptr, 0},                  \
  {S "_VelZ", 48, 16, true, 0.01, 0.0, -327.67, 327.67, "m/s",                                         \
   "tag velocity z (up), navigation frame; raw -32768 = not reported", NonFinite::kRawMinNa,            \
   kNotReportedValues, 1}

#define UWBNAV_COOP_SIGMA_SIGNALS(M, S)                                                                  \
  UWBNAV_CAN_HEADER(M "Sigma"),                                                                        \
  {S "_SigmaX", 16, 16, false, 0.001, 0.0, 0.0, 65.535, "m", "claimed 1-sigma of the tag x (unknown: maximum)", \
   NonFinite::kMaxFlagged, nullptr, 0},                                                                \
  {S "_SigmaY", 32, 16, false, 0.001, 0.0, 0.0, 65.535, "m", "claimed 1-sigma of the tag y (unknown: maximum)", \
   NonFinite::kMaxFlagged, nullptr, 0},                                                                \
  {S "_SigmaZ", 48, 16, false, 0.001, 0.0, 0.0, 65.535, "m", "claimed 1-sigma of the tag z (unknown: maximum)", \
   NonFinite::kMaxFlagged, nullptr, 0}

#define UWBNAV_COOP_CORR_SIGNALS(M, S)                                                                   \
  UWBNAV_CAN_HEADER(M "Corr"),                                                                         \
  {S "_CorrXY", 16, 8, true, 1.0 / 127.0, 0.0, -1.0, 1.0, "", "correlation coefficient of the x and y position errors", \
   NonFinite::kZeroFlagged, nullptr, 0},                                                               \
  {S "_CorrXZ", 24, 8, true, 1.0 / 127.0, 0.0, -1.0, 1.0, "", "correlation coefficient of the x and z position errors", \
   NonFinite::kZeroFlagged, nullptr, 0},                                                               \
  {S "_CorrYZ", 32, 8, true, 1.0 / 127.0, 0.0, -1.0, 1.0, "", "correlation coefficient of the y and z position errors", \
   NonFinite::kZeroFlagged, nullptr, 0}

inline constexpr SignalDef kCoopTimeSignals[] = {UWBNAV_COOP_TIME_SIGNALS("Coop", "Coop")};
inline constexpr SignalDef kCoopPosXSignals[] = {UWBNAV_COOP_AXIS_SIGNALS("Coop", "Coop", "X", "x")};
inline constexpr SignalDef kCoopPosYSignals[] = {UWBNAV_COOP_AXIS_SIGNALS("Coop", "Coop", "Y", "y")};
inline constexpr SignalDef kCoopPosZSignals[] = {UWBNAV_COOP_Z_SIGNALS("Coop", "Coop")};
inline constexpr SignalDef kCoopSigmaSignals[] = {UWBNAV_COOP_SIGMA_SIGNALS("Coop", "Coop")};
inline constexpr SignalDef kCoopCorrSignals[] = {UWBNAV_COOP_CORR_SIGNALS("Coop", "Coop")};
inline constexpr SignalDef kNeighbourTimeSignals[] = {UWBNAV_COOP_TIME_SIGNALS("Neighbour", "Neighbour")};
inline constexpr SignalDef kNeighbourPosXSignals[] = {UWBNAV_COOP_AXIS_SIGNALS("Neighbour", "Neighbour", "X", "x")};
inline constexpr SignalDef kNeighbourPosYSignals[] = {UWBNAV_COOP_AXIS_SIGNALS("Neighbour", "Neighbour", "Y", "y")};
inline constexpr SignalDef kNeighbourPosZSignals[] = {UWBNAV_COOP_Z_SIGNALS("Neighbour", "Neighbour")};
inline constexpr SignalDef kNeighbourSigmaSignals[] = {UWBNAV_COOP_SIGMA_SIGNALS("Neighbour", "Neighbour")};
inline constexpr SignalDef kNeighbourCorrSignals[] = {UWBNAV_COOP_CORR_SIGNALS("Neighbour", "Neighbour")};

#undef UWBNAV_COOP_TIME_SIGNALS
#undef UWBNAV_COOP_AXIS_SIGNALS
#undef UWBNAV_COOP_Z_SIGNALS
#undef UWBNAV_COOP_SIGMA_SIGNALS
#undef UWBNAV_COOP_CORR_SIGNALS
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
// GNSS fixes (docs/can.md "GNSS fixes"): the receiver's (or its gateway's)
// solution already in the navigation frame, as in gnss.csv
// (docs/dataset-format.md). Five frames, the same alive counter.
inline constexpr ValueName kGnssFixTypeValues[] = {{0, "no_fix"}, {1, "single"}, {2, "dgnss"}, {4, "rtk_fixed"},
                                                    {5, "rtk_float"}};
inline constexpr ValueName kGnssNotReportedValues[] = {{-32768, "not_reported"}};
inline constexpr ValueName kGnssVelSigmaValues[] = {{0, "not_reported"}};
inline constexpr SignalDef kGnssFixTimeSignals[] = {
    UWBNAV_CAN_HEADER("GnssFixTime"),
    {"Gnss_FixType", 12, 3, false, 1.0, 0.0, 0.0, 7.0, "",
     "fix type, NMEA GGA quality codes: 0 no fix (the receiver drops the fix), 1 single, 2 DGNSS, 4 RTK fixed, "
     "5 RTK float; 3, 6 and 7 are refused",
     NonFinite::kZeroFlagged, kGnssFixTypeValues, 5},
    {"Gnss_NumSv", 16, 8, false, 1.0, 0.0, 0.0, 255.0, "", "satellites used in the fix, 0 = not reported",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Gnss_TimeUs", 32, 32, false, 1.0, 0.0, 0.0, 4294967295.0, "us",
     "time of validity of the fix, low 32 bits of the common us time base (wraps every 71.6 min)",
     NonFinite::kZeroFlagged, nullptr, 0},
};
inline constexpr SignalDef kGnssFixPosXSignals[] = {
    UWBNAV_CAN_HEADER("GnssFixPosX"),
    {"Gnss_PosX", 16, 32, true, 0.001, 0.0, -2147483.648, 2147483.647, "m", "antenna x in the navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Gnss_VelX", 48, 16, true, 0.01, 0.0, -327.67, 327.67, "m/s",
     "antenna velocity x, navigation frame; raw -32768 = not reported", NonFinite::kRawMinNa, kGnssNotReportedValues, 1},
};
inline constexpr SignalDef kGnssFixPosYSignals[] = {
    UWBNAV_CAN_HEADER("GnssFixPosY"),
    {"Gnss_PosY", 16, 32, true, 0.001, 0.0, -2147483.648, 2147483.647, "m", "antenna y in the navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Gnss_VelY", 48, 16, true, 0.01, 0.0, -327.67, 327.67, "m/s",
     "antenna velocity y, navigation frame; raw -32768 = not reported", NonFinite::kRawMinNa, kGnssNotReportedValues, 1},
};
inline constexpr SignalDef kGnssFixPosZSignals[] = {
    UWBNAV_CAN_HEADER("GnssFixPosZ"),
    {"Gnss_PosZ", 16, 25, true, 0.001, 0.0, -16777.216, 16777.215, "m", "antenna z (up) in the navigation frame",
     NonFinite::kZeroFlagged, nullptr, 0},
    {"Gnss_VelZ", 48, 16, true, 0.01, 0.0, -327.67, 327.67, "m/s",
     "antenna velocity z (up), navigation frame; raw -32768 = not reported", NonFinite::kRawMinNa,
     kGnssNotReportedValues, 1},
};
inline constexpr SignalDef kGnssFixSigmaSignals[] = {
    UWBNAV_CAN_HEADER("GnssFixSigma"),
    {"Gnss_SigmaX", 16, 12, false, 0.005, 0.0, 0.0, 20.475, "m",
     "receiver's claimed 1-sigma of x (larger or unknown: maximum, flagged, and the fix is dropped)",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"Gnss_SigmaY", 28, 12, false, 0.005, 0.0, 0.0, 20.475, "m", "receiver's claimed 1-sigma of y",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"Gnss_SigmaZ", 40, 12, false, 0.005, 0.0, 0.0, 20.475, "m", "receiver's claimed 1-sigma of z",
     NonFinite::kMaxFlagged, nullptr, 0},
    {"Gnss_VelSigma", 52, 12, false, 0.005, 0.0, 0.005, 20.475, "m/s",
     "receiver's claimed 1-sigma per velocity axis; raw 0 = not reported", NonFinite::kRawZeroNa,
     kGnssVelSigmaValues, 1},
};
#endif  // UWBNAV_GNSS
#undef UWBNAV_CAN_HEADER

template <size_t N>
constexpr uint8_t count_of(const SignalDef (&)[N]) {
  static_assert(N <= kMaxSignals, "raise kMaxSignals");
  return static_cast<uint8_t>(N);
}

// Data IDs: 0x1000 | CAN id (unique per message, fixed for the life of the layout).
constexpr uint16_t data_id_for(MsgId id) { return static_cast<uint16_t>(0x1000U | id_of(id)); }

}  // namespace table

inline constexpr MessageDef kMessages[] = {
    {id_of(MsgId::kNavTime), "UWBNAV_NavTime", 8, table::data_id_for(MsgId::kNavTime), 10, kNodeUwbnav, kOutputReceivers,
     "Opens each 10 ms output group: the estimator time of the solution. PosXY, PosZ, VelHdg sent in the same cycle carry the same alive counter.",
     table::kNavTimeSignals, table::count_of(table::kNavTimeSignals)},
    {id_of(MsgId::kPosXY), "UWBNAV_PosXY", 8, table::data_id_for(MsgId::kPosXY), 10, kNodeUwbnav, kOutputReceivers,
     "Horizontal position of the body origin in the anchor frame, 1 mm, and the solution status.",
     table::kPosXYSignals, table::count_of(table::kPosXYSignals)},
    {id_of(MsgId::kPosZ), "UWBNAV_PosZ", 8, table::data_id_for(MsgId::kPosZ), 10, kNodeUwbnav, kOutputReceivers,
     "Vertical position and velocity, solution status, UWB ranges fused and rejected since the previous output.",
     table::kPosZSignals, table::count_of(table::kPosZSignals)},
    {id_of(MsgId::kVelHdg), "UWBNAV_VelHdg", 8, table::data_id_for(MsgId::kVelHdg), 10, kNodeUwbnav, kOutputReceivers,
     "Horizontal velocity in the navigation frame and heading.", table::kVelHdgSignals, table::count_of(table::kVelHdgSignals)},
    {id_of(MsgId::kAccuracy), "UWBNAV_Accuracy", 8, table::data_id_for(MsgId::kAccuracy), 20, kNodeUwbnav, kOutputReceivers,
     "Claimed 1-sigma position accuracy and x/y correlation (cycle: parameter can.accuracy_period_ms, default 20 ms).",
     table::kAccuracySignals, table::count_of(table::kAccuracySignals)},
    {id_of(MsgId::kDiag), "UWBNAV_Diag", 8, table::data_id_for(MsgId::kDiag), 100, kNodeUwbnav, kOutputReceivers,
     "Diagnostics: per-anchor NLOS decisions, loop overruns, input rejects, filter resets.",
     table::kDiagSignals, table::count_of(table::kDiagSignals)},
    {id_of(MsgId::kAttitude), "UWBNAV_Attitude", 8, table::data_id_for(MsgId::kAttitude), 20, kNodeUwbnav, kOutputReceivers,
     "Heading accuracy and the attitude's roll and pitch (sent with UWBNAV_Accuracy: parameter can.accuracy_period_ms).",
     table::kAttitudeSignals, table::count_of(table::kAttitudeSignals)},
    {id_of(MsgId::kHilImuTime), "HIL_ImuTime", 8, table::data_id_for(MsgId::kHilImuTime), 10, kNodeHilRig, kNodeUwbnav,
     "HIL input, IMU sample part 1 of 3 (time). The three parts of one sample carry the same alive counter.",
     table::kHilImuTimeSignals, table::count_of(table::kHilImuTimeSignals)},
    {id_of(MsgId::kHilImuAccel), "HIL_ImuAccel", 8, table::data_id_for(MsgId::kHilImuAccel), 10, kNodeHilRig, kNodeUwbnav,
     "HIL input, IMU sample part 2 of 3 (specific force).", table::kHilImuAccelSignals, table::count_of(table::kHilImuAccelSignals)},
    {id_of(MsgId::kHilImuGyro), "HIL_ImuGyro", 8, table::data_id_for(MsgId::kHilImuGyro), 10, kNodeHilRig, kNodeUwbnav,
     "HIL input, IMU sample part 3 of 3 (angular rate).", table::kHilImuGyroSignals, table::count_of(table::kHilImuGyroSignals)},
    {id_of(MsgId::kHilUwbRange), "HIL_UwbRange", 8, table::data_id_for(MsgId::kHilUwbRange), 0, kNodeHilRig, kNodeUwbnav,
     "HIL input, UWB range part 1 of 2 (anchor, tag, range). Both parts carry the same alive counter.",
     table::kHilUwbRangeSignals, table::count_of(table::kHilUwbRangeSignals)},
    {id_of(MsgId::kHilUwbTime), "HIL_UwbTime", 8, table::data_id_for(MsgId::kHilUwbTime), 0, kNodeHilRig, kNodeUwbnav,
     "HIL input, UWB range part 2 of 2 (time, channel powers).", table::kHilUwbTimeSignals, table::count_of(table::kHilUwbTimeSignals)},
#if UWBNAV_COOP
#define UWBNAV_COOP_MESSAGE(ID, NAME, CYCLE, TX, RX, COMMENT, SIGNALS) \
  {id_of(MsgId::ID), NAME, 8, table::data_id_for(MsgId::ID), CYCLE, TX, RX, COMMENT, table::SIGNALS, table::count_of(table::SIGNALS)}
    UWBNAV_COOP_MESSAGE(kCoopTime, "UWBNAV_CoopTime", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning: this vehicle's tag state for the V2X gateway, part 1 of 6 (flags, vehicle id, "
                        "time of validity). The six parts of one state are sent in order in one cycle with the same alive counter, "
                        "every can.coop_period_ms (default 100 ms) while coop.vehicle_id > 0 and the status is valid or degraded.",
                        kCoopTimeSignals),
    UWBNAV_COOP_MESSAGE(kCoopPosX, "UWBNAV_CoopPosX", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning, this vehicle's state part 2 of 6: tag x and vx.", kCoopPosXSignals),
    UWBNAV_COOP_MESSAGE(kCoopPosY, "UWBNAV_CoopPosY", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning, this vehicle's state part 3 of 6: tag y and vy.", kCoopPosYSignals),
    UWBNAV_COOP_MESSAGE(kCoopPosZ, "UWBNAV_CoopPosZ", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning, this vehicle's state part 4 of 6: tag z and vz.", kCoopPosZSignals),
    UWBNAV_COOP_MESSAGE(kCoopSigma, "UWBNAV_CoopSigma", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning, this vehicle's state part 5 of 6: position 1-sigmas (covariance diagonal).",
                        kCoopSigmaSignals),
    UWBNAV_COOP_MESSAGE(kCoopCorr, "UWBNAV_CoopCorr", 100, kNodeUwbnav, kNodeV2xGw,
                        "Cooperative positioning, this vehicle's state part 6 of 6: position correlation coefficients.",
                        kCoopCorrSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourTime, "V2X_NeighbourTime", 0, kNodeV2xGw, kNodeUwbnav,
                        "Cooperative positioning: another vehicle's tag state relayed by the V2X gateway, part 1 of 6 (layout of "
                        "UWBNAV_CoopTime). The six parts of one state carry the same alive counter; the gateway sends a whole "
                        "group before the next one. Decoded, validated, then ranges to that vehicle's tag are fused.",
                        kNeighbourTimeSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourPosX, "V2X_NeighbourPosX", 0, kNodeV2xGw, kNodeUwbnav,
                        "Neighbour vehicle state part 2 of 6: tag x and vx.", kNeighbourPosXSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourPosY, "V2X_NeighbourPosY", 0, kNodeV2xGw, kNodeUwbnav,
                        "Neighbour vehicle state part 3 of 6: tag y and vy.", kNeighbourPosYSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourPosZ, "V2X_NeighbourPosZ", 0, kNodeV2xGw, kNodeUwbnav,
                        "Neighbour vehicle state part 4 of 6: tag z and vz.", kNeighbourPosZSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourSigma, "V2X_NeighbourSigma", 0, kNodeV2xGw, kNodeUwbnav,
                        "Neighbour vehicle state part 5 of 6: position 1-sigmas.", kNeighbourSigmaSignals),
    UWBNAV_COOP_MESSAGE(kNeighbourCorr, "V2X_NeighbourCorr", 0, kNodeV2xGw, kNodeUwbnav,
                        "Neighbour vehicle state part 6 of 6: position correlation coefficients.", kNeighbourCorrSignals),
#undef UWBNAV_COOP_MESSAGE
#endif
#if UWBNAV_GNSS
#define UWBNAV_GNSS_MESSAGE(ID, NAME, COMMENT, SIGNALS) \
  {id_of(MsgId::ID), NAME, 8, table::data_id_for(MsgId::ID), 0, kNodeGnssGw, kNodeUwbnav, COMMENT, table::SIGNALS, \
   table::count_of(table::SIGNALS)}
    UWBNAV_GNSS_MESSAGE(kGnssFixTime, "GNSS_FixTime",
                        "GNSS fix from the receiver gateway, part 1 of 5 (fix type, satellites, time of validity), in the "
                        "navigation frame like gnss.csv. The five parts of one fix carry the same alive counter and are sent "
                        "in order, a whole fix before the next. Decoded, validated (gnss.* checks), then fused at its time.",
                        kGnssFixTimeSignals),
    UWBNAV_GNSS_MESSAGE(kGnssFixPosX, "GNSS_FixPosX", "GNSS fix part 2 of 5: antenna x and vx.", kGnssFixPosXSignals),
    UWBNAV_GNSS_MESSAGE(kGnssFixPosY, "GNSS_FixPosY", "GNSS fix part 3 of 5: antenna y and vy.", kGnssFixPosYSignals),
    UWBNAV_GNSS_MESSAGE(kGnssFixPosZ, "GNSS_FixPosZ", "GNSS fix part 4 of 5: antenna z and vz.", kGnssFixPosZSignals),
    UWBNAV_GNSS_MESSAGE(kGnssFixSigma, "GNSS_FixSigma", "GNSS fix part 5 of 5: position and velocity 1-sigmas.",
                        kGnssFixSigmaSignals),
#undef UWBNAV_GNSS_MESSAGE
#endif
};

inline constexpr size_t kNumMessages = sizeof(kMessages) / sizeof(kMessages[0]);

// Entry of kMessages for a CAN id, nullptr when none. Host/DBC side and
// constant expressions only: the firmware looks frames up with find_layout().
constexpr const MessageDef* find_message(uint32_t id) {
  for (const MessageDef& m : kMessages) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

}  // namespace uwbnav::can
