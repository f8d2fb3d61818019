// Range measurement model (seed 003 eq. 16-18), extended with the tag lever arm
// in the body frame, the range's own timestamp and the time-correlated range
// errors of docs/ekf.md: measured = (1 + s) |p_tag - a| + b_tag + b_anchor + c + n,
// with s the common scale error, b_tag / b_anchor the offset states and c the
// commissioned offset of the anchor/tag pair (a known constant).
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

struct RangePrediction {
  Vec3 tag_pos_nav_m = Vec3::Zero();  // predicted tag antenna position at the range time [m]
  Vec3 los_nav = Vec3::Zero();        // unit vector anchor -> tag [-]
  Real geometric_m = Real(0);         // |p_tag - a| [m]
  Real range_m = Real(0);             // predicted range h(x), errors included [m]
  ErrRow h = ErrRow::Zero();          // dh/d(error state)
  bool valid = false;                 // false: tag on the anchor (no direction), or non-finite
};

// Which range-error states a range reads (negative: none).
struct RangeErrorSlots {
  int tag_index = -1;         // tag offset state ErrIdx::kTagBias + tag_index
  int anchor_slot = -1;       // anchor offset state ErrIdx::kAnchorBias + anchor_slot
  bool scale = true;          // the common scale state
  Real known_offset_m = Real(0);  // commissioned pair offset c [m]
};

// dt_s = range time - state time [s] (either sign; |dt_s| of one IMU interval
// or, without IMU, zero after the constant-velocity prediction).
// gyro_body_radps: last measured body rate (bias is subtracted here).
RangePrediction mm_range_predict(const NominalState& x, const Mat3& c_nav_body, const Vec3& gyro_body_radps,
                                 const Vec3& lever_body_m, const Vec3& anchor_pos_nav_m, Real dt_s,
                                 const RangeErrorSlots& slots);

}  // namespace uwbnav
