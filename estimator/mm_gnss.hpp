// GNSS antenna position and velocity measurement model: lever arm and latency
// (docs/ekf.md "GNSS"). Loose coupling: the receiver's solution, one axis at a time.
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// Where the filter puts the GNSS antenna at the fix's time of validity
// t_state + dt_s (dt_s < 0: the fix is older than the state, its latency).
struct GnssPredictionInput {
  const NominalState* x = nullptr;
  Mat3 c_nav_body = Mat3::Identity();       // C(q) of the state
  Vec3 gyro_body_radps = Vec3::Zero();      // latest gyro sample (raw, bias not removed) [rad/s]
  Vec3 accel_nav_mps2 = Vec3::Zero();       // latest kinematic acceleration, nav frame [m/s^2]
  Vec3 lever_body_m = Vec3::Zero();         // antenna in the body frame (FLU) [m]
  Real dt_s = Real(0);                      // fix time minus state time [s]
};

// Antenna position along nav axis `axis` (0 x, 1 y, 2 z):
// p + v dt + a dt^2 / 2 + C (l + (w x l) dt), w = gyro - b_g.
ScalarObs mm_gnss_position(const GnssPredictionInput& in, int axis, Real meas_m, Real var_m2);

// Antenna velocity along nav axis `axis`: v + a dt + C (w x l).
ScalarObs mm_gnss_velocity(const GnssPredictionInput& in, int axis, Real meas_mps, Real var_m2ps2);

}  // namespace uwbnav
