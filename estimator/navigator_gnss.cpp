// GNSS fusion of the Navigator (docs/ekf.md "GNSS"): quality and latency checks,
// the innovation gate, and the loose position/velocity update of whichever
// filter runs (IMU filter or ranges-only filter), lever arm and latency applied.
#include <cmath>

#include "estimator/mm_gnss.hpp"
#include "estimator/navigator.hpp"

#if UWBNAV_GNSS
namespace uwbnav {
namespace {

int64_t diff_us(uint64_t a, uint64_t b) { return static_cast<int64_t>(a) - static_cast<int64_t>(b); }
Real seconds(int64_t dt_us) { return static_cast<Real>(dt_us) * Real(1e-6); }

// Fix types ordered by quality (gnss.min_quality): NMEA codes are not.
int gnss_rank(GnssFixType f) {
  switch (f) {
    case GnssFixType::kSingle: return 1;
    case GnssFixType::kDgnss: return 2;
    case GnssFixType::kRtkFloat: return 3;
    case GnssFixType::kRtkFixed: return 4;
    case GnssFixType::kNone: break;
  }
  return 0;
}

}  // namespace

GnssReport Navigator::on_gnss(const GnssFix& fix) {
  GnssReport rep;
  rep.t_us = fix.t_us;
  if (!configured_) return rep;
  ++diag_.gnss_received;
  const auto reject = [&](GnssVerdict v) {
    rep.verdict = v;
    ++diag_.gnss_rejected[static_cast<size_t>(v)];
    return rep;
  };
  if (!cfg_.gnss_enable) return reject(GnssVerdict::kDisabled);
  const Vec3 pos_meas = to_vec3(fix.pos_nav_m);
  const Vec3 sigma = to_vec3(fix.pos_sigma_m);
  const Real sigma_h = std::fmax(sigma.x(), sigma.y());
  if (gnss_rank(fix.fix) < cfg_.gnss_min_rank || (fix.num_sv != 0 && fix.num_sv < cfg_.gnss_min_sv) ||
      !(sigma_h <= cfg_.gnss_max_sigma) || !pos_meas.allFinite() || !(sigma.minCoeff() > Real(0))) {
    return reject(GnssVerdict::kQuality);
  }
  if (fix.rx_t_us < fix.t_us || fix.rx_t_us - fix.t_us > cfg_.gnss_max_latency_us) return reject(GnssVerdict::kLate);
  if (phase_ != Phase::kRunning) return reject(GnssVerdict::kNoFilter);
  if (!cv_mode_ && !imu_alive(fix.t_us)) enter_cv_mode(NavMode::kUwbOnly);
  if (!advance_cv(fix.t_us)) return reject(GnssVerdict::kNoFilter);
  // The state is at the last IMU sample (or range); a fix older than that by
  // more than the latency allowance no longer describes the state's recent past.
  if (diff_us(t_state_us_, fix.t_us) > static_cast<int64_t>(cfg_.gnss_max_latency_us)) return reject(GnssVerdict::kLate);

  GnssPredictionInput in;
  in.x = &ekf_.state();
  in.c_nav_body = ekf_.dcm();
  in.lever_body_m = to_vec3(site_.gnss_lever_body_m);
  in.dt_s = seconds(diff_us(fix.t_us, t_state_us_));
  if (!cv_mode_ && have_prev_imu_) {
    in.gyro_body_radps = last_gyro_body_radps_;
    in.accel_nav_mps2 = ekf_.dcm() * (to_vec3(prev_imu_.accel_body_mps2) - ekf_.state().ba_body_mps2);
    in.accel_nav_mps2.z() -= static_cast<Real>(site_.gravity_mps2);
  }
  // Ranges-only filter without a heading: the antenna lies anywhere on the
  // circle of its horizontal lever arm (as output() widens the position).
  Real lever_var_h = Real(0);
  if (cv_mode_ && !cv_yaw_known_) {
    lever_var_h = Real(0.5) * in.lever_body_m.head<2>().squaredNorm();
    in.lever_body_m.x() = Real(0);
    in.lever_body_m.y() = Real(0);
  }
  // Correlated error (multipath, atmosphere; a Gauss-Markov process of time
  // constant T): N fixes within 2T carry about the information of one, so each
  // is fused with its variance times 2T / dt (dt: time since the previous fused fix).
  Real corr = Real(1);
  if (gnss_prev_fused_us_ != 0 && cfg_.gnss_corr_time > Real(0)) {
    const Real dt_fix = std::fmax(seconds(diff_us(fix.t_us, gnss_prev_fused_us_)), Real(0.01));
    corr = std::fmax(Real(1), Real(2) * cfg_.gnss_corr_time / dt_fix);
  }

  // Gate on the prior with the receiver's single-epoch accuracy: a multipath
  // jump of several sigma is refused, whatever the correlation allowance.
  Real var_axis[3];
  Real nis_max = Real(0);
  bool gate_ok = true;
  for (int a = 0; a < 3; ++a) {
    const Real s = cfg_.gnss_sigma_scale * sigma(a);
    var_axis[a] = s * s + (a < 2 ? lever_var_h : Real(0));
    const ScalarObs obs = mm_gnss_position(in, a, pos_meas(a), var_axis[a]);
    const Real s_var = ekf_.innovation_variance(obs.h, obs.r_var);
    const Real nis = obs.innovation * obs.innovation / s_var;
    if (a == 0) rep.innovation_m.x = static_cast<float>(obs.innovation);
    if (a == 1) rep.innovation_m.y = static_cast<float>(obs.innovation);
    if (a == 2) rep.innovation_m.z = static_cast<float>(obs.innovation);
    nis_max = std::fmax(nis_max, nis);
    if (!(nis <= cfg_.gnss_gate_sigma * cfg_.gnss_gate_sigma)) gate_ok = false;
  }
  rep.nis_max = static_cast<float>(nis_max);
  if (!gate_ok) return reject(GnssVerdict::kGate);

  // Sequential scalar updates (independent axes), each predicted from the
  // state the previous one left.
  for (int a = 0; a < 3; ++a) {
    in.x = &ekf_.state();
    in.c_nav_body = ekf_.dcm();
    ignore_result(fuse(mm_gnss_position(in, a, pos_meas(a), var_axis[a] * corr)));
  }
  const Vec3 vel_meas = to_vec3(fix.vel_nav_mps);
  if (cfg_.gnss_use_vel && vel_meas.allFinite() && fix.vel_sigma_mps > 0.0F && std::isfinite(fix.vel_sigma_mps)) {
    const Real sv = cfg_.gnss_sigma_scale * static_cast<Real>(fix.vel_sigma_mps);
    const Real var_v = sv * sv;
    bool vel_ok = true;
    for (int a = 0; a < 3 && vel_ok; ++a) {
      const ScalarObs obs = mm_gnss_velocity(in, a, vel_meas(a), var_v);
      vel_ok = obs.innovation * obs.innovation <=
               cfg_.gnss_gate_sigma * cfg_.gnss_gate_sigma * ekf_.innovation_variance(obs.h, obs.r_var);
    }
    if (vel_ok) {
      for (int a = 0; a < 3; ++a) {
        in.x = &ekf_.state();
        in.c_nav_body = ekf_.dcm();
        ignore_result(fuse(mm_gnss_velocity(in, a, vel_meas(a), var_v)));
      }
      rep.vel_used = true;
    }
  }
  check_health(false);
  if (phase_ != Phase::kRunning) return reject(GnssVerdict::kNoFilter);
  rep.verdict = GnssVerdict::kFused;
  ++diag_.gnss_used;
  diag_.last_gnss_used_t_us = fix.t_us;
  gnss_prev_fused_us_ = fix.t_us;
  return rep;
}

}  // namespace uwbnav
#endif
