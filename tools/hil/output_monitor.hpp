// HIL rig output side: checks every CAN frame the firmware sends (E2E CRC,
// alive-counter gaps per message, output-group consistency) and measures
// end-to-end latency, cycle jitter and the received positions (docs/hil.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "firmware/can/messages.hpp"
#include "hal/hal.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/hil/sensor_stream.hpp"

namespace uwbnav::hil {

// Per output message (UWBNAV_NavTime .. UWBNAV_Diag).
struct MessageCheck {
  uint32_t id = 0;
  const char* name = "";
  uint32_t received = 0;       // frames with this id
  uint32_t accepted = 0;       // CRC, length and counter value good
  uint32_t missing = 0;        // frames lost: sum of (alive-counter step - 1) between accepted frames
  uint32_t repeated = 0;       // counter did not advance
  uint32_t crc_errors = 0;
  uint32_t length_errors = 0;  // DLC not the message's length, extended/FD/error frame
  uint32_t counter_errors = 0; // counter value 15 (never sent)
  uint32_t saturated = 0;      // Saturated flag set by the sender
  bool have_last = false;
  uint8_t last_counter = 0;
  uint32_t e2e_failures() const { return crc_errors + length_errors + counter_errors; }
};

// One received 10 ms solution (NavTime + PosXY [+ PosZ] with equal counters).
struct ReceivedSolution {
  uint64_t nav_t_us = 0;       // UWBNAV_NavTime [us], firmware clock
  uint64_t arrival_us = 0;     // arrival of UWBNAV_PosXY, firmware clock [us]
  int status = 0;              // PosXY_Status (estimates.csv status integers)
  double pos_nav_m[3] = {0, 0, 0};  // z NaN until PosZ of the group arrived
  bool has_z = false;
};

class OutputMonitor {
 public:
  // stream (may be nullptr): the sensor schedule, for the latency reference.
  explicit OutputMonitor(const SensorStream* stream = nullptr);

  // One frame read from the bus; arrival_us in the firmware clock [us].
  // Frames that are not uwbnav outputs are counted in other_frames().
  void on_frame(const hal::CanFrame& frame, uint64_t arrival_us);

  const std::vector<MessageCheck>& messages() const { return checks_; }
  uint32_t total_missing() const;
  uint32_t total_e2e_failures() const;
  uint32_t other_frames() const { return other_frames_; }
  // PosXY/PosZ/VelHdg frames whose counter differs from the last NavTime's (frames before
  // the first NavTime seen belong to a group joined midway and are not counted).
  uint32_t group_mismatches() const { return group_mismatches_; }

  // End-to-end latency per solution [us]: PosXY arrival - timestamp of the
  // newest scheduled sample with t <= NavTime (only while the stream covers NavTime).
  const std::vector<double>& latencies_us() const { return latencies_us_; }
  // Inter-arrival times of consecutive UWBNAV_PosXY frames [us].
  const std::vector<double>& periods_us() const { return periods_us_; }
  const std::vector<ReceivedSolution>& solutions() const { return solutions_; }

  // Latest UWBNAV_Diag content (firmware overruns and input rejects).
  bool have_diag() const { return have_diag_; }
  const can::DiagMsg& last_diag() const { return last_diag_; }

 private:
  MessageCheck* check_of(uint32_t id);
  // E2E verdict bookkeeping; true when the frame may be used.
  bool admit(MessageCheck& c, Status decoded, const can::FrameMeta& meta);

  const SensorStream* stream_;
  std::vector<MessageCheck> checks_;
  uint32_t other_frames_ = 0;
  uint32_t group_mismatches_ = 0;

  bool have_nav_time_ = false;
  uint8_t nav_counter_ = 0;
  uint64_t nav_t_us_ = 0;
  bool have_last_pos_arrival_ = false;
  uint64_t last_pos_arrival_us_ = 0;
  bool pos_open_ = false;  // the last solution waits for PosZ of its group
  uint8_t pos_counter_ = 0;

  std::vector<double> latencies_us_;
  std::vector<double> periods_us_;
  std::vector<ReceivedSolution> solutions_;
  bool have_diag_ = false;
  can::DiagMsg last_diag_;
};

// Received solutions -> estimates rows in recording time (for the metrics).
std::vector<dataset::EstimateRow> solutions_to_estimates(const std::vector<ReceivedSolution>& solutions,
                                                         const TimeMap& map);

}  // namespace uwbnav::hil
