// Gaussian-sum yaw estimator (after ArduPilot's EKF-GSF yaw estimator): one
// 7-state EKF per yaw hypothesis, Gaussian-sum weights from the range
// likelihoods (docs/ekf.md "Heading without a heading source").
#include "estimator/yaw_gsf.hpp"

#include <cmath>

#include "estimator/trig.hpp"

namespace uwbnav {
namespace {

constexpr Real kTwoPi = Real(2) * kPi;
// Normalised innovation squared beyond which a range is treated as an outlier
// for the model: its likelihood is clipped (one NLOS range cannot decide
// between hypotheses) and its R inflated so the update stays bounded.
constexpr Real kNisClip = Real(9);
// Smallest weight kept: a hypothesis penalised by a few bad ranges can recover.
constexpr Real kMinWeight = Real(1e-4);
// Weights change only while the vehicle moves faster than this: at rest the
// yaw only turns the lever arm, and the models differ merely in how well their
// seed happened to fit the (noisy) first fix [m/s].
constexpr Real kMinWeightSpeed_mps = Real(0.3);

// d(Rz(psi) x)/d(psi) = e_z x (Rz(psi) x).
Vec3 dyaw(const Vec3& rotated) { return Vec3(-rotated.y(), rotated.x(), Real(0)); }

Vec3 rot_z(Real psi, const Vec3& x) {
  Vec3 r = x;
  rotate_xy(r.x(), r.y(), sin_cos(psi));
  return r;
}

}  // namespace

void YawGsf::reset() {
  active_ = false;
  updates_ = 0;
  dv_lvl_.setZero();
  dp_lvl_.setZero();
  t_acc_s_ = Real(0);
}

void YawGsf::start(const Vec3& tag_pos_nav_m, const Vec3& lever_lvl_m, Real yaw0_rad, Real pos_sigma_h_m,
                   Real pos_sigma_v_m, Real vel_sigma_mps) {
  reset();
  const Real yaw_sigma = kPi / static_cast<Real>(kModels);
  for (int k = 0; k < kModels; ++k) {
    const Real psi = wrap_pi(yaw0_rad + kTwoPi * static_cast<Real>(k) / static_cast<Real>(kModels));
    x_[k].setZero();
    x_[k].head<3>() = tag_pos_nav_m - rot_z(psi, lever_lvl_m);
    x_[k](6) = psi;
    p_[k].setZero();
    p_[k](0, 0) = pos_sigma_h_m * pos_sigma_h_m;
    p_[k](1, 1) = pos_sigma_h_m * pos_sigma_h_m;
    p_[k](2, 2) = pos_sigma_v_m * pos_sigma_v_m;
    for (int i = 3; i < 6; ++i) p_[k](i, i) = vel_sigma_mps * vel_sigma_mps;
    p_[k](6, 6) = yaw_sigma * yaw_sigma;
    w_[k] = Real(1) / static_cast<Real>(kModels);
  }
  active_ = true;
}

void YawGsf::accumulate(const Vec3& f_lvl_mps2, Real dt_s) {
  if (!active_) return;
  // Exact double integral of a piecewise-constant specific force.
  dp_lvl_ += dv_lvl_ * dt_s + f_lvl_mps2 * (Real(0.5) * dt_s * dt_s);
  dv_lvl_ += f_lvl_mps2 * dt_s;
  t_acc_s_ += dt_s;
}

void YawGsf::propagate(Real gravity_mps2, const Noise& noise) {
  if (!active_ || !(t_acc_s_ > Real(0))) return;
  const Real t = t_acc_s_;
  const Real qa = noise.accel_psd * noise.accel_psd;
  for (int k = 0; k < kModels; ++k) {
    Vec7& x = x_[k];
    Mat7& p = p_[k];
    const Real psi = x(6);
    const Vec3 dv = rot_z(psi, dv_lvl_);
    const Vec3 dp = rot_z(psi, dp_lvl_);
    // v+ = v + Rz dv - g e_z t;  p+ = p + v t + Rz dp - g e_z t^2 / 2.
    x.head<3>() += x.segment<3>(3) * t + dp;
    x(2) -= Real(0.5) * gravity_mps2 * t * t;
    x.segment<3>(3) += dv;
    x(5) -= gravity_mps2 * t;
    // F = [I, I t, dRz/dpsi dp; 0, I, dRz/dpsi dv; 0, 0, 1]: P <- F P F^T by block rows/columns.
    const Vec3 jp = dyaw(dp);
    const Vec3 jv = dyaw(dv);
    p.middleRows<3>(0) += t * p.middleRows<3>(3) + jp * p.row(6);
    p.middleRows<3>(3) += jv * p.row(6);
    p.middleCols<3>(0) += t * p.middleCols<3>(3) + p.col(6) * jp.transpose();
    p.middleCols<3>(3) += p.col(6) * jv.transpose();
    for (int i = 0; i < 3; ++i) {
      p(i, i) += qa * t * t * t / Real(3);
      p(i, 3 + i) += qa * t * t * Real(0.5);
      p(3 + i, i) += qa * t * t * Real(0.5);
      p(3 + i, 3 + i) += qa * t;
    }
    p(6, 6) += noise.yaw_psd * noise.yaw_psd * t;
    p = (Real(0.5) * (p + p.transpose())).eval();
  }
  dv_lvl_.setZero();
  dp_lvl_.setZero();
  t_acc_s_ = Real(0);
}

bool YawGsf::update_range(const Vec3& anchor_nav_m, const Vec3& lever_lvl_m, Real range_m, Real sigma_m) {
  if (!active_) return false;
  Real lik[kModels];
  bool usable = true;
  for (int k = 0; k < kModels && usable; ++k) {
    const Vec3 lev = rot_z(x_[k](6), lever_lvl_m);
    const Vec3 d = x_[k].head<3>() + lev - anchor_nav_m;
    usable = d.norm() > Real(1e-3);
  }
  if (!usable) return false;
  const Real r = sigma_m * sigma_m;
  for (int k = 0; k < kModels; ++k) {
    Vec7& x = x_[k];
    Mat7& p = p_[k];
    const Vec3 lev = rot_z(x(6), lever_lvl_m);
    const Vec3 d = x.head<3>() + lev - anchor_nav_m;
    const Real dist = d.norm();
    const Vec3 u = d / dist;
    Eigen::Matrix<Real, 1, kN> h = Eigen::Matrix<Real, 1, kN>::Zero();
    h.head<3>() = u.transpose();
    h(6) = u.dot(dyaw(lev));
    const Vec7 pht = p * h.transpose();
    const Real hph = h.dot(pht);
    const Real innov = range_m - dist;
    Real s = hph + r;
    const Real nis = innov * innov / s;
    // Outlier for this model: clipped likelihood, inflated R (bounded update).
    if (nis > kNisClip) s *= nis / kNisClip;
    // Gaussian likelihood up to a common factor (clipped NIS keeps it above exp(-4.5)/sqrt(S)).
    lik[k] = std::exp(-Real(0.5) * std::fmin(nis, kNisClip)) / std::sqrt(s);
    const Vec7 gain = pht / s;
    x += gain * innov;
    x(6) = wrap_pi(x(6));
    p -= gain * pht.transpose();
    p = (Real(0.5) * (p + p.transpose())).eval();
  }
  Real speed = Real(0);
  for (int k = 0; k < kModels; ++k) speed += w_[k] * x_[k].segment<2>(3).norm();
  if (speed < kMinWeightSpeed_mps) return true;
  // Weights: w_k <- w_k l_k, normalised, floored (the floor keeps the products in range).
  Real sum = Real(0);
  for (int k = 0; k < kModels; ++k) {
    w_[k] *= lik[k];
    sum += w_[k];
  }
  if (!(sum > Real(0)) || !std::isfinite(sum)) return true;
  Real sum2 = Real(0);
  for (int k = 0; k < kModels; ++k) {
    w_[k] = std::fmax(w_[k] / sum, kMinWeight);
    sum2 += w_[k];
  }
  for (int k = 0; k < kModels; ++k) w_[k] /= sum2;
  ++updates_;
  return true;
}

}  // namespace uwbnav
