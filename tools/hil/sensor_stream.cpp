// Recording -> time-mapped sensor stream -> HIL CAN frames (see sensor_stream.hpp).
#include "tools/hil/sensor_stream.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/app.hpp"

namespace uwbnav::hil {

uint64_t TimeMap::to_clock_us(uint64_t t_rec_us) const {
  const uint64_t d_rec_us = t_rec_us >= rec_origin_us ? t_rec_us - rec_origin_us : 0;
  if (speed == 1.0) return clock_origin_us + d_rec_us;
  return clock_origin_us + static_cast<uint64_t>(std::llround(static_cast<double>(d_rec_us) / speed));
}

bool TimeMap::to_rec_us(uint64_t t_clock_us, uint64_t* t_rec_us) const {
  if (t_clock_us < clock_origin_us) return false;
  const uint64_t d_us = t_clock_us - clock_origin_us;
  *t_rec_us = speed == 1.0 ? rec_origin_us + d_us
                           : rec_origin_us + static_cast<uint64_t>(std::llround(static_cast<double>(d_us) * speed));
  return true;
}

uint64_t first_sensor_time_us(const dataset::Recording& rec) {
  uint64_t t = UINT64_MAX;
  if (!rec.imu.empty()) t = rec.imu.front().t_us;
  if (!rec.uwb.empty()) t = std::min(t, rec.uwb.front().range.t_us);
  return t == UINT64_MAX ? 0 : t;
}

TimeMap map_recording_to_clock(const dataset::Recording& rec, uint64_t earliest_clock_us, double speed) {
  TimeMap m;
  m.speed = speed;
  m.rec_origin_us = first_sensor_time_us(rec);
  // Same phase to the 10 ms grid as in the recording: clock_origin = rec_origin (mod period).
  const uint64_t phase_us = m.rec_origin_us % kCyclePeriodUs;
  uint64_t origin = (earliest_clock_us / kCyclePeriodUs) * kCyclePeriodUs + phase_us;
  if (origin < earliest_clock_us) origin += kCyclePeriodUs;
  m.clock_origin_us = origin;
  return m;
}

SensorStream::SensorStream(const dataset::Recording& rec, const TimeMap& map) : rec_(&rec), map_(map) {
  items_.reserve(rec.imu.size() + rec.uwb.size());
  for (size_t i = 0; i < rec.imu.size(); ++i) {
    items_.push_back({map.to_clock_us(rec.imu[i].t_us), StreamKind::kImu, static_cast<uint32_t>(i)});
  }
  for (size_t i = 0; i < rec.uwb.size(); ++i) {
    items_.push_back({map.to_clock_us(rec.uwb[i].range.t_us), StreamKind::kUwb, static_cast<uint32_t>(i)});
  }
  std::stable_sort(items_.begin(), items_.end(), [](const StreamItem& a, const StreamItem& b) {
    if (a.t_clock_us != b.t_clock_us) return a.t_clock_us < b.t_clock_us;
    return a.kind < b.kind;
  });
}

ImuSample SensorStream::imu_at(size_t i) const {
  ImuSample s = rec_->imu[items_[i].index];
  s.t_us = items_[i].t_clock_us;
  return s;
}

UwbRange SensorStream::uwb_at(size_t i) const {
  UwbRange r = rec_->uwb[items_[i].index].range;
  r.t_us = items_[i].t_clock_us;
  return r;
}

size_t SensorStream::encode(size_t i, can::CanSensorEncoder& encoder, hal::CanFrame (&out)[can::kImuFrames]) const {
  if (items_[i].kind == StreamKind::kImu) {
    ignore_result(encoder.encode_imu(imu_at(i), out));
    return can::kImuFrames;
  }
  hal::CanFrame uwb[can::kUwbFrames];
  ignore_result(encoder.encode_uwb(uwb_at(i), uwb));
  for (size_t k = 0; k < can::kUwbFrames; ++k) out[k] = uwb[k];
  return can::kUwbFrames;
}

bool SensorStream::newest_at_or_before(uint64_t t_us, uint64_t* t_sample_us) const {
  auto it = std::upper_bound(items_.begin(), items_.end(), t_us,
                             [](uint64_t t, const StreamItem& item) { return t < item.t_clock_us; });
  if (it == items_.begin()) return false;
  *t_sample_us = std::prev(it)->t_clock_us;
  return true;
}

}  // namespace uwbnav::hil
