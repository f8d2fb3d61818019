// RbfBridge: standalone-INS shadows, on-line training of the RBF network on
// their drift while UWB is fused, and the outage pseudo-measurement (seed 004
// §2.2-2.3, fig. 3).
#include "estimator/rbf_bridge.hpp"

#include <cmath>

namespace uwbnav {
namespace {

// Input scales: the centre grid below is one unit apart in every input.
constexpr Real kTauScale_s = Real(10);
constexpr Real kSpeedScale_mps = Real(7.5);
// Training sample period of each shadow [us].
constexpr uint64_t kSamplePeriodUs = 500000;
// A training window is valid only while ranges keep being fused this often:
// the filter it learns from must not be coasting itself [us].
constexpr uint64_t kFreshUs = 500000;
// An IMU gap longer than this breaks every shadow [us].
constexpr uint64_t kMaxImuGapUs = 100000;

uint64_t window_us() { return static_cast<uint64_t>(RbfBridge::kWindowS * Real(1e6)); }

// Fixed-capacity centre scheme: a grid, 4 times (0, 10, 20, 30 s) x 2 start
// speeds (1.9, 9.4 m/s) x 2 heading changes (-90, +90 deg), in input units.
RbfNet::Centres grid_centres() {
  RbfNet::Centres c;
  int k = 0;
  for (int it = 0; it < 4; ++it) {
    for (int iv = 0; iv < 2; ++iv) {
      for (int ip = 0; ip < 2; ++ip) {
        c(0, k) = static_cast<Real>(it);
        c(1, k) = Real(0.25) + static_cast<Real>(iv);
        c(2, k) = Real(-0.5) + static_cast<Real>(ip);
        ++k;
      }
    }
  }
  return c;
}

}  // namespace

RbfBridge::RbfBridge() {
  static_assert(RbfNet::kCentres == 16, "grid_centres() fills 4 x 2 x 2 centres");
  net_.configure(grid_centres(), Real(0), RbfNet::Settings{});
}

void RbfBridge::configure(RbfMode mode) {
  if (mode != mode_) reset();
  mode_ = mode;
}

void RbfBridge::reset() {
  net_.reset();
  restart_shadows();
  diag_ = RbfBridgeDiag{};
}

void RbfBridge::restart_shadows() {
  for (Shadow& s : train_) s.active = false;
  outage_.active = false;
  last_window_start_us_ = 0;
}

RbfNet::Input RbfBridge::inputs(Real tau_s, Real speed0_mps, Real dyaw_rad) {
  return RbfNet::Input(tau_s / kTauScale_s, speed0_mps / kSpeedScale_mps, wrap_pi(dyaw_rad) / kPi);
}

void RbfBridge::start(Shadow& s, uint64_t t_us, const NominalState& filter) {
  s.pos_nav_m = filter.pos_nav_m;
  s.vel_nav_mps = filter.vel_nav_mps;
  s.q_nav_body = filter.q_nav_body;
  s.ba_body_mps2 = filter.ba_body_mps2;
  s.bg_body_radps = filter.bg_body_radps;
  s.t0_us = t_us;
  s.next_sample_us = t_us + kSamplePeriodUs;
  s.yaw0_rad = quat_yaw(filter.q_nav_body);
  s.speed0_mps = filter.vel_nav_mps.head<2>().norm();
  s.active = true;
}

void RbfBridge::integrate(Shadow& s, const Vec3& f_body, const Vec3& w_body, Real dt_s, Real gravity_mps2) {
  // EkfCore::predict_imu's nominal mechanisation (seed 003 eq. 5, 10), no corrections.
  const Vec3 w = w_body - s.bg_body_radps;
  const Vec3 f = f_body - s.ba_body_mps2;
  const Quat q_mid = quat_mul(s.q_nav_body, quat_exp(w * (Real(0.5) * dt_s)));
  Vec3 acc = quat_to_dcm(q_mid) * f;
  acc.z() -= gravity_mps2;
  const Vec3 v_old = s.vel_nav_mps;
  s.vel_nav_mps += acc * dt_s;
  s.pos_nav_m += (v_old + s.vel_nav_mps) * (Real(0.5) * dt_s);
  s.q_nav_body = quat_normalised(quat_mul(s.q_nav_body, quat_exp(w * dt_s)));
}

RbfNet::Input RbfBridge::shadow_inputs(const Shadow& s, uint64_t t_us) const {
  const Real tau = static_cast<Real>(t_us - s.t0_us) * Real(1e-6);
  return inputs(tau, s.speed0_mps, quat_yaw(s.q_nav_body) - s.yaw0_rad);
}

void RbfBridge::on_imu(uint64_t t_us, const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps, Real dt_s,
                       Real gravity_mps2, const NominalState& filter, uint64_t last_fix_us) {
  if (mode_ == RbfMode::kOff) return;
  if (last_imu_us_ != 0 && (t_us <= last_imu_us_ || t_us - last_imu_us_ > kMaxImuGapUs)) restart_shadows();
  last_imu_us_ = t_us;
  if (outage_.active) integrate(outage_, accel_mean_body_mps2, gyro_mean_body_radps, dt_s, gravity_mps2);
  const bool fresh = last_fix_us != 0 && t_us >= last_fix_us && t_us - last_fix_us <= kFreshUs;
  for (Shadow& s : train_) {
    if (!s.active) continue;
    integrate(s, accel_mean_body_mps2, gyro_mean_body_radps, dt_s, gravity_mps2);
    if (t_us < s.next_sample_us) continue;
    if (!fresh) {
      // The filter is coasting: it is no reference for the drift any more.
      s.active = false;
      continue;
    }
    // Target: the standalone INS's position error against the UWB/INS
    // solution (seed 004 §2.3: the difference the network learns), nav x/y.
    const RbfNet::Output target = (filter.pos_nav_m - s.pos_nav_m).head<2>();
    net_.train(shadow_inputs(s, t_us), target);
    ++diag_.train_samples;
    s.next_sample_us += kSamplePeriodUs;
    if (t_us - s.t0_us >= window_us()) s.active = false;
  }
  // Start a window when one is free and the stagger has passed.
  if (!fresh || !filter.pos_nav_m.allFinite()) return;
  const uint64_t stagger_us = window_us() / kTrainShadows;
  if (last_window_start_us_ != 0 && t_us - last_window_start_us_ < stagger_us) return;
  for (Shadow& s : train_) {
    if (s.active) continue;
    start(s, t_us, filter);
    last_window_start_us_ = t_us;
    ++diag_.windows;
    break;
  }
}

void RbfBridge::on_fix(uint64_t t_us, const NominalState& filter) {
  if (mode_ == RbfMode::kOff) return;
  start(outage_, t_us, filter);
}

bool RbfBridge::predict(uint64_t t_us, Correction& out) {
  if (mode_ == RbfMode::kOff || !outage_.active || t_us < outage_.t0_us) return false;
  const RbfNet::Prediction p = net_.predict(shadow_inputs(outage_, t_us));
  if (!p.valid) return false;
  out.pos_x_nav_m = outage_.pos_nav_m.x() + p.y(0);
  out.pos_y_nav_m = outage_.pos_nav_m.y() + p.y(1);
  out.var_x_m2 = p.var(0);
  out.var_y_m2 = p.var(1);
  out.tau_s = static_cast<Real>(t_us - outage_.t0_us) * Real(1e-6);
  ++diag_.predictions;
  diag_.last_corr_x_m = static_cast<float>(p.y(0));
  diag_.last_corr_y_m = static_cast<float>(p.y(1));
  diag_.last_sigma_m = static_cast<float>(std::sqrt(Real(0.5) * (p.var(0) + p.var(1))));
  diag_.last_tau_s = static_cast<float>(out.tau_s);
  return true;
}

}  // namespace uwbnav
