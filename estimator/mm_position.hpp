// Horizontal position pseudo-measurement of the body origin: the RBF outage
// bridge's estimate during a UWB outage (rbf_bridge.hpp, docs/ekf.md "Outage bridging").
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// p_axis = pos_m with variance var_m2 (axis 0 = nav x, 1 = nav y).
ScalarObs mm_position(const NominalState& x, int axis, Real pos_m, Real var_m2);

}  // namespace uwbnav
