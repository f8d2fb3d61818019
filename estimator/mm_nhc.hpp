// Non-holonomic constraint of a ground vehicle: zero lateral and vertical
// velocity of the body origin in the road frame (pseudo-measurements).
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// axis 1 = body y (lateral), 2 = body z (vertical). Measurement 0 with
// variance sigma^2: h(x) = d^T C^T v_nav with d = e_y (lateral) or
// d = e_z - theta e_x (vertical), theta = the suspension's pitch of the body
// against the road [rad, nose down positive, small]: on a level road the
// body-frame vertical velocity is v_x sin(theta), not 0 (docs/ekf.md
// "Ground-vehicle constraints").
ScalarObs mm_nhc(const NominalState& x, const Mat3& c_nav_body, int axis, Real sigma_mps,
                 Real road_pitch_rad = Real(0));

// The predicted road-frame velocity component h(x) (for tests and diagnostics).
Real mm_nhc_predict(const NominalState& x, const Mat3& c_nav_body, int axis, Real road_pitch_rad = Real(0));

}  // namespace uwbnav
