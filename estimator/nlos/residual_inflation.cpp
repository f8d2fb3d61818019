// Residual-based R inflation (seed 003 eq. 21-25).
#include "estimator/nlos/residual_inflation.hpp"

#include <cmath>

#include "estimator/types.hpp"

namespace uwbnav {

float residual_inflation_factor(float residual, float threshold, float beta) {
  if (!std::isfinite(residual) || !std::isfinite(threshold) || !std::isfinite(beta) || !(threshold > 0.0F)) {
    return kNaNf;
  }
  const float delta = std::fabs(residual);  // eq. 21
  if (delta <= threshold) return 1.0F;      // eq. 22-23, LOS
  return beta * delta / threshold;          // eq. 23, NLOS
}

}  // namespace uwbnav
