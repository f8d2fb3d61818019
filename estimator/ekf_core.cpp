// Error-state EKF core (seed 003 §2.1-2.2 state and update, error-state form):
// IMU mechanisation, block-sparse covariance propagation, scalar updates.
#include "estimator/ekf_core.hpp"

#include <cmath>

namespace uwbnav {
namespace {

// Variance floors and ceilings per 3-block of the core (1-sigma^2): below a
// floor the filter would stop listening to measurements; above a ceiling
// linearisation is void. Then the range errors: scale, offsets.
constexpr Real kFloorVar[5] = {Real(1e-6), Real(1e-6), Real(1e-9), Real(1e-10), Real(1e-12)};
constexpr Real kCeilVar[5] = {Real(1e6), Real(1e4), Real(4.0), Real(4.0), Real(0.25)};
constexpr Real kFloorVarScale = Real(1e-10);  // (1e-5)^2
constexpr Real kCeilVarScale = Real(1e-4);    // (1 %)^2
constexpr Real kFloorVarOffset = Real(1e-8);  // (0.1 mm)^2 [m^2]
constexpr Real kCeilVarOffset = Real(4.0);    // (2 m)^2 [m^2]
// Range errors beyond these are not an offset any more: the state exploded.
constexpr Real kMaxScale = Real(0.05);
constexpr Real kMaxOffset_m = Real(20);
// The state is declared exploded beyond these magnitudes.
constexpr Real kMaxPos_m = Real(1e6);
constexpr Real kMaxVel_mps = Real(1e3);
constexpr Real kMaxBiasAccel_mps2 = Real(20);
constexpr Real kMaxBiasGyro_radps = Real(2);

// Predictions between full symmetric/finite checks of the covariance.
constexpr uint32_t kFullCheckEvery = 10;

constexpr int P = ErrIdx::kPos;
constexpr int V = ErrIdx::kVel;
constexpr int A = ErrIdx::kAtt;
constexpr int BA = ErrIdx::kBa;
constexpr int BG = ErrIdx::kBg;

}  // namespace

EkfCore::EkfCore() {
  p_.setIdentity();
  c_nav_body_.setIdentity();
  u_.setZero();
}

void EkfCore::init(const NominalState& x, const ErrVec& sigma) {
  x_ = x;
  x_.q_nav_body = quat_normalised(x_.q_nav_body);
  p_.setZero();
  for (int i = 0; i < kN; ++i) p_(i, i) = sigma(i) * sigma(i);
  refresh_dcm();
}

void EkfCore::refresh_dcm() { c_nav_body_ = quat_to_dcm(x_.q_nav_body); }

void EkfCore::predict_imu(const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps, Real dt_s,
                          Real gravity_mps2, const ImuNoise& noise) {
  // Nominal mechanisation (seed 003 eq. 5, 10, 12 with the corrected biases).
  const Vec3 w_body = gyro_mean_body_radps - x_.bg_body_radps;
  const Vec3 f_body = accel_mean_body_mps2 - x_.ba_body_mps2;
  const Quat q_mid = quat_mul(x_.q_nav_body, quat_exp(w_body * (Real(0.5) * dt_s)));
  const Mat3 c_mid = quat_to_dcm(q_mid);
  const Vec3 f_nav = c_mid * f_body;
  Vec3 acc_nav = f_nav;
  acc_nav.z() -= gravity_mps2;
  const Vec3 v_old = x_.vel_nav_mps;
  x_.vel_nav_mps += acc_nav * dt_s;
  x_.pos_nav_m += (v_old + x_.vel_nav_mps) * (Real(0.5) * dt_s);
  x_.q_nav_body = quat_normalised(quat_mul(x_.q_nav_body, quat_exp(w_body * dt_s)));
  refresh_dcm();

  // Transition matrix Phi = I + A dt + A^2 dt^2/2 + A^3 dt^3/6 (seed 003 eq. 14
  // in error-state form; the series terminates: A is nilpotent here). Non-zero
  // off-diagonal blocks only:
  const Real dt2 = dt_s * dt_s;
  const Mat3 fx = skew(f_nav);
  const Mat3 phi_pa = fx * (-Real(0.5) * dt2);
  const Mat3 phi_pba = c_mid * (-Real(0.5) * dt2);
  const Mat3 fxc = fx * c_mid;
  const Mat3 phi_pbg = fxc * (dt2 * dt_s / Real(6));
  const Mat3 phi_va = fx * (-dt_s);
  const Mat3 phi_vba = c_mid * (-dt_s);
  const Mat3 phi_vbg = fxc * (Real(0.5) * dt2);
  const Mat3 phi_abg = c_mid * (-dt_s);

  // P <- Phi P (block rows, in place: each row block only reads rows updated later).
  p_.middleRows<3>(P) += dt_s * p_.middleRows<3>(V) + phi_pa * p_.middleRows<3>(A) +
                         phi_pba * p_.middleRows<3>(BA) + phi_pbg * p_.middleRows<3>(BG);
  p_.middleRows<3>(V) += phi_va * p_.middleRows<3>(A) + phi_vba * p_.middleRows<3>(BA) +
                         phi_vbg * p_.middleRows<3>(BG);
  p_.middleRows<3>(A) += phi_abg * p_.middleRows<3>(BG);
  // P <- (Phi P) Phi^T (block columns, same order).
  p_.middleCols<3>(P) += dt_s * p_.middleCols<3>(V) + p_.middleCols<3>(A) * phi_pa.transpose() +
                         p_.middleCols<3>(BA) * phi_pba.transpose() + p_.middleCols<3>(BG) * phi_pbg.transpose();
  p_.middleCols<3>(V) += p_.middleCols<3>(A) * phi_va.transpose() + p_.middleCols<3>(BA) * phi_vba.transpose() +
                         p_.middleCols<3>(BG) * phi_vbg.transpose();
  p_.middleCols<3>(A) += p_.middleCols<3>(BG) * phi_abg.transpose();

  // Q: white accel noise integrated into v and p, white gyro noise into the
  // attitude, random walks into the biases (isotropic, so frame-free).
  const Real qa = noise.accel_noise * noise.accel_noise;
  const Real qg = noise.gyro_noise * noise.gyro_noise;
  const Real qba = noise.accel_bias_rw * noise.accel_bias_rw * dt_s;
  const Real qbg = noise.gyro_bias_rw * noise.gyro_bias_rw * dt_s;
  for (int i = 0; i < 3; ++i) {
    p_(P + i, P + i) += qa * dt2 * dt_s / Real(3);
    p_(P + i, V + i) += qa * dt2 * Real(0.5);
    p_(V + i, P + i) += qa * dt2 * Real(0.5);
    p_(V + i, V + i) += qa * dt_s;
    p_(A + i, A + i) += qg * dt_s;
    p_(BA + i, BA + i) += qba;
    p_(BG + i, BG + i) += qbg;
  }
}

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

void EkfCore::predict_cv(Real dt_s, Real accel_psd, Real yaw_psd, Real vel_tau_s, Real turn_psd) {
  if (turn_psd > Real(0) && dt_s > Real(0)) {
    // Turn rate: attitude and gyro bias blocks of predict_imu with a zero
    // gyro reading (w = -b_g; Phi_att,bg = -C dt), independent of (p, v).
    // Only b_g,z carries variance here (cv_start_turn_rate), so Phi_att,bg
    // reduces to its third column: row and column updates with one vector.
    const Vec3 w_body = -x_.bg_body_radps;
    x_.q_nav_body = quat_normalised(quat_mul(x_.q_nav_body, quat_exp(w_body * dt_s)));
    const Vec3 phi_z = c_nav_body_.col(2) * (-dt_s);
    // Plain loops (not Eigen row expressions, which unroll over the whole
    // state and cost flash on the M4F): all rows first, then all columns.
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < kN; ++k) p_(A + i, k) += phi_z(i) * p_(BG + 2, k);
    }
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < kN; ++k) p_(k, A + i) += phi_z(i) * p_(k, BG + 2);
    }
    p_(BG + 2, BG + 2) += turn_psd * turn_psd * dt_s;
    refresh_dcm();
  }
  const CvStep st = cv_step(dt_s, accel_psd, vel_tau_s);
  x_.pos_nav_m += x_.vel_nav_mps * st.f_pv;
  x_.vel_nav_mps *= st.f_vv;
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
}

void EkfCore::predict_level(Real dt_s, Real sigma_rad, Real tau_s) {
  if (!(dt_s > Real(0)) || !(tau_s > Real(0))) return;
  const Real phi = std::exp(-dt_s / tau_s);
  const Vec3 z_body_nav = c_nav_body_.col(2);
  const Vec3 axis(-z_body_nav.y(), z_body_nav.x(), Real(0));  // e_z x z_body
  const Real s = axis.norm();
  if (s > Real(1e-9)) {
    // Left multiplication = nav-frame rotation, as the attitude error.
    const Real tilt = std::atan2(s, z_body_nav.z());
    x_.q_nav_body = quat_normalised(quat_mul(quat_exp(axis * (-(Real(1) - phi) * tilt / s)), x_.q_nav_body));
    refresh_dcm();
  }
  const Real q = sigma_rad * sigma_rad * (Real(1) - phi * phi);
  for (int i = 0; i < 2; ++i) {
    scale_row_col(A + i, phi);
    p_(A + i, A + i) += q;
  }
}

void EkfCore::scale_row_col(int i, Real scale) {
  // Row and column i of P times scale (the diagonal entry twice: scale^2).
  for (int k = 0; k < kN; ++k) {
    p_(i, k) *= scale;
    p_(k, i) *= scale;
  }
}

Real EkfCore::innovation_variance(const ErrRow& h, Real r_var) const {
  return h.dot(p_.lazyProduct(h.transpose())) + r_var;
}

Real EkfCore::prepare(const ErrRow& h) {
  // Coefficient-wise product: fixed size, no blocked GEMV path (no temporaries).
  u_.noalias() = p_.lazyProduct(h.transpose());
  hph_ = h.dot(u_);
  return hph_;
}

UpdateResult EkfCore::update(const ScalarObs& obs, bool consider_range_errors) {
  (void)prepare(obs.h);
  return update_prepared(obs.innovation, obs.r_var, consider_range_errors);
}

UpdateResult EkfCore::update_prepared(Real innovation, Real r_var, bool consider_range_errors) {
  UpdateResult res;
  const Real s = hph_ + r_var;
  res.innovation_var = s;
  if (!(s > Real(0)) || !std::isfinite(s) || !std::isfinite(innovation)) return res;
  const Real inv_s = Real(1) / s;
  const int n_est = consider_range_errors ? ErrIdx::kCore : kN;
  for (int i = 0; i < n_est; ++i) {
    if (p_(i, i) - u_(i) * u_(i) * inv_s < Real(0)) return res;  // ArduPilot-style refusal
  }
  // Joseph form with the optimal scalar gain K = u / S (see header).
  p_.noalias() -= (u_ * inv_s) * u_.transpose();
  if (consider_range_errors) {
    // Schmidt-Kalman: K is zero on the consider states. With a scalar update the
    // Joseph form (I-KH)P(I-KH)^T + K R K^T then differs from the optimal one
    // only in the consider-consider block, which keeps its prior value.
    p_.bottomRightCorner<ErrIdx::kRange, ErrIdx::kRange>().noalias() +=
        (u_.tail<ErrIdx::kRange>() * inv_s) * u_.tail<ErrIdx::kRange>().transpose();
    u_.tail<ErrIdx::kRange>().setZero();
  }
  const Real gain = innovation * inv_s;  // K = u / S, so dx = u * innovation / S
  inject(u_ * gain);
  for (int i = 0; i < 2; ++i) {
    tilt_tally_.correction_sum_rad(i) += u_(A + i) * gain;
    tilt_tally_.removed_var_rad2(i) += u_(A + i) * u_(A + i) * inv_s;
  }
  res.applied = true;
  return res;
}

void EkfCore::inject(const ErrVec& dx) {
  x_.pos_nav_m += dx.segment<3>(P);
  x_.vel_nav_mps += dx.segment<3>(V);
  x_.q_nav_body = quat_normalised(quat_mul(quat_exp(dx.segment<3>(A)), x_.q_nav_body));
  x_.ba_body_mps2 += dx.segment<3>(BA);
  x_.bg_body_radps += dx.segment<3>(BG);
  x_.range_err += dx.tail<ErrIdx::kRange>();
  refresh_dcm();
}

bool EkfCore::sanitise(bool symmetrise) {
  // After a scalar update a NaN would show on the diagonal (u u^T / S): check
  // the diagonal only; after a prediction check the whole matrix.
  const bool p_finite = symmetrise ? p_.allFinite() : p_.diagonal().allFinite();
  if (!p_finite || !x_.pos_nav_m.allFinite() || !x_.vel_nav_mps.allFinite() || !x_.q_nav_body.allFinite() ||
      !x_.ba_body_mps2.allFinite() || !x_.bg_body_radps.allFinite()) {
    return false;
  }
  if (x_.pos_nav_m.cwiseAbs().maxCoeff() > kMaxPos_m || x_.vel_nav_mps.norm() > kMaxVel_mps ||
      x_.ba_body_mps2.norm() > kMaxBiasAccel_mps2 || x_.bg_body_radps.norm() > kMaxBiasGyro_radps ||
      !x_.range_err.allFinite() || std::fabs(x_.range_scale()) > kMaxScale ||
      x_.range_err.tail<ErrIdx::kRange - 1>().cwiseAbs().maxCoeff() > kMaxOffset_m) {
    return false;
  }
  for (int i = 0; i < kN; ++i) {
    Real floor_var, ceil_var;
    if (i < ErrIdx::kCore) {
      floor_var = kFloorVar[i / 3];
      ceil_var = kCeilVar[i / 3];
    } else if (i == ErrIdx::kScale) {
      floor_var = kFloorVarScale;
      ceil_var = kCeilVarScale;
    } else {
      floor_var = kFloorVarOffset;
      ceil_var = kCeilVarOffset;
    }
    const Real d = p_(i, i);
    if (d > ceil_var) {
      scale_row_col(i, std::sqrt(ceil_var / d));
    } else if (d < floor_var) {
      p_(i, i) = floor_var;
    }
  }
  // Symmetrise (predict accumulates tiny asymmetries from the block products),
  // in place: each off-diagonal pair is read before either element is written.
  if (symmetrise) {
    for (int r = 0; r < kN; ++r) {
      for (int c = r + 1; c < kN; ++c) {
        const Real m = Real(0.5) * (p_(r, c) + p_(c, r));
        p_(r, c) = m;
        p_(c, r) = m;
      }
    }
  }
  return true;
}

bool EkfCore::sanitise_after_predict() {
  // The block products leave asymmetries of a few ulp per step and a NaN
  // anywhere reaches the diagonal at the next prediction or update: the whole
  // matrix is checked and symmetrised every kFullCheckEvery-th prediction.
  ++predictions_;
  return sanitise(predictions_ % kFullCheckEvery == 0);
}

void EkfCore::decouple_inertial(const ErrVec& sigma) {
  constexpr int kInertial = ErrIdx::kCore - A;  // attitude and IMU biases
  p_.middleRows<kInertial>(A).setZero();
  p_.middleCols<kInertial>(A).setZero();
  for (int i = A; i < ErrIdx::kCore; ++i) p_(i, i) = sigma(i) * sigma(i);
}

void EkfCore::add_variance(int i, Real var) {
  if (i < 0 || i >= kN || !(var > Real(0)) || !std::isfinite(var)) return;
  p_(i, i) += var;
}

void EkfCore::reset_state(int i, Real var) {
  if (i < 0 || i >= kN) return;
  p_.row(i).setZero();
  p_.col(i).setZero();
  p_(i, i) = var;
  if (i >= ErrIdx::kCore) x_.range_err(i - ErrIdx::kCore) = Real(0);
}

void EkfCore::inflate_to(int first, int count, Real var) {
  for (int i = first; i < first + count && i < kN; ++i) {
    if (i >= 0 && p_(i, i) < var) p_(i, i) = var;
  }
}

}  // namespace uwbnav
