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
