// Checks and measures the firmware's CAN output on the HIL rig (see output_monitor.hpp).
#include "tools/hil/output_monitor.hpp"

#include <cmath>

#include "firmware/can/e2e.hpp"

namespace uwbnav::hil {
namespace {

constexpr can::MsgId kOutputs[] = {can::MsgId::kNavTime, can::MsgId::kPosXY,    can::MsgId::kPosZ,
                                   can::MsgId::kVelHdg,  can::MsgId::kAccuracy, can::MsgId::kDiag,
                                   can::MsgId::kAttitude};

}  // namespace

OutputMonitor::OutputMonitor(const SensorStream* stream) : stream_(stream) {
  for (can::MsgId m : kOutputs) {
    MessageCheck c;
    c.id = can::id_of(m);
    const can::MessageDef* def = can::find_message(c.id);
    c.name = def != nullptr ? def->name : "?";
    checks_.push_back(c);
  }
  latencies_us_.reserve(1 << 16);
  periods_us_.reserve(1 << 16);
  solutions_.reserve(1 << 16);
}

MessageCheck* OutputMonitor::check_of(uint32_t id) {
  for (auto& c : checks_) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

uint32_t OutputMonitor::total_missing() const {
  uint32_t n = 0;
  for (const auto& c : checks_) n += c.missing;
  return n;
}

uint32_t OutputMonitor::total_e2e_failures() const {
  uint32_t n = 0;
  for (const auto& c : checks_) n += c.e2e_failures();
  return n;
}

bool OutputMonitor::admit(MessageCheck& c, Status decoded, const can::FrameMeta& meta) {
  if (decoded == Status::kRejected) {
    ++c.crc_errors;
    return false;
  }
  if (decoded == Status::kOutOfRange) {
    ++c.counter_errors;
    return false;
  }
  if (!ok(decoded)) {
    ++c.length_errors;
    return false;
  }
  ++c.accepted;
  if (meta.saturated) ++c.saturated;
  if (c.have_last) {
    const uint8_t step = static_cast<uint8_t>((meta.counter + can::kAliveCounterModulo - c.last_counter) %
                                              can::kAliveCounterModulo);
    if (step == 0) {
      ++c.repeated;
    } else {
      c.missing += static_cast<uint32_t>(step - 1);
    }
  }
  c.have_last = true;
  c.last_counter = meta.counter;
  return true;
}

void OutputMonitor::on_frame(const hal::CanFrame& frame, uint64_t arrival_us) {
  MessageCheck* c = check_of(frame.id);
  if (c == nullptr) {
    ++other_frames_;
    return;
  }
  ++c->received;
  if ((frame.flags & (hal::CanFrame::kFlagExtended | hal::CanFrame::kFlagError | hal::CanFrame::kFlagFd)) != 0) {
    ++c->length_errors;
    return;
  }
  can::FrameMeta meta;
  switch (static_cast<can::MsgId>(frame.id)) {
    case can::MsgId::kNavTime: {
      can::NavTimeMsg m;
      if (!admit(*c, can::decode(frame, m, &meta), meta)) return;
      have_nav_time_ = true;
      nav_counter_ = meta.counter;
      nav_t_us_ = m.nav_t_us;
      pos_open_ = false;
      return;
    }
    case can::MsgId::kPosXY: {
      can::PosXYMsg m;
      if (!admit(*c, can::decode(frame, m, &meta), meta)) return;
      if (have_last_pos_arrival_) periods_us_.push_back(static_cast<double>(arrival_us) - static_cast<double>(last_pos_arrival_us_));
      have_last_pos_arrival_ = true;
      last_pos_arrival_us_ = arrival_us;
      if (!have_nav_time_) return;  // joined mid-group: the group's NavTime was before the first frame seen
      if (meta.counter != nav_counter_) {
        ++group_mismatches_;
        return;
      }
      ReceivedSolution s;
      s.nav_t_us = nav_t_us_;
      s.arrival_us = arrival_us;
      s.status = static_cast<int>(m.status);
      s.pos_nav_m[0] = static_cast<double>(m.x_nav_m);
      s.pos_nav_m[1] = static_cast<double>(m.y_nav_m);
      s.pos_nav_m[2] = std::nan("");
      solutions_.push_back(s);
      pos_open_ = true;
      pos_counter_ = meta.counter;
      uint64_t t_sample_us = 0;
      if (stream_ != nullptr && stream_->size() > 0 && nav_t_us_ >= stream_->first_clock_us() &&
          nav_t_us_ <= stream_->last_clock_us() && stream_->newest_at_or_before(nav_t_us_, &t_sample_us)) {
        latencies_us_.push_back(static_cast<double>(arrival_us) - static_cast<double>(t_sample_us));
      }
      return;
    }
    case can::MsgId::kPosZ: {
      can::PosZMsg m;
      if (!admit(*c, can::decode(frame, m, &meta), meta)) return;
      if (!have_nav_time_) return;
      if (meta.counter != nav_counter_) {
        ++group_mismatches_;
        return;
      }
      if (pos_open_ && pos_counter_ == meta.counter && !solutions_.empty()) {
        solutions_.back().pos_nav_m[2] = static_cast<double>(m.z_nav_m);
        solutions_.back().has_z = true;
        pos_open_ = false;
      }
      return;
    }
    case can::MsgId::kVelHdg: {
      can::VelHdgMsg m;
      if (!admit(*c, can::decode(frame, m, &meta), meta)) return;
      if (have_nav_time_ && meta.counter != nav_counter_) ++group_mismatches_;
      return;
    }
    case can::MsgId::kAccuracy: {
      can::AccuracyMsg m;
      ignore_result(admit(*c, can::decode(frame, m, &meta), meta));
      return;
    }
    case can::MsgId::kAttitude: {
      can::AttitudeMsg m;
      ignore_result(admit(*c, can::decode(frame, m, &meta), meta));
      return;
    }
    case can::MsgId::kDiag: {
      can::DiagMsg m;
      if (!admit(*c, can::decode(frame, m, &meta), meta)) return;
      have_diag_ = true;
      last_diag_ = m;
      return;
    }
    default:
      ++other_frames_;
      return;
  }
}

std::vector<dataset::EstimateRow> solutions_to_estimates(const std::vector<ReceivedSolution>& solutions,
                                                         const TimeMap& map) {
  std::vector<dataset::EstimateRow> rows;
  rows.reserve(solutions.size());
  for (const auto& s : solutions) {
    dataset::EstimateRow r;
    if (!map.to_rec_us(s.nav_t_us, &r.t_us)) continue;
    for (int k = 0; k < 3; ++k) r.pos_nav_m[k] = s.pos_nav_m[k];
    for (int k = 0; k < 3; ++k) r.pos_sigma_m[k] = std::nan("");
    r.status = s.status;
    rows.push_back(r);
  }
  return rows;
}

}  // namespace uwbnav::hil
