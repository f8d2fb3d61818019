// Horizontal position pseudo-measurement of the body origin.
#include "estimator/mm_position.hpp"

namespace uwbnav {

ScalarObs mm_position(const NominalState& x, int axis, Real pos_m, Real var_m2) {
  ScalarObs obs;
  const int a = axis == 1 ? 1 : 0;
  obs.h(ErrIdx::kPos + a) = Real(1);
  obs.innovation = pos_m - x.pos_nav_m(a);
  obs.r_var = var_m2;
  return obs;
}

}  // namespace uwbnav
