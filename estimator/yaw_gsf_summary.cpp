// Summaries of the Gaussian-sum yaw bank (estimator/yaw_gsf.cpp): the mean
// yaw, its sigma and the mixture's position/velocity. Read once per range or
// output while aligning, not per model and sample: a file of its own so that
// boards that build the bank's per-sample code for speed (hal/mps2: -O3)
// build these for size.
#include <cmath>

#include "estimator/trig.hpp"
#include "estimator/yaw_gsf.hpp"

namespace uwbnav {

Real YawGsf::yaw_mean() const {
  Real c = Real(0);
  Real s = Real(0);
  for (int k = 0; k < kModels; ++k) {
    const SinCos sc = sin_cos(x_[k](6));
    c += w_[k] * sc.cos;
    s += w_[k] * sc.sin;
  }
  return std::atan2(s, c);
}

Real YawGsf::yaw_sigma() const {
  const Real mean = yaw_mean();
  Real var = Real(0);
  for (int k = 0; k < kModels; ++k) {
    const Real d = wrap_pi(x_[k](6) - mean);
    var += w_[k] * (p_[k](6, 6) + d * d);
  }
  return std::sqrt(var);
}

void YawGsf::mixture(Vec3& pos_nav_m, Vec3& pos_sigma_m, Vec3& vel_nav_mps, Vec3& vel_sigma_mps) const {
  // The most likely model's state; the spread of the others about it counts
  // in its sigma (averaging hypotheses of different yaw gives no valid state).
  int best = 0;
  for (int k = 1; k < kModels; ++k) {
    if (w_[k] > w_[best]) best = k;
  }
  Vec7 var = Vec7::Zero();
  for (int k = 0; k < kModels; ++k) {
    const Vec7 d = x_[k] - x_[best];
    var += w_[k] * (p_[k].diagonal() + d.cwiseProduct(d));
  }
  pos_nav_m = x_[best].head<3>();
  vel_nav_mps = x_[best].segment<3>(3);
  pos_sigma_m = var.head<3>().cwiseSqrt();
  vel_sigma_mps = var.segment<3>(3).cwiseSqrt();
}

}  // namespace uwbnav
