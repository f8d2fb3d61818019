// Error-state EKF core: nominal-state propagation from IMU samples (or a
// constant-velocity model without IMU), sparse covariance propagation,
// sequential scalar updates with error injection, and covariance hygiene.
// Static memory only; scratch matrices are members.
#pragma once

#include "estimator/ekf_state.hpp"

namespace uwbnav {

// Continuous-time noise densities of the IMU (params 100-103).
struct ImuNoise {
  Real accel_noise = Real(2e-3);     // [m/s^2/sqrt(Hz)]
  Real gyro_noise = Real(2.9e-5);    // [rad/s/sqrt(Hz)]
  Real accel_bias_rw = Real(1e-4);   // [m/s^3/sqrt(Hz)]
  Real gyro_bias_rw = Real(1e-5);    // [rad/s^2/sqrt(Hz)]
};

// One step of the ranges-only velocity model per nav axis: integrated
// Ornstein-Uhlenbeck velocity (Singer-type, mean-reverting with time constant
// tau_s, white acceleration of density q), exact discretisation:
//   p <- p + f_pv v,   v <- f_vv v,   f_vv = exp(-dt/tau), f_pv = tau (1 - f_vv)
// and the process noise q_pp, q_pv, q_vv of that step. tau -> infinity gives
// the constant-velocity model (dt, q dt^3/3, q dt^2/2, q dt); so does tau <= 0.
struct CvStep {
  Real f_pv = Real(0);  // [s]
  Real f_vv = Real(1);  // [-]
  Real q_pp = Real(0);  // [m^2]
  Real q_pv = Real(0);  // [m^2/s]
  Real q_vv = Real(0);  // [m^2/s^2]
};
CvStep cv_step(Real dt_s, Real accel_psd, Real tau_s);

// One scalar measurement linearised about the nominal state.
struct ScalarObs {
  ErrRow h = ErrRow::Zero();  // d(measurement)/d(error state)
  Real innovation = Real(0);  // measured - predicted
  Real r_var = Real(1);       // measurement variance
};

// Outcome of one scalar update.
struct UpdateResult {
  Real innovation_var = Real(0);  // S = H P H^T + R
  bool applied = false;           // false: S not positive/finite or a variance would go negative
};

class EkfCore {
 public:
  EkfCore();

  // Starts from `x` with a diagonal covariance of the given 1-sigmas.
  void init(const NominalState& x, const ErrVec& sigma);

  // One IMU interval of dt_s between two samples (trapezoid of the two
  // samples' rates and specific forces is done by the caller: pass the means).
  // Attitude: exact quaternion exponential of the mean rate; velocity: mean
  // specific force rotated with the mid-interval attitude; position: trapezoid.
  void predict_imu(const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps, Real dt_s,
                   Real gravity_mps2, const ImuNoise& noise);

  // Ranges-only velocity model (no IMU): white acceleration of density
  // accel_psd [m/s^2/sqrt(Hz)] in every nav axis, velocity mean-reverting with
  // time constant vel_tau_s (cv_step); the heading walks with yaw_psd
  // [rad/s/sqrt(Hz)]; tilt and accelerometer bias frozen. turn_psd > 0
  // [rad/s^2/sqrt(Hz)] adds the turn rate: the IMU model with a gyro that
  // reads zero, so the body rate is -b_g and b_g,z walks with turn_psd
  // (constant turn rate); turn_psd 0 freezes b_g as well. turn_rad: a
  // measured rotation of the body about nav z over the step (a ground
  // vehicle's gyro; its velocity turns with the body), applied half before
  // and half after the position step (rotate_vertical).
  void predict_cv(Real dt_s, Real accel_psd, Real yaw_psd, Real vel_tau_s, Real turn_psd = Real(0),
                  Real turn_rad = Real(0));

  // Ground vehicle without IMU (nothing measures gravity, and ranges from
  // anchors near the tags' height cannot tell a tilt from a shift of the body
  // origin below the tags): roll and pitch are a first-order Gauss-Markov
  // process about level, stationary 1-sigma sigma_rad, time constant tau_s.
  // The nav-frame tilt of the body z axis shrinks by phi = exp(-dt/tau); the
  // attitude errors x, y get P <- phi^2 P + sigma^2 (1 - phi^2).
  void predict_level(Real dt_s, Real sigma_rad, Real tau_s);

  // Variance of the innovation of `obs` (H P H^T + R).
  Real innovation_variance(const ErrRow& h, Real r_var) const;

  // Two-step form of update() for gated measurements: prepare() caches
  // u = P H^T and returns H P H^T; update_prepared() then fuses with the
  // innovation and R chosen after the gate, without recomputing u.
  Real prepare(const ErrRow& h);
  // P H^T of the last prepare() (the direction of its update's correction).
  const ErrVec& prepared_cov_h() const { return u_; }
  // consider_range_errors: the range-error states are Schmidt "consider"
  // states for this update (their uncertainty enters S and the cross
  // covariances, their values and their own covariance block stay).
  UpdateResult update_prepared(Real innovation, Real r_var, bool consider_range_errors = false);

  // Scalar update and immediate injection into the nominal state. The
  // covariance update is the Joseph form written for a scalar with the optimal
  // gain, P+ = P - u u^T / S with u = P H^T (algebraically identical to
  // (I-KH)P(I-KH)^T + K R K^T), exactly symmetric; refused when it would
  // drive a variance negative. consider_range_errors as in update_prepared().
  UpdateResult update(const ScalarObs& obs, bool consider_range_errors = false);

  // Clamps variances to [floor, ceiling] (row/column scaling keeps P positive
  // semi-definite) and symmetrises (scalar updates keep P exactly symmetric,
  // so callers skip that part after updates). Returns false when P or x is not finite or
  // the state exploded (caller resets).
  bool sanitise(bool symmetrise = true);
  // sanitise() after a prediction: the diagonal every time, the whole matrix
  // (finite, symmetrised) every tenth call.
  bool sanitise_after_predict();

  // Removes the correlation of attitude and IMU biases with the other states
  // and resets their variances to sigma (entering or leaving the
  // constant-velocity mode). Position, velocity and range errors keep theirs.
  void decouple_inertial(const ErrVec& sigma);

  // Adds process noise var to the variance of error state i (range-error
  // random walks driven by geometry and time, applied by the Navigator).
  void add_variance(int i, Real var);
  // Re-lends error state i: nominal value 0, no correlation, variance var.
  void reset_state(int i, Real var);
  // Inflates the variances of error states [first, first + count) to at least
  // var (diagonal addition of the shortfall keeps P positive semi-definite).
  void inflate_to(int first, int count, Real var);

  // Tilt corrections the scalar updates injected since clear_tilt_tally()
  // (TiltTally, ekf_state.hpp; evidence of the learned bias instability).
  const TiltTally& tilt_tally() const { return tilt_tally_; }
  void clear_tilt_tally() { tilt_tally_ = TiltTally{}; }

  const NominalState& state() const { return x_; }
  NominalState& mutable_state() { return x_; }
  const ErrCov& cov() const { return p_; }
  ErrCov& mutable_cov() { return p_; }
  const Mat3& dcm() const { return c_nav_body_; }
  // Refreshes the cached rotation matrix after the attitude was changed outside.
  void refresh_dcm();

 private:
  void inject(const ErrVec& dx);
  // Multiplies row and column i of P by scale (the diagonal entry by scale^2).
  void scale_row_col(int i, Real scale);
  // Known rotation about nav z, given the sin_cos of half its angle, of the
  // horizontal velocity and the attitude (q <- R_z q); P <- F P F^T with F
  // rotating the (v_x, v_y) and the nav-frame (theta_x, theta_y) error pairs.
  void rotate_vertical(const SinCos& half);

  NominalState x_;
  TiltTally tilt_tally_;  // tilt corrections since clear_tilt_tally()
  ErrCov p_;
  Mat3 c_nav_body_;
  // Scratch (a member, not a function static).
  ErrVec u_;      // P H^T
  Real hph_ = Real(0);  // H P H^T of the prepared measurement
  uint32_t predictions_ = 0;  // counts sanitise() after predictions (periodic full check)
};

}  // namespace uwbnav
