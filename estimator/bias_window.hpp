// One learning window of the IMU bias instability (docs/ekf.md "Learned bias
// instability"): covariance matching (Mehra 1972) of the bias states'
// corrections against the variance the model gave them.
//
// Under the model each scalar update's correction of a bias state is zero-mean
// with variance equal to what the update removes from its P entry, and the
// corrections of successive updates are uncorrelated; predictions leave the
// nominal bias alone (random walk, Phi = I on the bias block, no other state
// feeds it) and add q^2 dt to its variance; a projection of the nominal bias
// (shifted()) is taken out of the sum. Over a window, per axis:
//   sum of corrections        = b_end - b_start
//   their model variance      = P_start + q^2 T - P_end   (T: predicted time)
// so the ratio of the first squared to the second has mean 1 when the bias
// walks as modelled, and grows when it walks faster.
// A gyro bias that walks faster than modelled can also be explained by the
// filter as tilt (nav-frame attitude x, y), whose corrections then add up
// while the bias state's stay within their model: the tilt corrections over
// the window (EkfCore's TiltTally, the same identity: each update's correction
// has the variance it removes) are pooled with the gyro bias axes.
#pragma once

#include "estimator/ekf_state.hpp"

namespace uwbnav {

class BiasWindow {
 public:
  // The two IMU biases of the error state.
  enum Bias : int { kGyro = 0, kAccel = 1 };

  // Starts a window at the current bias estimates and their variances.
  void open(const NominalState& x, const ErrCov& p) {
    b0_[kGyro] = x.bg_body_radps;
    b0_[kAccel] = x.ba_body_mps2;
    p0_[kGyro] = p.diagonal().segment<3>(ErrIdx::kBg);
    p0_[kAccel] = p.diagonal().segment<3>(ErrIdx::kBa);
    predicted_s_ = Real(0);
  }
  void close() { predicted_s_ = Real(-1); }
  // A move of the nominal bias that is no update's correction (the vertical
  // balance's projection, Navigator::hold_rest_force_magnitude): kept out of
  // the window's correction sum.
  void shifted(Bias which, const Vec3& delta) { b0_[which] += delta; }
  bool is_open() const { return predicted_s_ >= Real(0); }
  // One prediction of dt_s with the bias random walks in effect.
  void predicted(Real dt_s) { predicted_s_ += dt_s; }
  // Time predicted since open() [s].
  Real predicted_s() const { return predicted_s_; }

  // Mean over the axes of (correction sum)^2 / model variance for one bias,
  // each axis clipped at ratio_max against single outliers; negative when no
  // axis was updated in the window (nothing to compare). x, p: now; rw: the
  // random-walk density used over the window [unit/s/sqrt(s)].
  // For the gyro, tilt (the window's tilt corrections: the caller clears
  // EkfCore's tally when it opens the window) adds its two axes to the mean;
  // the accelerometer ignores it.
  Real ratio(Bias which, const NominalState& x, const ErrCov& p, Real rw, Real ratio_max,
             const TiltTally& tilt) const;

 private:
  Vec3 b0_[2];                  // bias estimates at open(): gyro [rad/s], accel [m/s^2]
  Vec3 p0_[2];                  // their variances at open() [rad^2/s^2], [m^2/s^4]
  Real predicted_s_ = Real(-1);  // predicted time since open() [s]; negative: closed
};

}  // namespace uwbnav
