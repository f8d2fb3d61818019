// Zero-velocity update and zero-angular-rate update while the vehicle is
// detected at rest (rest detector: estimator/rest_detector.hpp).
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// v_nav[axis] = 0 with variance sigma^2.
ScalarObs mm_zupt(const NominalState& x, int axis, Real sigma_mps);

// At rest the mean gyro output over the window is the gyro bias:
// gyro_mean[axis] = b_g[axis] with variance sigma^2 (Earth rate neglected).
ScalarObs mm_zaru(const NominalState& x, const Vec3& gyro_mean_body_radps, int axis, Real sigma_radps);

}  // namespace uwbnav
