// GNSS antenna position and velocity measurement model (see mm_gnss.hpp).
// Jacobians in the error-state conventions of ekf_state.hpp:
// C_true = (I + [dtheta]x) C, w = gyro - b_g.
#include "estimator/mm_gnss.hpp"

namespace uwbnav {
namespace {
int clamp_axis(int axis) { return axis < 0 ? 0 : (axis > 2 ? 2 : axis); }
}  // namespace

ScalarObs mm_gnss_position(const GnssPredictionInput& in, int axis, Real meas_m, Real var_m2) {
  ScalarObs obs;
  const int a = clamp_axis(axis);
  const NominalState& x = *in.x;
  const Real dt = in.dt_s;
  const Vec3 w_body = in.gyro_body_radps - x.bg_body_radps;
  // Lever arm at the fix time, as the range model (mm_range.cpp).
  const Vec3 lever_t_body = in.lever_body_m + w_body.cross(in.lever_body_m) * dt;
  const Vec3 lever_nav = in.c_nav_body * lever_t_body;
  const Vec3 pred = x.pos_nav_m + x.vel_nav_mps * dt + in.accel_nav_mps2 * (Real(0.5) * dt * dt) + lever_nav;
  obs.h(ErrIdx::kPos + a) = Real(1);
  obs.h(ErrIdx::kVel + a) = dt;
  // d(C_true l)/d dtheta = -[C l]x, row a.
  const Mat3 d_att = -skew(lever_nav);
  obs.h.segment<3>(ErrIdx::kAtt) = d_att.row(a);
  // d(w x l)/d b_g = [l]x (w = gyro - b_g).
  const Mat3 d_bg = in.c_nav_body * skew(in.lever_body_m) * dt;
  obs.h.segment<3>(ErrIdx::kBg) = d_bg.row(a);
  obs.innovation = meas_m - pred(a);
  obs.r_var = var_m2;
  return obs;
}

ScalarObs mm_gnss_velocity(const GnssPredictionInput& in, int axis, Real meas_mps, Real var_m2ps2) {
  ScalarObs obs;
  const int a = clamp_axis(axis);
  const NominalState& x = *in.x;
  const Vec3 w_body = in.gyro_body_radps - x.bg_body_radps;
  const Vec3 rot_nav = in.c_nav_body * w_body.cross(in.lever_body_m);
  const Vec3 pred = x.vel_nav_mps + in.accel_nav_mps2 * in.dt_s + rot_nav;
  obs.h(ErrIdx::kVel + a) = Real(1);
  const Mat3 d_att = -skew(rot_nav);
  obs.h.segment<3>(ErrIdx::kAtt) = d_att.row(a);
  const Mat3 d_bg = in.c_nav_body * skew(in.lever_body_m);
  obs.h.segment<3>(ErrIdx::kBg) = d_bg.row(a);
  obs.innovation = meas_mps - pred(a);
  obs.r_var = var_m2ps2;
  return obs;
}

}  // namespace uwbnav
