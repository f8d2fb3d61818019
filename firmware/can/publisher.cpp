// CanPublisher: periodic, E2E-protected, non-blocking transmission of the navigation output.
#include "firmware/can/publisher.hpp"

#include <cmath>

#include "firmware/can/e2e.hpp"

namespace uwbnav::can {
namespace {

// Rounds ms to whole 10 ms ticks (half away from zero) in float, no double:
// the float quotient ms / 10 is correctly rounded and lands on a half tick only
// when the exact quotient is one (neighbouring float ms values lie at least
// 0.8 ulp of ms / 10 apart, more than the 0.5 ulp of its rounding), so the result is the rounding of the exact quotient, as before.
uint32_t period_us_from_ms(float ms) {
  const long ticks = std::lround(ms / 10.0F);
  return static_cast<uint32_t>(ticks < 1 ? 1 : ticks) * kCanTickUs;
}

// One frame to the bus driver, counted; never retried.
void transmit(const hal::CanFrame& frame, bool saturated, hal::CanBus& bus, CanTxStats& stats) {
  const Status s = bus.send(frame);
  if (s == Status::kOk) {
    ++stats.sent;
    if (saturated) ++stats.saturated;
  } else if (s == Status::kWouldBlock) {
    ++stats.dropped;
  } else {
    ++stats.failed;
  }
}

}  // namespace

void CanDiag::set_anchor_nlos(int anchor_index, bool nlos) {
  if (anchor_index < 0 || anchor_index >= 16) return;
  const auto bit = static_cast<uint16_t>(1U << static_cast<unsigned>(anchor_index));
  nlos_mask = nlos ? static_cast<uint16_t>(nlos_mask | bit) : static_cast<uint16_t>(nlos_mask & ~bit);
}

void CanDiag::set_from_stats(const AppStats& stats) {
  loop_overruns = stats.loop.overruns;
  input_rejects = stats.imu.rejected_total() + stats.uwb.rejected_total() + stats.can_rx.rejected_total();
#if UWBNAV_GNSS
  input_rejects += stats.gnss.rejected_total();
#endif
#if UWBNAV_COOP
  input_rejects += stats.neighbours.rejected_total();
#endif
}

PosXYMsg pos_xy_from(const NavOutput& nav) {
  PosXYMsg m;
  m.status = nav.status;
  m.x_nav_m = nav.pos_nav_m.x;
  m.y_nav_m = nav.pos_nav_m.y;
  return m;
}

PosZMsg pos_z_from(const NavOutput& nav) {
  PosZMsg m;
  m.status = nav.status;
  m.z_nav_m = nav.pos_nav_m.z;
  m.vz_nav_mps = nav.vel_nav_mps.z;
  m.ranges_used = nav.ranges_used;
  m.ranges_rejected = nav.ranges_rejected;
  return m;
}

VelHdgMsg vel_hdg_from(const NavOutput& nav) {
  VelHdgMsg m;
  m.vx_nav_mps = nav.vel_nav_mps.x;
  m.vy_nav_mps = nav.vel_nav_mps.y;
  m.heading_rad = nav.heading_rad;
  return m;
}

AccuracyMsg accuracy_from(const NavOutput& nav) {
  AccuracyMsg m;
  m.sigma_x_m = nav.pos_sigma_m.x;
  m.sigma_y_m = nav.pos_sigma_m.y;
  m.sigma_z_m = nav.pos_sigma_m.z;
  m.corr_xy = nav.pos_xy_corr;
  return m;
}

AttitudeMsg attitude_from(const NavOutput& nav) {
  // Roll and pitch of the Z-Y-X (yaw, pitch, roll) decomposition of q_nav_body.
  AttitudeMsg m;
  const float w = nav.q_nav_body[0], x = nav.q_nav_body[1], y = nav.q_nav_body[2], z = nav.q_nav_body[3];
  m.heading_sigma_rad = nav.heading_sigma_rad;
  m.roll_rad = std::atan2(2.0F * (w * x + y * z), 1.0F - 2.0F * (x * x + y * y));
  m.pitch_rad = std::asin(std::fmin(std::fmax(2.0F * (w * y - z * x), -1.0F), 1.0F));
  return m;
}

DiagMsg diag_from(const CanDiag& diag) {
  DiagMsg m;
  m.nlos_mask = diag.nlos_mask;
  m.resets = diag.resets;
  m.overruns = diag.loop_overruns;
  m.input_rejects = diag.input_rejects;
  return m;
}

#if UWBNAV_COOP
NeighbourState coop_state_from(const NavOutput& nav, const Vec3f& tag_lever_body_m, uint16_t vehicle_id,
                               bool cooperative) {
  // R(q) * v = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z) of the unit quaternion.
  const float w = nav.q_nav_body[0], ux = nav.q_nav_body[1], uy = nav.q_nav_body[2], uz = nav.q_nav_body[3];
  const Vec3f& v = tag_lever_body_m;
  const float cx = uy * v.z - uz * v.y, cy = uz * v.x - ux * v.z, cz = ux * v.y - uy * v.x;  // u x v
  const float dx = uy * cz - uz * cy, dy = uz * cx - ux * cz, dz = ux * cy - uy * cx;        // u x (u x v)
  NeighbourState s;
  s.t_us = nav.t_us;
  s.rx_t_us = nav.t_us;
  s.vehicle_id = vehicle_id;
  s.pos_nav_m = Vec3f{nav.pos_nav_m.x + v.x + 2.0F * (w * cx + dx), nav.pos_nav_m.y + v.y + 2.0F * (w * cy + dy),
                      nav.pos_nav_m.z + v.z + 2.0F * (w * cz + dz)};
  const Vec3f& sg = nav.pos_sigma_m;
  s.cov_pos_m2[0] = sg.x * sg.x;
  s.cov_pos_m2[1] = nav.pos_xy_corr * sg.x * sg.y;
  s.cov_pos_m2[2] = 0.0F;
  s.cov_pos_m2[3] = sg.y * sg.y;
  s.cov_pos_m2[4] = 0.0F;
  s.cov_pos_m2[5] = sg.z * sg.z;
  s.vel_nav_mps = nav.vel_nav_mps;
  s.cooperative = cooperative;
  return s;
}

void CanPublisher::set_coop_state(const NeighbourState& s) {
  coop_state_ = s;
  coop_pending_ = true;
}
#endif

void CanPublisher::configure(const Params& params) {
  enabled_ = params[ParamId::kCanTxEnable] >= 0.5F;
  pos_.period_us = period_us_from_ms(params[ParamId::kCanPosPeriodMs]);
  accuracy_.period_us = period_us_from_ms(params[ParamId::kCanAccPeriodMs]);
  diag_.period_us = period_us_from_ms(params[ParamId::kCanDiagPeriodMs]);
  pos_.started = accuracy_.started = diag_.started = false;
#if UWBNAV_COOP
  coop_.period_us = period_us_from_ms(params[ParamId::kCanCoopPeriodMs]);
  coop_.started = false;
  const auto n = static_cast<uint32_t>(params[ParamId::kCoopVehicleId]);  // 0..32766 (parameter bounds)
  coop_id_ = n > 0 ? static_cast<uint16_t>(kFirstVehicleId + n) : kNoVehicleId;
#endif
}

bool CanPublisher::due(Schedule& s, uint64_t t_us) {
  // Half a tick of tolerance absorbs loop jitter; a clock that jumped back by
  // more than a period or a loop that fell behind restarts the schedule at t_us
  // instead of bursting the missed frames.
  if (!s.started || s.next_due_us > t_us + s.period_us) {
    s.started = true;
    s.next_due_us = t_us + s.period_us;
    return true;
  }
  if (t_us + kCanTickUs / 2 < s.next_due_us) return false;
  s.next_due_us += s.period_us;
  if (s.next_due_us <= t_us) s.next_due_us = t_us + s.period_us;
  return true;
}

void CanPublisher::send(Slot slot, hal::CanFrame& frame, bool saturated, hal::CanBus& bus) {
  counters_[slot] = next_alive_counter(counters_[slot]);
  transmit(frame, saturated, bus, stats_);
}

void CanPublisher::on_cycle(uint64_t t_us, const NavOutput& nav, const CanDiag& diag, hal::CanBus& bus) {
  if (!enabled_) return;
  hal::CanFrame f;
  f.t_us = t_us;
  if (due(pos_, t_us)) {
    bool sat = encode(NavTimeMsg{nav.t_us, nav.mode}, counters_[kNavTime], f);
    send(kNavTime, f, sat, bus);
    sat = encode(pos_xy_from(nav), counters_[kPosXY], f);
    send(kPosXY, f, sat, bus);
    sat = encode(pos_z_from(nav), counters_[kPosZ], f);
    send(kPosZ, f, sat, bus);
    sat = encode(vel_hdg_from(nav), counters_[kVelHdg], f);
    send(kVelHdg, f, sat, bus);
  }
  if (due(accuracy_, t_us)) {
    bool sat = encode(accuracy_from(nav), counters_[kAccuracy], f);
    send(kAccuracy, f, sat, bus);
    sat = encode(attitude_from(nav), counters_[kAttitude], f);
    send(kAttitude, f, sat, bus);
  }
  if (due(diag_, t_us)) {
    const bool sat = encode(diag_from(diag), counters_[kDiag], f);
    send(kDiag, f, sat, bus);
  }
#if UWBNAV_COOP
  send_coop(t_us, nav, bus);
#endif
}

#if UWBNAV_COOP
// The six frames of this vehicle's state, one alive counter for the group; a
// frame the bus refuses is counted like any other and the group is not resent.
void CanPublisher::send_coop(uint64_t t_us, const NavOutput& nav, hal::CanBus& bus) {
  const bool pending = coop_pending_;
  coop_pending_ = false;  // a state is good for the cycle it was set in
  const bool usable = nav.status == NavStatus::kValid || nav.status == NavStatus::kDegraded;
  if (coop_id_ == kNoVehicleId || !pending || !usable || !due(coop_, t_us)) return;
  NeighbourState s = coop_state_;
  s.vehicle_id = coop_id_;
  const CoopParts parts = coop_parts_from(s, true);
  hal::CanFrame f;
  f.t_us = t_us;
  for (size_t k = 0; k < kCoopFrames; ++k) {
    const bool sat = encode_coop_part(parts, CoopGroup::kOwn, k, counters_[kCoop], f);
    transmit(f, sat, bus, stats_);
  }
  counters_[kCoop] = next_alive_counter(counters_[kCoop]);
}
#endif

}  // namespace uwbnav::can
