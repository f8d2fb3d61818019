// Range measurement model with lever arm, time offset and range-error states
// (seed 003 eq. 16-18; error model in docs/ekf.md "Range errors").
#include "estimator/mm_range.hpp"

#include <cmath>

namespace uwbnav {
namespace {
// Below this predicted distance the line-of-sight direction is undefined [m].
constexpr Real kMinRange_m = Real(1e-3);
}  // namespace

RangePrediction mm_range_predict(const NominalState& x, const Mat3& c_nav_body, const Vec3& gyro_body_radps,
                                 const Vec3& lever_body_m, const Vec3& anchor_pos_nav_m, Real dt_s,
                                 const RangeErrorSlots& slots) {
  RangePrediction out;
  const Vec3 w_body = gyro_body_radps - x.bg_body_radps;
  // Lever arm at the range time: l_nav = C (l + (w x l) dt).
  const Vec3 lever_t_body = lever_body_m + w_body.cross(lever_body_m) * dt_s;
  const Vec3 lever_nav = c_nav_body * lever_t_body;
  out.tag_pos_nav_m = x.pos_nav_m + x.vel_nav_mps * dt_s + lever_nav;
  const Vec3 diff = out.tag_pos_nav_m - anchor_pos_nav_m;
  out.geometric_m = diff.norm();
  if (!(out.geometric_m >= kMinRange_m) || !std::isfinite(out.geometric_m)) return out;
  const Vec3 u = diff / out.geometric_m;  // seed 003 eq. 18 row
  out.los_nav = u;
  const Real scale = slots.scale ? Real(1) + x.range_scale() : Real(1);
  out.range_m = scale * out.geometric_m + slots.known_offset_m;
  const Eigen::Matrix<Real, 1, 3> su = scale * u.transpose();
  out.h.segment<3>(ErrIdx::kPos) = su;
  out.h.segment<3>(ErrIdx::kVel) = su * dt_s;
  // C_true l = (I + [dtheta]x) C l  ->  d/d dtheta = -[C l]x.
  out.h.segment<3>(ErrIdx::kAtt) = -(su * skew(lever_nav));
  // w = gyro - b_g  ->  d(w x l)/d b_g = [l]x.
  out.h.segment<3>(ErrIdx::kBg) = (su * c_nav_body * skew(lever_body_m)) * dt_s;
  if (slots.scale) out.h(ErrIdx::kScale) = out.geometric_m;
  if (slots.tag_index >= 0 && slots.tag_index < static_cast<int>(kMaxTags)) {
    out.range_m += x.tag_bias_m(slots.tag_index);
    out.h(ErrIdx::kTagBias + slots.tag_index) = Real(1);
  }
  if (slots.anchor_slot >= 0 && slots.anchor_slot < kBiasSlots) {
    out.range_m += x.anchor_bias_m(slots.anchor_slot);
    out.h(ErrIdx::kAnchorBias + slots.anchor_slot) = Real(1);
  }
  out.valid = out.h.allFinite() && std::isfinite(out.range_m);
  return out;
}

}  // namespace uwbnav
