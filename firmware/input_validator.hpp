// Input validation: every IMU, UWB and GNSS frame is checked (NaN/Inf, physical range,
// unknown anchor/tag, duplicate = same stream/pair and same timestamp,
// out-of-order, stale, future) and counted per reason before anything reaches
// the estimator.
#pragma once

#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"
#include "firmware/app_stats.hpp"

namespace uwbnav {

// Verdict on one frame: accepted, or the first reason it failed.
struct Verdict {
  bool accepted = false;
  RejectReason reason = RejectReason::kNotFinite;
};

class InputValidator {
 public:
  // Binds the site (anchor/tag tables) and parameter limits; clears history.
  void configure(const SiteConfig& site, const Params& params);
  void update_params(const Params& params);
  void reset_history();

  // `now_us` is the loop time of the cycle that drains the frame.
  Verdict check_imu(const ImuSample& s, uint64_t now_us);
  Verdict check_uwb(const UwbRange& r, uint64_t now_us);
#if UWBNAV_GNSS
  // GNSS fix: finite position, positive finite claimed sigmas, finite or absent
  // (NaN) velocity, arrival not before validity, latency within gnss.max_latency
  // (out of range), arrival stale/future against the loop time, validity time
  // duplicate/out of order against the last accepted fix.
  Verdict check_gnss(const GnssFix& f, uint64_t now_us);
#endif
#if UWBNAV_COOP
  // Neighbour state: a vehicle id, finite position, a finite positive-definite
  // covariance, finite or absent (NaN) velocity, arrival not before validity,
  // latency within coop.max_age (out of range), arrival stale/future against the
  // loop time, validity time duplicate/out of order per vehicle.
  Verdict check_neighbour(const NeighbourState& s, uint64_t now_us);
#endif

 private:
  Verdict check_time(uint64_t t_us, uint64_t now_us, uint64_t last_t_us, bool have_last) const;

  const SiteConfig* site_ = nullptr;
  float max_accel_mps2_ = 0.0F;
  float max_gyro_radps_ = 0.0F;
  float min_range_m_ = 0.0F;
  float max_range_m_ = 0.0F;
  uint64_t stale_us_ = 0;

  bool have_imu_ = false;
  uint64_t last_imu_t_us_ = 0;
  bool have_uwb_ = false;
  uint64_t last_uwb_t_us_ = 0;
#if UWBNAV_GNSS
  uint64_t gnss_max_latency_us_ = 0;
  bool have_gnss_ = false;
  uint64_t last_gnss_t_us_ = 0;
#endif
#if UWBNAV_COOP
  // Per neighbour vehicle: its last accepted state time and, per tag, its last
  // accepted range time (duplicates and order). A vehicle not in a full table
  // takes the entry used least recently.
  struct VehicleHistory {
    uint16_t vehicle_id = kNoVehicleId;
    uint64_t last_use_us = 0;           // loop time of the entry's last use [us]
    bool have_state = false;
    uint64_t state_t_us = 0;
    bool have_range[kMaxTags] = {};
    uint64_t range_t_us[kMaxTags] = {};
  };
  VehicleHistory& vehicle_history(uint16_t vehicle_id, uint64_t now_us);
  Verdict check_vehicle_range(const UwbRange& r, uint64_t now_us);
  static constexpr size_t kVehicleHistory = 8;
  VehicleHistory vehicles_[kVehicleHistory];
  uint64_t coop_max_age_us_ = 0;
#endif
  // Timestamp of the last accepted range per (anchor index, tag index): duplicate detection.
  uint64_t last_pair_t_us_[kMaxAnchors][kMaxTags] = {};
  bool have_pair_[kMaxAnchors][kMaxTags] = {};
};

}  // namespace uwbnav
