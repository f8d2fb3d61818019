// Replay sources for a real-time host firmware: the recording's IMU, UWB, GNSS and
// neighbour-state streams (hal::ReplaySources) with sensor time mapped onto the board clock,
// so samples become due when the wall clock reaches them (t_clock = map(t_rec)).
#pragma once

#include <cstdint>

#include "hal/host/replay_sources.hpp"
#include "tools/hil/sensor_stream.hpp"

namespace uwbnav::hil {

class ClockMappedImuSource final : public hal::ImuSource {
 public:
  ClockMappedImuSource(hal::ReplayImuSource& inner, const TimeMap& map) : inner_(inner), map_(map) {}
  // kOk with the next sample (t_us in clock time) once its clock time <= up_to_us.
  [[nodiscard]] Status poll(uint64_t up_to_us, ImuSample& out) override;
  bool finished() const override { return inner_.finished(); }

 private:
  hal::ReplayImuSource& inner_;
  TimeMap map_;
};

class ClockMappedUwbSource final : public hal::UwbSource {
 public:
  ClockMappedUwbSource(hal::ReplayUwbSource& inner, const TimeMap& map) : inner_(inner), map_(map) {}
  [[nodiscard]] Status poll(uint64_t up_to_us, UwbRange& out) override;
  bool finished() const override { return inner_.finished(); }

 private:
  hal::ReplayUwbSource& inner_;
  TimeMap map_;
};

// GNSS fixes: validity and arrival both mapped; due when the arrival's clock time is reached.
class ClockMappedGnssSource final : public hal::GnssSource {
 public:
  ClockMappedGnssSource(hal::ReplayGnssSource& inner, const TimeMap& map) : inner_(inner), map_(map) {}
  [[nodiscard]] Status poll(uint64_t up_to_us, GnssFix& out) override;
  bool finished() const override { return inner_.finished(); }

 private:
  hal::ReplayGnssSource& inner_;
  TimeMap map_;
};

// Neighbour states: validity and arrival both mapped; due when the arrival's clock time is reached.
class ClockMappedNeighbourSource final : public hal::NeighbourSource {
 public:
  ClockMappedNeighbourSource(hal::ReplayNeighbourSource& inner, const TimeMap& map) : inner_(inner), map_(map) {}
  [[nodiscard]] Status poll(uint64_t up_to_us, NeighbourState& out) override;
  bool finished() const override { return inner_.finished(); }

 private:
  hal::ReplayNeighbourSource& inner_;
  TimeMap map_;
};

}  // namespace uwbnav::hil
