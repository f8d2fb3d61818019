// Multi-sensor consistency model (seed 000 eq. 3-6).
#include "estimator/nlos/consistency.hpp"

#include <cmath>

#include "estimator/types.hpp"

namespace uwbnav {

float consistency_excess_m(float delta_range_m, float dist_travelled_m) {
  if (!std::isfinite(delta_range_m) || !std::isfinite(dist_travelled_m)) return kNaNf;
  return std::fabs(delta_range_m) - dist_travelled_m;  // seed 000 eq. 4-5
}

float consistency_p_nlos(float delta_range_m, float dist_travelled_m, float sigma_uwb_m) {
  const float excess_m = consistency_excess_m(delta_range_m, dist_travelled_m);
  if (!std::isfinite(excess_m) || !(sigma_uwb_m > 0.0F) || !std::isfinite(sigma_uwb_m)) return kNaNf;
  // seed 000 eq. 6
  if (excess_m > 3.0F * sigma_uwb_m) return 0.9F;
  if (excess_m > 2.0F * sigma_uwb_m) return 0.7F;
  if (excess_m > sigma_uwb_m) return 0.55F;
  return 0.35F;
}

}  // namespace uwbnav
