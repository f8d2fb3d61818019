// HIL sensor frames: rig-side encoding and firmware-side E2E-checked decoding.
#include "firmware/can/sensor_decoder.hpp"

namespace uwbnav::can {
namespace {

// Receiver index = position in this list: HIL IMU parts, HIL UWB parts, then
// (UWBNAV_COOP) the V2X_Neighbour parts and (UWBNAV_GNSS) the GNSS_Fix parts,
// each in group order.
constexpr uint32_t kInputIds[] = {id_of(MsgId::kHilImuTime), id_of(MsgId::kHilImuAccel),
                                  id_of(MsgId::kHilImuGyro), id_of(MsgId::kHilUwbRange),
                                  id_of(MsgId::kHilUwbTime)
#if UWBNAV_COOP
                                  , coop_id(CoopGroup::kNeighbour, 0), coop_id(CoopGroup::kNeighbour, 1),
                                  coop_id(CoopGroup::kNeighbour, 2), coop_id(CoopGroup::kNeighbour, 3),
                                  coop_id(CoopGroup::kNeighbour, 4), coop_id(CoopGroup::kNeighbour, 5)
#endif
#if UWBNAV_GNSS
                                  , gnss_id(0), gnss_id(1), gnss_id(2), gnss_id(3), gnss_id(4)
#endif
};
constexpr uint8_t kImuAll = 0x7;
constexpr uint8_t kUwbAll = 0x3;
#if UWBNAV_COOP
constexpr uint8_t kNeighbourAll = 0x3F;
static_assert(kCoopFrames == 6, "kNeighbourAll has a bit per part");
#endif
#if UWBNAV_GNSS
constexpr uint8_t kGnssAll = 0x1F;
static_assert(kGnssFrames == 5, "kGnssAll has a bit per part");
#endif

}  // namespace

bool CanSensorEncoder::encode_imu(const ImuSample& s, hal::CanFrame (&out)[kImuFrames]) {
  bool sat = encode(HilImuTimeMsg{static_cast<uint32_t>(s.t_us)}, imu_counter_, out[0]);
  sat = encode(HilImuAccelMsg{s.accel_body_mps2}, imu_counter_, out[1]) || sat;
  sat = encode(HilImuGyroMsg{s.gyro_body_radps}, imu_counter_, out[2]) || sat;
  for (auto& f : out) f.t_us = s.t_us;
  imu_counter_ = next_alive_counter(imu_counter_);
  return sat;
}

bool CanSensorEncoder::encode_uwb(const UwbRange& r, hal::CanFrame (&out)[kUwbFrames]) {
  HilUwbRangeMsg range;
  range.anchor_id = r.anchor_id;
  range.tag_id = r.tag_id;
  range.range_m = r.range_m;
  HilUwbTimeMsg time;
  time.t_sensor_us = static_cast<uint32_t>(r.t_us);
  time.fp_power_dbm = r.fp_power_dbm;
  time.rx_power_dbm = r.rx_power_dbm;
  bool sat = encode(range, uwb_counter_, out[0]);
  sat = encode(time, uwb_counter_, out[1]) || sat;
  for (auto& f : out) f.t_us = r.t_us;
  uwb_counter_ = next_alive_counter(uwb_counter_);
  return sat;
}

void CanSensorDecoder::configure(const Params& params) {
  const auto max_delta = static_cast<uint8_t>(params[ParamId::kCanE2eMaxDelta]);
  for (auto& r : rx_) r.set_max_delta(max_delta);
}

void CanSensorDecoder::reset() {
  for (auto& r : rx_) r.reset();
  imu_ = ImuGroup{};
  uwb_ = UwbGroup{};
#if UWBNAV_COOP
  neighbour_ = NeighbourGroup{};
#endif
#if UWBNAV_GNSS
  gnss_ = GnssGroup{};
#endif
  stats_ = CanSensorStats{};
}

Status CanSensorDecoder::check(size_t input, const MessageLayout& m, const hal::CanFrame& f) {
  ++stats_.frames;
  if ((f.flags & (hal::CanFrame::kFlagExtended | hal::CanFrame::kFlagError)) != 0) {
    ++stats_.length_errors;
    return Status::kRejected;
  }
  E2eReceiver& rx = rx_[input];
  const uint8_t before = rx.last_counter();
  const E2eVerdict v = rx.check(m.data_id, f.data, f.len, m.dlc);
  switch (v) {
    case E2eVerdict::kOk:
    case E2eVerdict::kInitial:
      return Status::kOk;
    case E2eVerdict::kOkSomeLost:
      stats_.frames_lost += static_cast<uint32_t>((rx.last_counter() + kAliveCounterModulo - before) %
                                                  kAliveCounterModulo) - 1U;
      return Status::kOk;
    case E2eVerdict::kWrongCrc:
      ++stats_.crc_errors;
      return Status::kRejected;
    case E2eVerdict::kBadLength:
      ++stats_.length_errors;
      return Status::kRejected;
    case E2eVerdict::kRepeated:
    case E2eVerdict::kWrongSequence:
    case E2eVerdict::kBadCounter:
      ++stats_.counter_errors;
      return Status::kRejected;
  }
  return Status::kRejected;
}

Status CanSensorDecoder::on_frame(const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out) {
  static_assert(sizeof kInputIds / sizeof kInputIds[0] == kNumInputs, "one receiver per input id");
  for (size_t i = 0; i < kNumInputs; ++i) {
    if (f.id != kInputIds[i]) continue;
#if UWBNAV_COOP || UWBNAV_GNSS
    if (i < kNumHilInputs && !hil_enabled_) return Status::kNotFound;
#endif
    const Status s = check(i, *find_layout(f.id), f);
    if (s != Status::kOk) return s;
    if (i < kImuFrames) return on_imu_part(i, f, now_us, out);
#if UWBNAV_GNSS
    if (i >= kFirstGnssInput) return on_gnss_part(i - kFirstGnssInput, f, now_us, out);
#endif
#if UWBNAV_COOP
    if (i >= kNumHilInputs) return on_neighbour_part(i - kNumHilInputs, f, now_us, out);
#endif
    return on_uwb_part(i - kImuFrames, f, now_us, out);
  }
  return Status::kNotFound;
}

Status CanSensorDecoder::on_imu_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out) {
  FrameMeta meta;
  HilImuTimeMsg time;
  HilImuAccelMsg accel;
  HilImuGyroMsg gyro;
  const Status s = part == 0 ? decode(f, time, &meta) : part == 1 ? decode(f, accel, &meta) : decode(f, gyro, &meta);
  if (s != Status::kOk) return Status::kRejected;  // unreachable after check(); defensive
  if (imu_.have != 0 && imu_.counter != meta.counter) {
    ++stats_.incomplete;
    imu_ = ImuGroup{};
  }
  imu_.counter = meta.counter;
  imu_.have = static_cast<uint8_t>(imu_.have | (1U << part));
  imu_.saturated = imu_.saturated || meta.saturated;
  if (part == 0) {
    imu_.t32_us = time.t_sensor_us;
  } else if (part == 1) {
    imu_.sample.accel_body_mps2 = accel.accel_body_mps2;
  } else {
    imu_.sample.gyro_body_radps = gyro.gyro_body_radps;
  }
  if (imu_.have != kImuAll) return Status::kEmpty;
  const ImuGroup done = imu_;
  imu_ = ImuGroup{};
  if (done.saturated) {
    ++stats_.saturated;
    return Status::kRejected;
  }
  out.kind = SensorKind::kImu;
  out.imu = done.sample;
  out.imu.t_us = unwrap_time_us(done.t32_us, now_us);
  ++stats_.imu_samples;
  return Status::kOk;
}

Status CanSensorDecoder::on_uwb_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out) {
  FrameMeta meta;
  HilUwbRangeMsg range;
  HilUwbTimeMsg time;
  const Status s = part == 0 ? decode(f, range, &meta) : decode(f, time, &meta);
  if (s != Status::kOk) return Status::kRejected;  // unreachable after check(); defensive
  if (uwb_.have != 0 && uwb_.counter != meta.counter) {
    ++stats_.incomplete;
    uwb_ = UwbGroup{};
  }
  uwb_.counter = meta.counter;
  uwb_.have = static_cast<uint8_t>(uwb_.have | (1U << part));
  uwb_.saturated = uwb_.saturated || meta.saturated;
  if (part == 0) {
    uwb_.range.anchor_id = range.anchor_id;
    uwb_.range.tag_id = range.tag_id;
    uwb_.range.range_m = range.range_m;
  } else {
    uwb_.t32_us = time.t_sensor_us;
    uwb_.range.fp_power_dbm = time.fp_power_dbm;
    uwb_.range.rx_power_dbm = time.rx_power_dbm;
  }
  if (uwb_.have != kUwbAll) return Status::kEmpty;
  const UwbGroup done = uwb_;
  uwb_ = UwbGroup{};
  if (done.saturated) {
    ++stats_.saturated;
    return Status::kRejected;
  }
  out.kind = SensorKind::kUwb;
  out.uwb = done.range;
  out.uwb.t_us = unwrap_time_us(done.t32_us, now_us);
  ++stats_.uwb_ranges;
  return Status::kOk;
}

#if UWBNAV_COOP
// The six parts of one neighbour state, grouped by alive counter like the HIL
// samples: a part with another counter drops the partial group (incomplete);
// a complete group is dropped when a part was flagged (saturated) or the
// sender marked it not valid, and delivered otherwise.
Status CanSensorDecoder::on_neighbour_part(size_t part, const hal::CanFrame& f, uint64_t now_us,
                                           CanSensorSample& out) {
  FrameMeta meta;
  CoopParts parts = neighbour_.parts;
  if (decode_coop_part(f, CoopGroup::kNeighbour, part, parts, &meta) != Status::kOk) {
    return Status::kRejected;  // unreachable after check(); defensive
  }
  if (neighbour_.have != 0 && neighbour_.counter != meta.counter) {
    ++stats_.incomplete;
    neighbour_ = NeighbourGroup{};
    parts = CoopParts{};
    static_cast<void>(decode_coop_part(f, CoopGroup::kNeighbour, part, parts, nullptr));  // this part, fresh group
  }
  neighbour_.parts = parts;
  neighbour_.counter = meta.counter;
  neighbour_.have = static_cast<uint8_t>(neighbour_.have | (1U << part));
  neighbour_.saturated = neighbour_.saturated || meta.saturated;
  if (neighbour_.have != kNeighbourAll) return Status::kEmpty;
  const NeighbourGroup done = neighbour_;
  neighbour_ = NeighbourGroup{};
  if (done.saturated) {
    ++stats_.saturated;
    return Status::kRejected;
  }
  if (!done.parts.valid) {
    ++stats_.neighbour_invalid;
    return Status::kRejected;
  }
  out.kind = SensorKind::kNeighbour;
  out.neighbour = neighbour_state_from(done.parts, now_us);
  ++stats_.neighbour_states;
  return Status::kOk;
}
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
// The five parts of one GNSS fix, grouped by alive counter like the neighbour
// states: a complete group is dropped when a part was flagged (saturated:
// e.g. a claimed sigma above 20.475 m) or it carries no usable fix type.
Status CanSensorDecoder::on_gnss_part(size_t part, const hal::CanFrame& f, uint64_t now_us, CanSensorSample& out) {
  FrameMeta meta;
  GnssParts parts = gnss_.parts;
  if (decode_gnss_part(f, part, parts, &meta) != Status::kOk) {
    return Status::kRejected;  // unreachable after check(); defensive
  }
  if (gnss_.have != 0 && gnss_.counter != meta.counter) {
    ++stats_.incomplete;
    gnss_ = GnssGroup{};
    parts = GnssParts{};
    static_cast<void>(decode_gnss_part(f, part, parts, nullptr));  // this part, fresh group
  }
  gnss_.parts = parts;
  gnss_.counter = meta.counter;
  gnss_.have = static_cast<uint8_t>(gnss_.have | (1U << part));
  gnss_.saturated = gnss_.saturated || meta.saturated;
  if (gnss_.have != kGnssAll) return Status::kEmpty;
  const GnssGroup done = gnss_;
  gnss_ = GnssGroup{};
  if (done.saturated) {
    ++stats_.saturated;
    return Status::kRejected;
  }
  if (gnss_fix_from(done.parts, now_us, out.gnss) != Status::kOk) {
    ++stats_.gnss_no_fix;
    return Status::kRejected;
  }
  out.kind = SensorKind::kGnss;
  ++stats_.gnss_fixes;
  return Status::kOk;
}
#endif  // UWBNAV_GNSS

}  // namespace uwbnav::can
