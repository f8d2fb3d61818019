// Height constraint of a ground vehicle: the body origin stays near its
// surveyed height (anchors near the tag height leave z poorly observed).
#pragma once

#include "estimator/ekf_core.hpp"

namespace uwbnav {

// p_z = height_m with variance sigma^2.
ScalarObs mm_height(const NominalState& x, Real height_m, Real sigma_m);

}  // namespace uwbnav
