// Input validation rules for IMU and UWB frames (see input_validator.hpp).
#include "firmware/input_validator.hpp"

#include <cmath>
#include <cstring>

namespace uwbnav {
namespace {

bool finite3(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

float norm3(const Vec3f& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

Verdict reject(RejectReason r) { return Verdict{false, r}; }

}  // namespace

void InputValidator::configure(const SiteConfig& site, const Params& params) {
  site_ = &site;
  update_params(params);
  reset_history();
}

void InputValidator::update_params(const Params& params) {
  max_accel_mps2_ = params[ParamId::kInImuMaxAccel];
  max_gyro_radps_ = params[ParamId::kInImuMaxGyro];
  min_range_m_ = params[ParamId::kUwbMinRange];
  max_range_m_ = params[ParamId::kUwbMaxRange];
  stale_us_ = param_us(params[ParamId::kInStaleUs]);
#if UWBNAV_GNSS
  gnss_max_latency_us_ = param_us(params[ParamId::kGnssMaxLatency] * 1e6F);
#endif
#if UWBNAV_COOP
  coop_max_age_us_ = param_us(params[ParamId::kCoopMaxAge] * 1e6F);
#endif
}

void InputValidator::reset_history() {
  have_imu_ = false;
  have_uwb_ = false;
  last_imu_t_us_ = 0;
  last_uwb_t_us_ = 0;
#if UWBNAV_GNSS
  have_gnss_ = false;
  last_gnss_t_us_ = 0;
#endif
  std::memset(have_pair_, 0, sizeof have_pair_);
#if UWBNAV_COOP
  for (VehicleHistory& h : vehicles_) h = VehicleHistory{};
#endif
}

Verdict InputValidator::check_time(uint64_t t_us, uint64_t now_us, uint64_t last_t_us, bool have_last) const {
  if (t_us > now_us) return reject(RejectReason::kFuture);
  if (now_us - t_us > stale_us_) return reject(RejectReason::kStale);
  if (have_last && t_us < last_t_us) return reject(RejectReason::kOutOfOrder);
  return Verdict{true, RejectReason::kNotFinite};
}

Verdict InputValidator::check_imu(const ImuSample& s, uint64_t now_us) {
  if (!finite3(s.accel_body_mps2) || !finite3(s.gyro_body_radps)) return reject(RejectReason::kNotFinite);
  if (norm3(s.accel_body_mps2) > max_accel_mps2_ || norm3(s.gyro_body_radps) > max_gyro_radps_) {
    return reject(RejectReason::kOutOfRange);
  }
  if (have_imu_ && s.t_us == last_imu_t_us_) return reject(RejectReason::kDuplicate);
  const Verdict v = check_time(s.t_us, now_us, last_imu_t_us_, have_imu_);
  if (!v.accepted) return v;
  have_imu_ = true;
  last_imu_t_us_ = s.t_us;
  return v;
}

Verdict InputValidator::check_uwb(const UwbRange& r, uint64_t now_us) {
  if (!std::isfinite(r.range_m)) return reject(RejectReason::kNotFinite);
  // Channel diagnostics are optional (NaN = unknown) but never Inf.
  if (std::isinf(r.fp_power_dbm) || std::isinf(r.rx_power_dbm)) return reject(RejectReason::kNotFinite);
  if (r.range_m < min_range_m_ || r.range_m > max_range_m_) return reject(RejectReason::kOutOfRange);
  if (site_ == nullptr) return reject(RejectReason::kUnknownAnchor);
#if UWBNAV_COOP
  if (is_vehicle_id(r.anchor_id)) return check_vehicle_range(r, now_us);
#endif
  const int a = site_->find_anchor(r.anchor_id);
  if (a < 0) return reject(RejectReason::kUnknownAnchor);
  const int g = site_->find_tag(r.tag_id);
  if (g < 0) return reject(RejectReason::kUnknownTag);
  const size_t ai = static_cast<size_t>(a);
  const size_t gi = static_cast<size_t>(g);
  // A duplicate is a second report of one ranging exchange: the same pair with
  // the same sensor timestamp (whatever its value). Equal values at different
  // timestamps are new measurements: a radio with 1 cm (or 6 mm) resolution
  // legitimately repeats its last value whenever the tag moved less than that.
  if (have_pair_[ai][gi] && r.t_us == last_pair_t_us_[ai][gi]) return reject(RejectReason::kDuplicate);
  const Verdict v = check_time(r.t_us, now_us, last_uwb_t_us_, have_uwb_);
  if (!v.accepted) return v;
  have_uwb_ = true;
  last_uwb_t_us_ = r.t_us;
  have_pair_[ai][gi] = true;
  last_pair_t_us_[ai][gi] = r.t_us;
  return v;
}

#if UWBNAV_GNSS
Verdict InputValidator::check_gnss(const GnssFix& f, uint64_t now_us) {
  if (!finite3(f.pos_nav_m) || !finite3(f.pos_sigma_m)) return reject(RejectReason::kNotFinite);
  // Velocity is optional (NaN = not reported) but never Inf.
  if (std::isinf(f.vel_nav_mps.x) || std::isinf(f.vel_nav_mps.y) || std::isinf(f.vel_nav_mps.z) ||
      std::isinf(f.vel_sigma_mps)) {
    return reject(RejectReason::kNotFinite);
  }
  constexpr float kMaxPos_m = 1.0e6F;  // a local navigation frame, not ECEF
  if (!(f.pos_sigma_m.x > 0.0F && f.pos_sigma_m.y > 0.0F && f.pos_sigma_m.z > 0.0F) || norm3(f.pos_nav_m) > kMaxPos_m ||
      f.rx_t_us < f.t_us || f.rx_t_us - f.t_us > gnss_max_latency_us_) {
    return reject(RejectReason::kOutOfRange);
  }
  if (have_gnss_ && f.t_us == last_gnss_t_us_) return reject(RejectReason::kDuplicate);
  if (f.rx_t_us > now_us) return reject(RejectReason::kFuture);
  if (now_us - f.rx_t_us > stale_us_) return reject(RejectReason::kStale);
  if (have_gnss_ && f.t_us < last_gnss_t_us_) return reject(RejectReason::kOutOfOrder);
  have_gnss_ = true;
  last_gnss_t_us_ = f.t_us;
  return Verdict{true, RejectReason::kNotFinite};
}
#endif

#if UWBNAV_COOP
InputValidator::VehicleHistory& InputValidator::vehicle_history(uint16_t vehicle_id, uint64_t now_us) {
  VehicleHistory* victim = nullptr;  // a free entry, else the one used least recently
  for (VehicleHistory& h : vehicles_) {
    if (h.vehicle_id == vehicle_id) {
      h.last_use_us = now_us;
      return h;
    }
    const bool free = h.vehicle_id == kNoVehicleId;
    if (victim == nullptr || (free && victim->vehicle_id != kNoVehicleId) ||
        (!free && victim->vehicle_id != kNoVehicleId && h.last_use_us < victim->last_use_us)) {
      victim = &h;
    }
  }
  *victim = VehicleHistory{};
  victim->vehicle_id = vehicle_id;
  victim->last_use_us = now_us;
  return *victim;
}

// A range to a neighbour vehicle's tag: the same checks as a range to an
// anchor, duplicates kept per vehicle and tag.
Verdict InputValidator::check_vehicle_range(const UwbRange& r, uint64_t now_us) {
  const int g = site_->find_tag(r.tag_id);
  if (g < 0) return reject(RejectReason::kUnknownTag);
  const size_t gi = static_cast<size_t>(g);
  const Verdict v = check_time(r.t_us, now_us, last_uwb_t_us_, have_uwb_);
  if (!v.accepted) return v;
  VehicleHistory& h = vehicle_history(r.anchor_id, now_us);
  if (h.have_range[gi] && r.t_us == h.range_t_us[gi]) return reject(RejectReason::kDuplicate);
  have_uwb_ = true;
  last_uwb_t_us_ = r.t_us;
  h.have_range[gi] = true;
  h.range_t_us[gi] = r.t_us;
  return v;
}

Verdict InputValidator::check_neighbour(const NeighbourState& s, uint64_t now_us) {
  if (!is_vehicle_id(s.vehicle_id)) return reject(RejectReason::kUnknownAnchor);
  if (!finite3(s.pos_nav_m)) return reject(RejectReason::kNotFinite);
  for (float c : s.cov_pos_m2) {
    if (!std::isfinite(c)) return reject(RejectReason::kNotFinite);
  }
  // Velocity is optional (NaN = not reported) but never Inf.
  if (std::isinf(s.vel_nav_mps.x) || std::isinf(s.vel_nav_mps.y) || std::isinf(s.vel_nav_mps.z)) {
    return reject(RejectReason::kNotFinite);
  }
  constexpr float kMaxPos_m = 1.0e6F;  // a local navigation frame, not ECEF
  const float* c = s.cov_pos_m2;       // xx, xy, xz, yy, yz, zz
  const float det = c[0] * (c[3] * c[5] - c[4] * c[4]) - c[1] * (c[1] * c[5] - c[4] * c[2]) +
                    c[2] * (c[1] * c[4] - c[3] * c[2]);
  const bool pd = c[0] > 0.0F && c[3] > 0.0F && c[5] > 0.0F && c[0] * c[3] - c[1] * c[1] > 0.0F && det > 0.0F;
  if (!pd || norm3(s.pos_nav_m) > kMaxPos_m || s.rx_t_us < s.t_us || s.rx_t_us - s.t_us > coop_max_age_us_) {
    return reject(RejectReason::kOutOfRange);
  }
  if (s.rx_t_us > now_us) return reject(RejectReason::kFuture);
  if (now_us - s.rx_t_us > stale_us_) return reject(RejectReason::kStale);
  VehicleHistory& h = vehicle_history(s.vehicle_id, now_us);
  if (h.have_state && s.t_us == h.state_t_us) return reject(RejectReason::kDuplicate);
  if (h.have_state && s.t_us < h.state_t_us) return reject(RejectReason::kOutOfOrder);
  h.have_state = true;
  h.state_t_us = s.t_us;
  return Verdict{true, RejectReason::kNotFinite};
}
#endif

}  // namespace uwbnav
