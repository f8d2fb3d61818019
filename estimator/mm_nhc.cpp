// Non-holonomic constraint pseudo-measurements (ground vehicles), taken in the
// road frame: the body pitched by the suspension against the road.
#include "estimator/mm_nhc.hpp"

namespace uwbnav {

namespace {

// Constraint direction in the nav frame: C d, d = e_y or e_z - theta e_x.
Vec3 nhc_dir_nav(const Mat3& c_nav_body, int axis, Real road_pitch_rad) {
  Vec3 d = c_nav_body.col(axis);
  if (axis == 2) d -= road_pitch_rad * c_nav_body.col(0);
  return d;
}

}  // namespace

Real mm_nhc_predict(const NominalState& x, const Mat3& c_nav_body, int axis, Real road_pitch_rad) {
  return nhc_dir_nav(c_nav_body, axis, road_pitch_rad).dot(x.vel_nav_mps);
}

ScalarObs mm_nhc(const NominalState& x, const Mat3& c_nav_body, int axis, Real sigma_mps, Real road_pitch_rad) {
  ScalarObs obs;
  // v_body = C_true^T v = C^T (I - [dtheta]x) v = C^T v + C^T [v]x dtheta.
  const Eigen::Matrix<Real, 1, 3> d_ct = nhc_dir_nav(c_nav_body, axis, road_pitch_rad).transpose();
  obs.h.segment<3>(ErrIdx::kVel) = d_ct;
  obs.h.segment<3>(ErrIdx::kAtt) = d_ct * skew(x.vel_nav_mps);
  obs.innovation = -d_ct.dot(x.vel_nav_mps);
  obs.r_var = sigma_mps * sigma_mps;
  return obs;
}

}  // namespace uwbnav
