// HIL sensor input over CAN: the rig-side encoder (ImuSample/UwbRange -> frames)
// and the firmware-side decoder (frames -> samples) with E2E checks, multi-frame
// grouping by alive counter and 32-bit timestamp reconstruction.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"
#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"
#include "hal/hal.hpp"

namespace uwbnav::can {

// Reconstructs a 64-bit time from its low 32 bits: the value congruent to
// t32_us (mod 2^32) nearest to ref_us (the receiver's clock). Exact while the
// sensor time is within +-35.7 min of ref_us; never negative.
uint64_t unwrap_time_us(uint32_t t32_us, uint64_t ref_us);

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
  uint32_t frames = 0;          // HIL input frames seen (any verdict)
  uint32_t crc_errors = 0;      // wrong CRC: dropped
  uint32_t counter_errors = 0;  // repeated / wrong sequence / counter 15: dropped
  uint32_t length_errors = 0;   // wrong DLC, extended or error frame: dropped
  uint32_t frames_lost = 0;     // frames missing per accepted counter steps > 1
  uint32_t incomplete = 0;      // partial groups discarded (a part never arrived)
  uint32_t saturated = 0;       // complete samples dropped: the rig flagged clipping
  uint32_t imu_samples = 0;     // complete IMU samples delivered
  uint32_t uwb_ranges = 0;      // complete UWB ranges delivered
};

enum class SensorKind : uint8_t { kNone = 0, kImu, kUwb };

struct CanSensorSample {
  SensorKind kind = SensorKind::kNone;
  ImuSample imu;   // valid when kind == kImu
  UwbRange uwb;    // valid when kind == kUwb
};

// Firmware side. Delivered samples still go through InputValidator like any
// other source (the decoder checks transport integrity, not physics).
class CanSensorDecoder {
 public:
  // Reads can.e2e_max_delta.
  void configure(const Params& params);

  // Feeds one received frame; now_us is the receiver clock used to rebuild the
  // 64-bit sensor time. kOk: `out` holds a complete sample. kEmpty: frame
  // accepted, sample not complete yet. kNotFound: not a HIL input frame
  // (ignored, not counted). kRejected: E2E failure or flagged sample, dropped and counted.
  [[nodiscard]] Status on_frame(const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out);

  const CanSensorStats& stats() const { return stats_; }
  void reset();
  void reset_stats() { stats_ = CanSensorStats{}; }  // counters only; reception state kept

 private:
  static constexpr size_t kNumInputs = 5;
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

  E2eReceiver rx_[kNumInputs];
  ImuGroup imu_;
  UwbGroup uwb_;
  CanSensorStats stats_;
};

}  // namespace uwbnav::can
