// HIL sensor input over CAN: the rig-side encoder (ImuSample/UwbRange -> frames)
// and the firmware-side decoder (frames -> samples) with E2E checks, multi-frame
// grouping by alive counter and 32-bit timestamp reconstruction. With
// UWBNAV_COOP the decoder also reassembles neighbour vehicles' states
// (V2X_Neighbour*, relayed by the V2X gateway), with UWBNAV_GNSS receiver
// fixes (GNSS_Fix*, from the GNSS gateway), with the same rules.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"
#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"
#include "hal/hal.hpp"

namespace uwbnav::can {

// unwrap_time_us() (32-bit sensor time -> 64 bits against the receiver clock)
// is declared in firmware/can/messages.hpp.

constexpr size_t kImuFrames = 3;  // HIL_ImuTime, HIL_ImuAccel, HIL_ImuGyro
constexpr size_t kUwbFrames = 2;  // HIL_UwbRange, HIL_UwbTime

// Rig side: turns samples into the HIL frames (same alive counter within a group).
class CanSensorEncoder {
 public:
  // Fills out[0..2] (time, accel, gyro); t_us of each frame = sample time.
  // Returns true when a value was clipped (the frames carry the Saturated flag
  // and the decoder will drop the sample).
  bool encode_imu(const ImuSample& s, hal::CanFrame (&out)[kImuFrames]);
  // Fills out[0..1] (range, time).
  bool encode_uwb(const UwbRange& r, hal::CanFrame (&out)[kUwbFrames]);

 private:
  uint8_t imu_counter_ = 0;
  uint8_t uwb_counter_ = 0;
};

struct CanSensorStats {
  uint32_t frames = 0;          // input frames seen (HIL, V2X_Neighbour, GNSS_Fix; any verdict)
  uint32_t crc_errors = 0;      // wrong CRC: dropped
  uint32_t counter_errors = 0;  // repeated / wrong sequence / counter 15: dropped
  uint32_t length_errors = 0;   // wrong DLC, extended or error frame: dropped
  uint32_t frames_lost = 0;     // frames missing per accepted counter steps > 1
  uint32_t incomplete = 0;      // partial groups discarded (a part never arrived)
  uint32_t saturated = 0;       // complete samples dropped: the sender flagged clipping
  uint32_t imu_samples = 0;     // complete IMU samples delivered
  uint32_t uwb_ranges = 0;      // complete UWB ranges delivered
#if UWBNAV_COOP
  uint32_t neighbour_states = 0;   // complete V2X_Neighbour states delivered
  uint32_t neighbour_invalid = 0;  // complete V2X_Neighbour states dropped: Valid = 0 (sender says do not use)
#endif
#if UWBNAV_GNSS
  uint32_t gnss_fixes = 0;   // complete GNSS_Fix groups delivered
  uint32_t gnss_no_fix = 0;  // complete GNSS_Fix groups dropped: fix type 0 (no fix) or not a known type
#endif
};

enum class SensorKind : uint8_t {
  kNone = 0,
  kImu,
  kUwb,
#if UWBNAV_COOP
  kNeighbour,  // a neighbour vehicle's broadcast state (V2X_Neighbour*)
#endif
#if UWBNAV_GNSS
  kGnss,       // a GNSS receiver fix (GNSS_Fix*)
#endif
};

struct CanSensorSample {
  SensorKind kind = SensorKind::kNone;
  ImuSample imu;   // valid when kind == kImu
  UwbRange uwb;    // valid when kind == kUwb
#if UWBNAV_COOP
  // Valid when kind == kNeighbour: t_us unwrapped from the 32-bit time of
  // validity against the receiver clock, rx_t_us = that clock (now_us) at the
  // group's last frame, covariance rebuilt from the sigmas and correlations.
  NeighbourState neighbour;
#endif
#if UWBNAV_GNSS
  // Valid when kind == kGnss: t_us unwrapped like the neighbour time,
  // rx_t_us = now_us at the group's last frame.
  GnssFix gnss;
#endif
};

// Firmware side. Delivered samples still go through InputValidator like any
// other source (the decoder checks transport integrity, not physics).
class CanSensorDecoder {
 public:
  // Reads can.e2e_max_delta.
  void configure(const Params& params);

#if UWBNAV_COOP || UWBNAV_GNSS
  // HIL_Imu*/HIL_Uwb* frames are decoded only while enabled (default: enabled);
  // disabled they are kNotFound like any foreign frame, while V2X_Neighbour*
  // and GNSS_Fix* frames are still decoded. The App mirrors can.hil_rx_enable here.
  void set_hil_enabled(bool enabled) { hil_enabled_ = enabled; }
  bool hil_enabled() const { return hil_enabled_; }
#endif

  // Feeds one received frame; now_us is the receiver clock used to rebuild the
  // 64-bit sensor time. kOk: `out` holds a complete sample. kEmpty: frame
  // accepted, sample not complete yet. kNotFound: not an input frame (ignored,
  // not counted). kRejected: E2E failure, flagged sample or (neighbour state)
  // Valid = 0, dropped and counted.
  [[nodiscard]] Status on_frame(const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);

  const CanSensorStats& stats() const { return stats_; }
  void reset();
  void reset_stats() { stats_ = CanSensorStats{}; }  // counters only; reception state kept

 private:
  static constexpr size_t kNumHilInputs = kImuFrames + kUwbFrames;
#if UWBNAV_COOP
  static constexpr size_t kNumCoopInputs = kCoopFrames;
#else
  static constexpr size_t kNumCoopInputs = 0;
#endif
#if UWBNAV_GNSS
  static constexpr size_t kNumGnssInputs = kGnssFrames;
#else
  static constexpr size_t kNumGnssInputs = 0;
#endif
  static constexpr size_t kFirstGnssInput = kNumHilInputs + kNumCoopInputs;
  static constexpr size_t kNumInputs = kFirstGnssInput + kNumGnssInputs;
  Status check(size_t input, const MessageLayout& m, const hal::CanFrame& f);
  Status on_imu_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);
  Status on_uwb_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);

  struct ImuGroup {
    uint8_t counter = 0;
    uint8_t have = 0;  // bit per part
    bool saturated = false;
    uint32_t t32_us = 0;
    ImuSample sample;
  };
  struct UwbGroup {
    uint8_t counter = 0;
    uint8_t have = 0;
    bool saturated = false;
    uint32_t t32_us = 0;
    UwbRange range;
  };

#if UWBNAV_COOP
  Status on_neighbour_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);
  struct NeighbourGroup {
    uint8_t counter = 0;
    uint8_t have = 0;  // bit per part (kCoopFrames)
    bool saturated = false;
    CoopParts parts;
  };
  NeighbourGroup neighbour_;
#endif
#if UWBNAV_GNSS
  Status on_gnss_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);
  struct GnssGroup {
    uint8_t counter = 0;
    uint8_t have = 0;  // bit per part (kGnssFrames)
    bool saturated = false;
    GnssParts parts;
  };
  GnssGroup gnss_;
#endif
#if UWBNAV_COOP || UWBNAV_GNSS
  bool hil_enabled_ = true;
#endif

  E2eReceiver rx_[kNumInputs];
  ImuGroup imu_;
  UwbGroup uwb_;
  CanSensorStats stats_;
};

}  // namespace uwbnav::can
