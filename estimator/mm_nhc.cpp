// Non-holonomic constraint pseudo-measurements (ground vehicles).
#include "estimator/mm_nhc.hpp"

namespace uwbnav {

Real mm_nhc_predict(const NominalState& x, const Mat3& c_nav_body, int axis) {
  return c_nav_body.col(axis).dot(x.vel_nav_mps);
}

ScalarObs mm_nhc(const NominalState& x, const Mat3& c_nav_body, int axis, Real sigma_mps) {
  ScalarObs obs;
  // v_body = C_true^T v = C^T (I - [dtheta]x) v = C^T v + C^T [v]x dtheta.
  const Eigen::Matrix<Real, 1, 3> e_ct = c_nav_body.col(axis).transpose();
  obs.h.segment<3>(ErrIdx::kVel) = e_ct;
  obs.h.segment<3>(ErrIdx::kAtt) = e_ct * skew(x.vel_nav_mps);
  obs.innovation = -mm_nhc_predict(x, c_nav_body, axis);
  obs.r_var = sigma_mps * sigma_mps;
  return obs;
}

}  // namespace uwbnav
