// Host IMU, UWB, GNSS and neighbour-state sources replaying a format v1 recording in timestamp order.
// The UWB source hands out the range only: the NLOS label never reaches the firmware.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hal/hal.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::hal {

// Replays IMU samples. The samples (recording) must outlive the source.
class ReplayImuSource : public ImuSource {
 public:
  explicit ReplayImuSource(const std::vector<ImuSample>& samples) : samples_(&samples) {}
  explicit ReplayImuSource(const dataset::Recording& rec) : samples_(&rec.imu) {}

  // kOk with the next sample when its t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, ImuSample& out) override;
  bool finished() const override { return next_ >= samples_->size(); }

  size_t delivered() const { return next_; }
  size_t size() const { return samples_->size(); }
  // Timestamp of the next sample [us]; only valid when !finished().
  uint64_t next_t_us() const { return (*samples_)[next_].t_us; }
  void rewind() { next_ = 0; }

 private:
  const std::vector<ImuSample>* samples_;
  size_t next_ = 0;
};

// Replays UWB ranges, from recording rows (label dropped) or from bare ranges.
// The rows must outlive the source.
class ReplayUwbSource : public UwbSource {
 public:
  explicit ReplayUwbSource(const std::vector<dataset::UwbRow>& rows) : rows_(&rows) {}
  explicit ReplayUwbSource(const std::vector<UwbRange>& ranges) : ranges_(&ranges) {}
  explicit ReplayUwbSource(const dataset::Recording& rec) : rows_(&rec.uwb) {}

  // kOk with the next range when its t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, UwbRange& out) override;
  bool finished() const override { return next_ >= size(); }

  size_t delivered() const { return next_; }
  size_t size() const { return rows_ != nullptr ? rows_->size() : ranges_->size(); }
  // Timestamp of the next range [us]; only valid when !finished().
  uint64_t next_t_us() const { return at(next_).t_us; }
  void rewind() { next_ = 0; }

 private:
  const UwbRange& at(size_t i) const { return rows_ != nullptr ? (*rows_)[i].range : (*ranges_)[i]; }

  const std::vector<dataset::UwbRow>* rows_ = nullptr;
  const std::vector<UwbRange>* ranges_ = nullptr;
  size_t next_ = 0;
};

// Replays GNSS fixes when they arrive (rx_t_us). The fixes must outlive the source.
class ReplayGnssSource : public GnssSource {
 public:
  explicit ReplayGnssSource(const std::vector<GnssFix>& fixes) : fixes_(&fixes) {}
  explicit ReplayGnssSource(const dataset::Recording& rec) : fixes_(&rec.gnss) {}

  // kOk with the next fix when its rx_t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, GnssFix& out) override;
  bool finished() const override { return next_ >= fixes_->size(); }
  size_t delivered() const { return next_; }
  // Arrival time of the next fix [us]; only valid when !finished().
  uint64_t next_rx_t_us() const { return (*fixes_)[next_].rx_t_us; }

 private:
  const std::vector<GnssFix>* fixes_;
  size_t next_ = 0;
};

// Replays neighbour vehicles' broadcast states when they arrive (rx_t_us).
// The states must outlive the source.
class ReplayNeighbourSource : public NeighbourSource {
 public:
  explicit ReplayNeighbourSource(const std::vector<NeighbourState>& states) : states_(&states) {}
  explicit ReplayNeighbourSource(const dataset::Recording& rec) : states_(&rec.neighbours) {}

  // kOk with the next state when its rx_t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, NeighbourState& out) override;
  bool finished() const override { return next_ >= states_->size(); }
  size_t delivered() const { return next_; }
  // Arrival time of the next state [us]; only valid when !finished().
  uint64_t next_rx_t_us() const { return (*states_)[next_].rx_t_us; }

 private:
  const std::vector<NeighbourState>* states_;
  size_t next_ = 0;
};

// The replay sources of one recording (which must outlive them).
struct ReplaySources {
  explicit ReplaySources(const dataset::Recording& rec) : imu(rec), uwb(rec), gnss(rec), neighbours(rec) {}
  ReplayImuSource imu;
  ReplayUwbSource uwb;
  ReplayGnssSource gnss;
  ReplayNeighbourSource neighbours;
  // The board's GNSS source: null when the recording has no gnss.csv.
  GnssSource* gnss_or_null(const dataset::Recording& rec) { return rec.gnss.empty() ? nullptr : &gnss; }
  // The board's neighbour-state source: null when the recording has no neighbours.csv.
  NeighbourSource* neighbours_or_null(const dataset::Recording& rec) {
    return rec.neighbours.empty() ? nullptr : &neighbours;
  }
};

}  // namespace uwbnav::hal
