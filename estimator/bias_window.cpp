// Covariance-matching ratio of one learning window of the IMU bias instability
// (estimator/bias_window.hpp, docs/ekf.md "Learned bias instability").
#include "estimator/bias_window.hpp"

#include <cmath>

namespace uwbnav {

Real BiasWindow::ratio(Bias which, const NominalState& x, const ErrCov& p, Real rw, Real ratio_max,
                       const TiltTally& tilt) const {
  const Vec3& b = which == kGyro ? x.bg_body_radps : x.ba_body_mps2;
  const int first = which == kGyro ? ErrIdx::kBg : ErrIdx::kBa;
  Real sum = Real(0);
  int axes = 0;
  // Axes 0-2: the bias; 3-4 (gyro only): the tilt.
  const int n = which == kGyro ? 5 : 3;
  for (int i = 0; i < n; ++i) {
    Real d, var, least;
    if (i < 3) {
      d = b(i) - b0_[which](i);
      const Real prior = p0_[which](i) + rw * rw * predicted_s_;
      var = prior - p(first + i, first + i);
      // An axis the updates hardly touched (less than 0.1 % of its variance
      // removed) carries no evidence either way.
      least = Real(1e-3) * prior;
    } else {
      // A sum of removed variances (each >= 0): no cancellation, any
      // positive sum is evidence.
      d = tilt.correction_sum_rad(i - 3);
      var = tilt.removed_var_rad2(i - 3);
      least = Real(0);
    }
    if (!(var > least)) continue;
    const Real r = d * d / var;
    if (!std::isfinite(r)) continue;
    sum += std::fmin(r, ratio_max);
    ++axes;
  }
  return axes > 0 ? sum / static_cast<Real>(axes) : Real(-1);
}

}  // namespace uwbnav
