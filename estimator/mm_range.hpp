// Range measurement model (seed 003 eq. 16-18), extended with the tag lever arm
// in the body frame and the range's own timestamp: the tag position is
// predicted from the state time to the range time with the current velocity
// and body rate.
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

struct RangePrediction {
  Vec3 tag_pos_nav_m = Vec3::Zero();  // predicted tag antenna position at the range time [m]
  Real range_m = Real(0);             // predicted range h(x) [m]
  ErrRow h = ErrRow::Zero();          // dh/d(error state)
  bool valid = false;                 // false: tag on the anchor (no direction), or non-finite
};

// dt_s = range time - state time [s] (either sign; |dt_s| of one IMU interval
// or, without IMU, zero after the constant-velocity prediction).
// gyro_body_radps: last measured body rate (bias is subtracted here).
RangePrediction mm_range_predict(const NominalState& x, const Mat3& c_nav_body, const Vec3& gyro_body_radps,
                                 const Vec3& lever_body_m, const Vec3& anchor_pos_nav_m, Real dt_s);

}  // namespace uwbnav
