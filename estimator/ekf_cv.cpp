// EKF core: the ranges-only process model (integrated Ornstein-Uhlenbeck
// velocity, the turn-rate and levelling priors, a measured turn about the
// vertical). It runs once per range, not per IMU sample: kept out of
// ekf_core.cpp so that the M4F image builds it for size.
#include <cmath>

#include "estimator/ekf_core.hpp"

namespace uwbnav {
namespace {

constexpr int P = ErrIdx::kPos;
constexpr int V = ErrIdx::kVel;
constexpr int A = ErrIdx::kAtt;
constexpr int BG = ErrIdx::kBg;

}  // namespace

CvStep cv_step(Real dt_s, Real accel_psd, Real tau_s) {
  // Integrated Ornstein-Uhlenbeck velocity (Singer 1970 with white jerk
  // replaced by white acceleration): dv = -v/tau dt + q dW. With b = 1/tau,
  // x = b dt, phi = exp(-x):
  //   q_vv = q^2 (1 - phi^2) / (2b)
  //   q_pv = q^2 (1 - phi)^2 / (2b^2)
  //   q_pp = q^2 (2x - 3 + 4 phi - phi^2) / (2b^3)
  // For small x the closed forms cancel in float (q_pp: terms of order 1 for a
  // result of order x^3; 0.5 % off at x = 0.02 with fused multiply-adds on
  // aarch64): below x = 0.2 their series to O(x^4) is used instead (relative
  // truncation error < 1e-4; the closed forms are within 1e-4 above it).
  CvStep st;
  const Real qa = accel_psd * accel_psd;
  const Real dt = std::fmax(dt_s, Real(0));
  const Real tau = tau_s > Real(0) && std::isfinite(tau_s) ? tau_s : Real(0);
  const Real x = tau > Real(0) ? dt / tau : Real(0);
  const Real dt2 = dt * dt;
  if (x < Real(0.2)) {
    st.f_vv = Real(1) - x * (Real(1) - x * (Real(0.5) - x * (Real(1) / Real(6) - x * (Real(1) / Real(24) - x / Real(120)))));
    st.f_pv = dt * (Real(1) - x * (Real(0.5) - x * (Real(1) / Real(6) - x * (Real(1) / Real(24) - x / Real(120)))));
    st.q_vv = qa * dt * (Real(1) - x * (Real(1) - x * (Real(2) / Real(3) - x * (Real(1) / Real(3) - x * Real(2) / Real(15)))));
    st.q_pv = qa * dt2 * Real(0.5) * (Real(1) - x * (Real(1) - x * (Real(7) / Real(12) - x * (Real(0.25) - x * Real(31) / Real(360)))));
    st.q_pp = qa * dt2 * dt / Real(3) * (Real(1) - x * (Real(0.75) - x * (Real(0.35) - x * (Real(0.125) - x * Real(0.036904762)))));
    return st;
  }
  const Real phi = std::exp(-x);
  st.f_vv = phi;
  st.f_pv = tau * (Real(1) - phi);
  st.q_vv = qa * tau * Real(0.5) * (Real(1) - phi * phi);
  st.q_pv = qa * tau * tau * Real(0.5) * (Real(1) - phi) * (Real(1) - phi);
  st.q_pp = qa * tau * tau * tau * Real(0.5) * (Real(2) * x - Real(3) + Real(4) * phi - phi * phi);
  return st;
}

void EkfCore::predict_cv(Real dt_s, Real accel_psd, Real yaw_psd, Real vel_tau_s, Real turn_psd, Real turn_rad) {
  // Half the turn before the position step and half after (midpoint): the
  // sin_cos of a quarter of it is the quaternion's half angle.
  SinCos quarter{Real(0), Real(1)};
  if (turn_rad != Real(0)) {
    quarter = sin_cos(Real(0.25) * turn_rad);
    rotate_vertical(quarter);
  }
  if (turn_psd > Real(0) && dt_s > Real(0)) {
    // Turn rate: attitude and gyro bias blocks of predict_imu with a zero
    // gyro reading (w = -b_g; Phi_att,bg = -C dt), independent of (p, v).
    // Only b_g,z carries variance here (cv_start_turn_rate), so Phi_att,bg
    // reduces to its third column: row and column updates with one vector.
    x_.q_nav_body = quat_normalised(quat_mul(x_.q_nav_body, quat_exp(x_.bg_body_radps * (-dt_s))));
    // Plain loops (not Eigen row expressions, which unroll over the whole
    // state and cost flash on the M4F): all rows first, then all columns.
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < kN; ++k) p_(A + i, k) -= dt_s * c_nav_body_(i, 2) * p_(BG + 2, k);
    }
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < kN; ++k) p_(k, A + i) -= dt_s * c_nav_body_(i, 2) * p_(k, BG + 2);
    }
    p_(BG + 2, BG + 2) += turn_psd * turn_psd * dt_s;
    refresh_dcm();
  }
  const CvStep st = cv_step(dt_s, accel_psd, vel_tau_s);
  for (int i = 0; i < 3; ++i) {
    x_.pos_nav_m(i) += x_.vel_nav_mps(i) * st.f_pv;
    x_.vel_nav_mps(i) *= st.f_vv;
  }
  p_(A + 2, A + 2) += yaw_psd * yaw_psd * dt_s;
  // P <- F P F^T with F = [I f_pv I; 0 f_vv I] on (p, v): rows, then columns.
  // (Plain loops: see the turn-rate block.)
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < kN; ++k) {
      p_(P + i, k) += st.f_pv * p_(V + i, k);
      p_(V + i, k) *= st.f_vv;
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < kN; ++k) {
      p_(k, P + i) += st.f_pv * p_(k, V + i);
      p_(k, V + i) *= st.f_vv;
    }
  }
  for (int i = 0; i < 3; ++i) {
    p_(P + i, P + i) += st.q_pp;
    p_(P + i, V + i) += st.q_pv;
    p_(V + i, P + i) += st.q_pv;
    p_(V + i, V + i) += st.q_vv;
  }
  if (turn_rad != Real(0)) rotate_vertical(quarter);
}

void EkfCore::predict_level(Real dt_s, Real sigma_rad, Real tau_s) {
  if (!(dt_s > Real(0)) || !(tau_s > Real(0))) return;
  const Real phi = std::exp(-dt_s / tau_s);
  // Axis e_z x z_body of the tilt (z_body: the body z axis in nav, column 2).
  const Real ax = -c_nav_body_(1, 2);
  const Real ay = c_nav_body_(0, 2);
  const Real s = std::sqrt(ax * ax + ay * ay);
  if (s > Real(1e-9)) {
    // Left multiplication = nav-frame rotation, as the attitude error.
    const Real k = -(Real(1) - phi) * std::atan2(s, c_nav_body_(2, 2)) / s;
    x_.q_nav_body = quat_normalised(quat_mul(quat_exp(Vec3(ax * k, ay * k, Real(0))), x_.q_nav_body));
    refresh_dcm();
  }
  const Real q = sigma_rad * sigma_rad * (Real(1) - phi * phi);
  for (int i = 0; i < 2; ++i) {
    scale_row_col(A + i, phi);
    p_(A + i, A + i) += q;
  }
}

void EkfCore::rotate_vertical(const SinCos& half) {
  // A known rotation R about nav z moves the nav-frame errors with the
  // vectors: R q_true = Exp(R dtheta) R q (global attitude error, Sola 2017,
  // "Quaternion kinematics for the error-state Kalman filter", sec. 7.3), so
  // F = R on (dv_x, dv_y) and (dtheta_x, dtheta_y), and nothing is added.
  // q <- (cos h, 0, 0, sin h) q rotates the pairs (w, z) and (x, y) of q by
  // the half angle h; scalar kept non-negative as quat_normalised does.
  Quat& q = x_.q_nav_body;
  rotate_xy(q(0), q(3), half);
  rotate_xy(q(1), q(2), half);
  if (q(0) < Real(0)) q = -q;
  const SinCos sc{Real(2) * half.sin * half.cos, half.cos * half.cos - half.sin * half.sin};
  rotate_xy(x_.vel_nav_mps.x(), x_.vel_nav_mps.y(), sc);
  // Rows of both pairs, then columns (plain loops: see predict_cv).
  for (int i = V; i <= A; i += A - V) {
    for (int k = 0; k < kN; ++k) rotate_xy(p_(i, k), p_(i + 1, k), sc);
  }
  for (int i = V; i <= A; i += A - V) {
    for (int k = 0; k < kN; ++k) rotate_xy(p_(k, i), p_(k, i + 1), sc);
  }
  refresh_dcm();
}

}  // namespace uwbnav
