// Gaussian-sum yaw estimator for initialisation without a heading source: a
// bank of small EKFs (position, velocity, start yaw), one per yaw hypothesis
// spread over the circle, driven by the levelled IMU and weighted by the
// likelihood of each UWB range (after the EKF-GSF yaw estimator of ArduPilot,
// with single ranges instead of GNSS velocity). Static memory only.
#pragma once

#include "estimator/ekf_state.hpp"

namespace uwbnav {

class YawGsf {
 public:
  static constexpr int kModels = 8;
  static constexpr int kN = 7;  // p(3), v(3), start yaw (1)
  using Vec7 = Eigen::Matrix<Real, kN, 1>;
  using Mat7 = Eigen::Matrix<Real, kN, kN>;

  // Noise of the models: white acceleration covering accelerometer noise,
  // bias and tilt errors [m/s^2/sqrt(Hz)]; yaw random walk from gyro noise and
  // bias [rad/sqrt(s)].
  struct Noise {
    Real accel_psd = Real(0.2);
    Real yaw_psd = Real(0.01);
  };

  void reset();
  bool active() const { return active_; }

  // Seeds every model at the body origin below a tag fix: the yaw offset of
  // model k is yaw0 + 2 pi k / kModels (1-sigma pi / kModels), the origin is the
  // tag position minus the rotated (levelled-frame) lever arm.
  void start(const Vec3& tag_pos_nav_m, const Vec3& lever_lvl_m, Real yaw0_rad, Real pos_sigma_h_m,
             Real pos_sigma_v_m, Real vel_sigma_mps);

  // One IMU interval: specific force in the levelled frame (relative yaw), the
  // mean over the interval [m/s^2]. Only accumulated (shared by all models).
  void accumulate(const Vec3& f_lvl_mps2, Real dt_s);
  // Applies the accumulated interval to every model (mean and covariance).
  void propagate(Real gravity_mps2, const Noise& noise);

  // One range of a tag whose lever arm in the levelled frame is lever_lvl_m.
  // Returns false when the range was not usable (tag on the anchor).
  bool update_range(const Vec3& anchor_nav_m, const Vec3& lever_lvl_m, Real range_m, Real sigma_m);

  // Mixture of the models: circular mean of the start yaw and its 1-sigma
  // (spread of the hypotheses included) [rad].
  Real yaw_mean() const;
  Real yaw_sigma() const;
  // Body-origin position and velocity of the most likely model, with 1-sigmas
  // (diagonal) that include the spread of all models about it.
  void mixture(Vec3& pos_nav_m, Vec3& pos_sigma_m, Vec3& vel_nav_mps, Vec3& vel_sigma_mps) const;
  // Ranges that updated the weights (only while moving).
  int updates() const { return updates_; }
  Real weight(int k) const { return w_[k]; }
  Real model_yaw(int k) const { return x_[k](6); }

 private:
  Vec7 x_[kModels];
  Mat7 p_[kModels];
  Real w_[kModels] = {};
  bool active_ = false;
  int updates_ = 0;
  // Accumulated interval in the levelled frame.
  Vec3 dv_lvl_ = Vec3::Zero();  // integral of f dt [m/s]
  Vec3 dp_lvl_ = Vec3::Zero();  // double integral of f [m]
  Real t_acc_s_ = Real(0);
};

}  // namespace uwbnav
