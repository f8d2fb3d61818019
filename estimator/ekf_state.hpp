// Error-state layout of the UWB/IMU EKF (seed 003 §2.1 state: position,
// velocity, attitude, accelerometer bias, gyro bias), fixed-size Eigen types
// in the estimator's Real, and small quaternion helpers.
//
// Conventions (written once, used everywhere):
//  - nav frame: the anchors' frame, ENU-like, z up; body frame FLU.
//  - q_nav_body: Hamilton, scalar first, rotates body vectors into nav:
//    v_nav = C(q) v_body, C(q) as seed 003 eq. 6.
//  - attitude error: nav-frame small angle dtheta with
//    q_true = Exp(dtheta) (x) q_nominal, i.e. C_true = (I + [dtheta]x) C.
//  - IMU model: accel_meas = f_true + b_a + noise, gyro_meas = w_true + b_g + noise.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>

#include "estimator/trig.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

// Range-error states beside the inertial core: boards with little RAM build
// with fewer anchor-offset slots (UWBNAV_BIAS_SLOTS, e.g. hal/mps2). A slot is
// lent to an anchor while it is being ranged (least recently used goes first).
#ifndef UWBNAV_BIAS_SLOTS
#define UWBNAV_BIAS_SLOTS 8
#endif
constexpr int kBiasSlots = UWBNAV_BIAS_SLOTS;
static_assert(kBiasSlots >= 3 && kBiasSlots <= static_cast<int>(kMaxAnchors), "anchor offset slots: 3..kMaxAnchors");

// Index of each block of the error state (constexpr table, checked below).
// Inertial core (seed 003 state, error-state form) followed by the
// time-correlated range errors (docs/ekf.md "Range errors"): a common range
// scale error, one offset per tag (antenna delay) and one per anchor slot
// (antenna delay plus the survey error along the line of sight).
struct ErrIdx {
  static constexpr int kPos = 0;    // dp_nav [m]
  static constexpr int kVel = 3;    // dv_nav [m/s]
  static constexpr int kAtt = 6;    // dtheta_nav [rad]
  static constexpr int kBa = 9;     // d b_a (body) [m/s^2]
  static constexpr int kBg = 12;    // d b_g (body) [rad/s]
  static constexpr int kCore = 15;  // size of the inertial core
  static constexpr int kScale = 15;  // d s: range scale error, measured = (1 + s) true [-]
  static constexpr int kTagBias = 16;  // d b_tag, kMaxTags entries [m]
  static constexpr int kAnchorBias = kTagBias + static_cast<int>(kMaxTags);  // d b_slot, kBiasSlots entries [m]
  static constexpr int kSize = kAnchorBias + kBiasSlots;
  static constexpr int kRange = kSize - kCore;  // size of the range-error block
};
static_assert(ErrIdx::kPos + 3 == ErrIdx::kVel && ErrIdx::kVel + 3 == ErrIdx::kAtt &&
                  ErrIdx::kAtt + 3 == ErrIdx::kBa && ErrIdx::kBa + 3 == ErrIdx::kBg &&
                  ErrIdx::kBg + 3 == ErrIdx::kCore,
              "inertial blocks must tile 0..15 without gaps");
static_assert(ErrIdx::kCore == 15, "inertial core is 15 (seed 003 state without the quaternion's redundant component)");
static_assert(ErrIdx::kScale == ErrIdx::kCore && ErrIdx::kTagBias == ErrIdx::kScale + 1 &&
                  ErrIdx::kAnchorBias == ErrIdx::kTagBias + static_cast<int>(kMaxTags) &&
                  ErrIdx::kSize == ErrIdx::kAnchorBias + kBiasSlots,
              "range-error blocks must follow the core without gaps");

constexpr int kN = ErrIdx::kSize;

using Vec2 = Eigen::Matrix<Real, 2, 1>;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Quat = Eigen::Matrix<Real, 4, 1>;  // w, x, y, z (scalar first)
using ErrVec = Eigen::Matrix<Real, kN, 1>;
using ErrRow = Eigen::Matrix<Real, 1, kN>;
using ErrCov = Eigen::Matrix<Real, kN, kN>;
using RangeErrVec = Eigen::Matrix<Real, ErrIdx::kRange, 1>;

// Tilt (nav-frame attitude error x, y) corrections that scalar updates
// injected over a span, and the variance each removed from its P entry
// (u_i^2 / S with u = P H^T): under the model the corrections are zero-mean
// and uncorrelated, so their sum has the summed variance (EkfCore keeps it;
// BiasWindow reads it, docs/ekf.md "Learned bias instability").
struct TiltTally {
  Vec2 correction_sum_rad = Vec2::Zero();  // sum of injected tilt corrections, nav x, y [rad]
  Vec2 removed_var_rad2 = Vec2::Zero();    // sum of the variances the updates removed [rad^2]
};

// Nominal (full) state.
struct NominalState {
  Vec3 pos_nav_m = Vec3::Zero();      // body origin position [m]
  Vec3 vel_nav_mps = Vec3::Zero();    // body origin velocity [m/s]
  Quat q_nav_body = Quat(1, 0, 0, 0); // attitude body -> nav
  Vec3 ba_body_mps2 = Vec3::Zero();   // accelerometer bias [m/s^2]
  Vec3 bg_body_radps = Vec3::Zero();  // gyro bias [rad/s]
  // Range errors, laid out as the error state from ErrIdx::kScale on:
  // scale [-], tag offsets [m], anchor-slot offsets [m].
  RangeErrVec range_err = RangeErrVec::Zero();

  Real range_scale() const { return range_err(0); }
  Real tag_bias_m(int tag_index) const { return range_err(ErrIdx::kTagBias - ErrIdx::kCore + tag_index); }
  Real anchor_bias_m(int slot) const { return range_err(ErrIdx::kAnchorBias - ErrIdx::kCore + slot); }
};

inline Vec3 to_vec3(const Vec3f& v) {
  return Vec3(static_cast<Real>(v.x), static_cast<Real>(v.y), static_cast<Real>(v.z));
}
inline Vec3f to_vec3f(const Vec3& v) {
  return Vec3f{static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

inline Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << Real(0), -v.z(), v.y(), v.z(), Real(0), -v.x(), -v.y(), v.x(), Real(0);
  return m;
}

// Hamilton product a (x) b, scalar first.
inline Quat quat_mul(const Quat& a, const Quat& b) {
  return Quat(a(0) * b(0) - a(1) * b(1) - a(2) * b(2) - a(3) * b(3),
              a(0) * b(1) + a(1) * b(0) + a(2) * b(3) - a(3) * b(2),
              a(0) * b(2) - a(1) * b(3) + a(2) * b(0) + a(3) * b(1),
              a(0) * b(3) + a(1) * b(2) - a(2) * b(1) + a(3) * b(0));
}

// Exact quaternion exponential of a rotation vector (solution of seed 003
// eq. 5 for a constant rate over the step).
inline Quat quat_exp(const Vec3& rotvec_rad) {
  const Real angle = rotvec_rad.norm();
  const Real half = Real(0.5) * angle;
  // sin(x)/x with its series below 1e-4 rad (exact to float precision).
  const SinCos sc = sin_cos(half);
  const Real sinc = angle < Real(1e-4) ? Real(0.5) - angle * angle / Real(48) : sc.sin / angle;
  return Quat(sc.cos, sinc * rotvec_rad.x(), sinc * rotvec_rad.y(), sinc * rotvec_rad.z());
}

inline Quat quat_normalised(const Quat& q) {
  const Real n = q.norm();
  if (!(n > Real(0)) || !std::isfinite(n)) return Quat(1, 0, 0, 0);
  const Quat out = q / n;
  return out(0) < Real(0) ? Quat(-out) : out;  // keep the scalar non-negative
}

// Rotation matrix body -> nav (seed 003 eq. 6).
inline Mat3 quat_to_dcm(const Quat& q) {
  const Real w = q(0), x = q(1), y = q(2), z = q(3);
  Mat3 c;
  c << w * w + x * x - y * y - z * z, Real(2) * (x * y - w * z), Real(2) * (x * z + w * y),
      Real(2) * (x * y + w * z), w * w - x * x + y * y - z * z, Real(2) * (y * z - w * x),
      Real(2) * (x * z - w * y), Real(2) * (y * z + w * x), w * w - x * x - y * y + z * z;
  return c;
}

// Yaw of the body x axis in the nav frame, CCW from nav x (seed 003 eq. 9).
inline Real quat_yaw(const Quat& q) {
  return std::atan2(Real(2) * (q(1) * q(2) + q(0) * q(3)), q(0) * q(0) + q(1) * q(1) - q(2) * q(2) - q(3) * q(3));
}

// (x, y) <- R(angle) (x, y), R = [cos -sin; sin cos], from the angle's sin_cos.
inline void rotate_xy(Real& x, Real& y, const SinCos& sc) {
  const Real x0 = x;
  x = sc.cos * x0 - sc.sin * y;
  y = sc.sin * x0 + sc.cos * y;
}

// Quaternion of a pure rotation about nav z by yaw_rad.
inline Quat quat_from_yaw(Real yaw_rad) {
  const SinCos sc = sin_cos(Real(0.5) * yaw_rad);
  return Quat(sc.cos, Real(0), Real(0), sc.sin);
}

// Roll/pitch-only attitude whose body z axis is along the measured specific
// force (levelling at rest), yaw zero.
inline Quat quat_level(const Vec3& accel_body_mps2) {
  const Real roll = std::atan2(accel_body_mps2.y(), accel_body_mps2.z());
  const Real pitch = std::atan2(-accel_body_mps2.x(), std::sqrt(accel_body_mps2.y() * accel_body_mps2.y() +
                                                                 accel_body_mps2.z() * accel_body_mps2.z()));
  const SinCos r = sin_cos(Real(0.5) * roll);
  const SinCos p = sin_cos(Real(0.5) * pitch);
  const Quat qr(r.cos, r.sin, Real(0), Real(0));
  const Quat qp(p.cos, Real(0), p.sin, Real(0));
  return quat_mul(qp, qr);  // C = Ry(pitch) Rx(roll), yaw 0
}

// pi in the estimator's precision (M_PI is POSIX, not C++17: absent on picolibc).
constexpr Real kPi = static_cast<Real>(3.14159265358979323846);

inline Real wrap_pi(Real a) {
  const Real two_pi = Real(2) * kPi;
  if (!std::isfinite(a)) return Real(0);
  a = std::fmod(a + kPi, two_pi);
  if (a < Real(0)) a += two_pi;
  return a - kPi;
}

}  // namespace uwbnav
