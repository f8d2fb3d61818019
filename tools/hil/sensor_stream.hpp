// HIL rig input side: a recording's IMU samples and UWB ranges merged into one
// sensor-time-ordered stream, with the mapping of recording time onto the
// clock of the device under test, encoded as HIL CAN frames (docs/hil.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "firmware/can/sensor_decoder.hpp"
#include "hal/hal.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::hil {

// Recording time <-> clock time of the firmware under test:
//   t_clock = clock_origin_us + (t_rec - rec_origin_us) / speed
// speed 1.0 is an exact integer shift (t_rec = t_clock + offset).
struct TimeMap {
  uint64_t rec_origin_us = 0;    // recording time mapped to clock_origin_us [us]
  uint64_t clock_origin_us = 0;  // [us] in the firmware clock
  double speed = 1.0;            // playback speed (> 0): recording seconds per clock second

  // Recording time -> clock time. t_rec_us >= rec_origin_us.
  uint64_t to_clock_us(uint64_t t_rec_us) const;
  // Clock time -> recording time; false when t_clock_us is before clock_origin_us.
  bool to_rec_us(uint64_t t_clock_us, uint64_t* t_rec_us) const;
};

// Earliest sensor timestamp of a recording (IMU or UWB) [us]; 0 when empty.
uint64_t first_sensor_time_us(const dataset::Recording& rec);

// Maps the recording so that its first sample lands at or after
// `earliest_clock_us`, on the 10 ms loop grid phase the recording has (the
// shift is a multiple of the loop period), so IMU samples keep their phase to
// the firmware's deadlines exactly as in a lockstep replay.
TimeMap map_recording_to_clock(const dataset::Recording& rec, uint64_t earliest_clock_us, double speed);

enum class StreamKind : uint8_t { kImu = 0, kUwb = 1 };

struct StreamItem {
  uint64_t t_clock_us = 0;  // sample timestamp in the firmware clock [us]
  StreamKind kind = StreamKind::kImu;
  uint32_t index = 0;       // into rec.imu or rec.uwb
};

class SensorStream {
 public:
  // The recording must outlive the stream. Order: sensor time, IMU before UWB
  // on equal stamps (the order App::tick feeds the estimator).
  SensorStream(const dataset::Recording& rec, const TimeMap& map);

  size_t size() const { return items_.size(); }
  const StreamItem& operator[](size_t i) const { return items_[i]; }
  const TimeMap& map() const { return map_; }
  size_t imu_count() const { return rec_->imu.size(); }
  size_t uwb_count() const { return rec_->uwb.size(); }
  // Sample timestamps of the first and last item (clock) [us]; 0 when empty.
  uint64_t first_clock_us() const { return items_.empty() ? 0 : items_.front().t_clock_us; }
  uint64_t last_clock_us() const { return items_.empty() ? 0 : items_.back().t_clock_us; }

  // Encodes item i with its clock timestamp into out[0..n-1] (3 frames per IMU
  // sample, 2 per range); returns n. Frame t_us = sample clock time.
  size_t encode(size_t i, can::CanSensorEncoder& encoder, hal::CanFrame (&out)[can::kImuFrames]) const;

  // The sample as the firmware should receive it (timestamp in clock time).
  ImuSample imu_at(size_t i) const;
  UwbRange uwb_at(size_t i) const;

  // Timestamp of the newest item with t_clock_us <= t_us; false when none.
  bool newest_at_or_before(uint64_t t_us, uint64_t* t_sample_us) const;

 private:
  const dataset::Recording* rec_;
  TimeMap map_;
  std::vector<StreamItem> items_;
};

}  // namespace uwbnav::hil
