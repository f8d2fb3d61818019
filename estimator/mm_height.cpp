// Height pseudo-measurement of the body origin.
#include "estimator/mm_height.hpp"

namespace uwbnav {

ScalarObs mm_height(const NominalState& x, Real height_m, Real sigma_m) {
  ScalarObs obs;
  obs.h(ErrIdx::kPos + 2) = Real(1);
  obs.innovation = height_m - x.pos_nav_m.z();
  obs.r_var = sigma_m * sigma_m;
  return obs;
}

}  // namespace uwbnav
