// Range measurement model with lever arm and time offset (seed 003 eq. 16-18).
#include "estimator/mm_range.hpp"

#include <cmath>

namespace uwbnav {
namespace {
// Below this predicted distance the line-of-sight direction is undefined [m].
constexpr Real kMinRange_m = Real(1e-3);
}  // namespace

RangePrediction mm_range_predict(const NominalState& x, const Mat3& c_nav_body, const Vec3& gyro_body_radps,
                                 const Vec3& lever_body_m, const Vec3& anchor_pos_nav_m, Real dt_s) {
  RangePrediction out;
  const Vec3 w_body = gyro_body_radps - x.bg_body_radps;
  // Lever arm at the range time: l_nav = C (l + (w x l) dt).
  const Vec3 lever_t_body = lever_body_m + w_body.cross(lever_body_m) * dt_s;
  const Vec3 lever_nav = c_nav_body * lever_t_body;
  out.tag_pos_nav_m = x.pos_nav_m + x.vel_nav_mps * dt_s + lever_nav;
  const Vec3 diff = out.tag_pos_nav_m - anchor_pos_nav_m;
  out.range_m = diff.norm();
  if (!(out.range_m >= kMinRange_m) || !std::isfinite(out.range_m)) return out;
  const Vec3 u = diff / out.range_m;  // seed 003 eq. 18 row
  out.h.segment<3>(ErrIdx::kPos) = u.transpose();
  out.h.segment<3>(ErrIdx::kVel) = u.transpose() * dt_s;
  // C_true l = (I + [dtheta]x) C l  ->  d/d dtheta = -[C l]x.
  out.h.segment<3>(ErrIdx::kAtt) = -(u.transpose() * skew(lever_nav));
  // w = gyro - b_g  ->  d(w x l)/d b_g = [l]x.
  out.h.segment<3>(ErrIdx::kBg) = (u.transpose() * c_nav_body * skew(lever_body_m)) * dt_s;
  out.valid = out.h.allFinite();
  return out;
}

}  // namespace uwbnav
