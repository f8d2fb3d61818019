// Non-holonomic constraint of a ground vehicle: zero lateral and vertical
// velocity of the body origin in the body frame (pseudo-measurements).
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// axis 1 = body y (lateral), 2 = body z (vertical). Measurement 0 with
// variance sigma^2: h(x) = e_axis^T C^T v_nav.
ScalarObs mm_nhc(const NominalState& x, const Mat3& c_nav_body, int axis, Real sigma_mps);

// The predicted body-frame velocity component (for tests and diagnostics).
Real mm_nhc_predict(const NominalState& x, const Mat3& c_nav_body, int axis);

}  // namespace uwbnav
