// Zero-velocity and zero-angular-rate pseudo-measurements at rest.
#include "estimator/mm_zupt.hpp"

namespace uwbnav {

ScalarObs mm_zupt(const NominalState& x, int axis, Real sigma_mps) {
  ScalarObs obs;
  obs.h(ErrIdx::kVel + axis) = Real(1);
  obs.innovation = -x.vel_nav_mps(axis);
  obs.r_var = sigma_mps * sigma_mps;
  return obs;
}

ScalarObs mm_zaru(const NominalState& x, const Vec3& gyro_mean_body_radps, int axis, Real sigma_radps) {
  ScalarObs obs;
  obs.h(ErrIdx::kBg + axis) = Real(1);
  obs.innovation = gyro_mean_body_radps(axis) - x.bg_body_radps(axis);
  obs.r_var = sigma_radps * sigma_radps;
  return obs;
}

}  // namespace uwbnav
