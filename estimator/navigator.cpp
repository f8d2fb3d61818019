// Navigator: the running filter - IMU prediction, gated sequential range
// updates at each range's own time, ground-vehicle constraints, degraded modes
// (UWB outage, no IMU), health checks and the 10 ms output.
#include "estimator/navigator.hpp"

#include <cmath>

#include "estimator/mm_height.hpp"
#include "estimator/mm_nhc.hpp"
#include "estimator/mm_range.hpp"
#include "estimator/mm_zupt.hpp"

namespace uwbnav {
namespace {

Real seconds(int64_t dt_us) { return static_cast<Real>(dt_us) * Real(1e-6); }

int64_t diff_us(uint64_t a, uint64_t b) { return static_cast<int64_t>(a) - static_cast<int64_t>(b); }

// Shortest IMU interval integrated [us].
constexpr uint64_t kMinImuDtUs = 100;
// ZUPT only when the filter speed is also below this [m/s].
constexpr Real kZuptMaxSpeed_mps = Real(0.3);
// Innovations beyond this many sigmas and this many metres are never fused.
constexpr Real kHardGateSigma = Real(10);
constexpr Real kHardGateMin_m = Real(2);
// ... and the horizontal specific force below this (a steady brake is not rest) [m/s^2].
constexpr Real kRestMaxHorizAccel_mps2 = Real(0.1);
// Time constant of the on-line IMU noise floor [s].
constexpr Real kNoiseFloorTau_s = Real(1);
// Divergence monitor: fewest ranges judged; with sparse ranging the window
// stretches back to cover them (up to kMonitorMaxSpanUs).
constexpr size_t kMonitorMinRanges = 10;
constexpr uint64_t kMonitorMaxSpanUs = 30000000;

}  // namespace

Navigator::Navigator() {
  for (auto& row : prev_tag_pos_) {
    for (auto& v : row) v.setZero();
  }
}

Status Navigator::configure(const SiteConfig& site, const Params& params) {
  if (site.num_anchors == 0 || site.num_anchors > kMaxAnchors || site.num_tags > kMaxTags) {
    return Status::kInvalidArgument;
  }
  for (size_t i = 0; i < site.num_anchors; ++i) {
    const Vec3f& a = site.anchors[i].pos_nav_m;
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(a.z)) return Status::kNotFinite;
  }
  if (!(site.gravity_mps2 > 5.0F && site.gravity_mps2 < 15.0F)) return Status::kOutOfRange;
  site_ = site;
  params_ = params;
  update_params(params);
  const Status gs = gating_.configure(site_, params_);
  // Anchor layout: height spread decides the 2-D fix and the automatic height constraint.
  float z_lo = site_.anchors[0].pos_nav_m.z;
  float z_hi = z_lo;
  for (size_t i = 1; i < site_.num_anchors; ++i) {
    z_lo = std::fmin(z_lo, site_.anchors[i].pos_nav_m.z);
    z_hi = std::fmax(z_hi, site_.anchors[i].pos_nav_m.z);
  }
  planar_ = static_cast<Real>(z_hi - z_lo) < cfg_.planar_spread;
  diag_ = NavDiagnostics{};
  for (size_t i = 0; i < kMaxAnchors; ++i) {
    anchor_status_[i] = AnchorStatus{};
    if (i < site_.num_anchors) anchor_status_[i].anchor_id = site_.anchors[i].id;
  }
  configured_ = true;
  restart(false);
  after_failure_ = false;
  return gs;
}

void Navigator::update_params(const Params& params) {
  params_ = params;
  Config& c = cfg_;
  c.imu.gyro_noise = static_cast<Real>(params[ParamId::kImuGyroNoise]);
  c.imu.accel_noise = static_cast<Real>(params[ParamId::kImuAccelNoise]);
  c.imu.gyro_bias_rw = static_cast<Real>(params[ParamId::kImuGyroBiasRw]);
  c.imu.accel_bias_rw = static_cast<Real>(params[ParamId::kImuAccelBiasRw]);
  c.gyro_bias_init = static_cast<Real>(params[ParamId::kImuGyroBiasInit]);
  c.accel_bias_init = static_cast<Real>(params[ParamId::kImuAccelBiasInit]);
  c.uwb_sigma_m = static_cast<Real>(params[ParamId::kUwbSigma]);
  c.imu_timeout_us = param_us(params[ParamId::kInImuTimeoutUs]);
  c.uwb_timeout_us = param_us(params[ParamId::kInUwbTimeoutUs]);
  c.ground_constraints = params[ParamId::kEkfGroundConstraints] > 0.5F && site_.platform == Platform::kGround;
  c.nhc_sigma_lat = static_cast<Real>(params[ParamId::kEkfNhcSigmaLat]);
  c.nhc_sigma_vert = static_cast<Real>(params[ParamId::kEkfNhcSigmaVert]);
  c.zupt_sigma = static_cast<Real>(params[ParamId::kEkfZuptSigma]);
  c.zaru_sigma = static_cast<Real>(params[ParamId::kEkfZaruSigma]);
  c.height_mode = static_cast<int>(std::lround(params[ParamId::kEkfHeightMode]));
  c.height_sigma = static_cast<Real>(params[ParamId::kEkfHeightSigma]);
  c.origin_height = static_cast<Real>(params[ParamId::kEkfOriginHeight]);
  c.constraint_period_us = param_us(1e6F / params[ParamId::kEkfConstraintRate]);
  c.cv_accel_psd = static_cast<Real>(params[ParamId::kEkfCvAccelPsd]);
  c.init_window_us = param_us(params[ParamId::kEkfInitWindow] * 1e6F);
  c.init_heading_dist = static_cast<Real>(params[ParamId::kEkfInitHeadingDist]);
  c.init_heading_timeout_us = param_us(params[ParamId::kEkfInitHeadingTimeout] * 1e6F);
  c.planar_spread = static_cast<Real>(params[ParamId::kEkfPlanarSpread]);
  c.diverge_nis = static_cast<Real>(params[ParamId::kEkfDivergeNis]);
  c.diverge_fraction = static_cast<Real>(params[ParamId::kEkfDivergeFraction]);
  c.diverge_window_us = param_us(params[ParamId::kEkfDivergeWindow] * 1e6F);
  c.degraded_sigma = static_cast<Real>(params[ParamId::kEkfDegradedSigma]);
  c.init_speed = static_cast<Real>(params[ParamId::kEkfInitSpeed]);
  c.init_yaw_sigma = static_cast<Real>(params[ParamId::kEkfInitYawSigma]);
  imu_eff_ = c.imu;
  rest_.configure(static_cast<Real>(params[ParamId::kEkfRestWindow]), static_cast<Real>(params[ParamId::kEkfRestAccelStd]),
                  static_cast<Real>(params[ParamId::kEkfRestGyroMax]));
  if (configured_) gating_.update_params(params);
}

const NavDiagnostics& Navigator::diagnostics() const { return diag_; }
size_t Navigator::num_anchors() const { return site_.num_anchors; }
const AnchorStatus& Navigator::anchor_status(size_t index) const {
  return anchor_status_[index < kMaxAnchors ? index : kMaxAnchors - 1];
}

void Navigator::reset() {
  restart(false);
  after_failure_ = false;
}

Vec3 Navigator::lever(int tag_index) const {
  if (tag_index < 0 || static_cast<size_t>(tag_index) >= site_.num_tags) return Vec3::Zero();
  return to_vec3(site_.tags[tag_index].lever_body_m);
}

bool Navigator::imu_alive(uint64_t t_us) const {
  return diag_.imu_samples > 0 && diff_us(t_us, diag_.last_imu_t_us) <= static_cast<int64_t>(cfg_.imu_timeout_us);
}

void Navigator::track_imu_noise(const Vec3& accel_body_mps2, const Vec3& gyro_body_radps, Real dt_s) {
  // Second difference f_k - 2 f_k-1 + f_k-2: smooth motion cancels, white noise
  // of per-sample variance s2 gives variance 6 s2; its density^2 is s2 dt.
  const Vec3 f1 = to_vec3(prev_imu_.accel_body_mps2);
  const Vec3 w1 = to_vec3(prev_imu_.gyro_body_radps);
  if (imu_history_ >= 2 && dt_s > Real(0)) {
    const Real a = std::fmin(dt_s / kNoiseFloorTau_s, Real(1));
    const Vec3 d2f = accel_body_mps2 - Real(2) * f1 + prev2_accel_body_mps2_;
    const Vec3 d2w = gyro_body_radps - Real(2) * w1 + prev2_gyro_body_radps_;
    accel_d2_ms_ += a * (d2f.squaredNorm() / Real(3) - accel_d2_ms_);
    gyro_d2_ms_ += a * (d2w.squaredNorm() / Real(3) - gyro_d2_ms_);
    imu_eff_.accel_noise = std::fmax(cfg_.imu.accel_noise, std::sqrt(accel_d2_ms_ / Real(6) * dt_s));
    imu_eff_.gyro_noise = std::fmax(cfg_.imu.gyro_noise, std::sqrt(gyro_d2_ms_ / Real(6) * dt_s));
  }
  prev2_accel_body_mps2_ = f1;
  prev2_gyro_body_radps_ = w1;
  if (imu_history_ < 2) ++imu_history_;
}

Status Navigator::on_imu(const ImuSample& imu) {
  if (!configured_) return Status::kNotInitialised;
  const Vec3 f = to_vec3(imu.accel_body_mps2);
  const Vec3 w = to_vec3(imu.gyro_body_radps);
  if (!f.allFinite() || !w.allFinite()) return Status::kNotFinite;
  if (have_prev_imu_ && imu.t_us <= prev_imu_.t_us) return Status::kInvalidArgument;
  const bool gap = !have_prev_imu_ || imu.t_us - prev_imu_.t_us > cfg_.imu_timeout_us;
  if (gap) {
    imu_history_ = 0;
  } else {
    track_imu_noise(f, w, seconds(diff_us(imu.t_us, prev_imu_.t_us)));
  }
  ++diag_.imu_samples;
  diag_.last_imu_t_us = imu.t_us;
  rest_.add(imu.t_us, f, w);
  last_gyro_body_radps_ = w;

  if (phase_ != Phase::kRunning) {
    if (!gap) init_on_imu(imu);
    if (first_imu_t_us_ == 0) first_imu_t_us_ = imu.t_us;
    prev_imu_ = imu;
    have_prev_imu_ = true;
    return Status::kOk;
  }
  if (cv_mode_) {
    // IMU back after an outage (or first IMU of a UWB-first start): keep the
    // constant-velocity solution while levelling and heading are re-acquired
    // exactly as at power-on; start_filter() then switches to the IMU model.
    if (gap) begin_imu_recovery();
    if (first_imu_t_us_ == 0) first_imu_t_us_ = imu.t_us;
    if (!gap) init_on_imu(imu);
    prev_imu_ = imu;
    have_prev_imu_ = true;
    return Status::kOk;
  }
  if (!gap && imu.t_us - prev_imu_.t_us >= kMinImuDtUs) {
    const Real dt = seconds(diff_us(imu.t_us, prev_imu_.t_us));
    const Vec3 f_mean = Real(0.5) * (f + to_vec3(prev_imu_.accel_body_mps2));
    const Vec3 w_mean = Real(0.5) * (w + to_vec3(prev_imu_.gyro_body_radps));
    ekf_.predict_imu(f_mean, w_mean, dt, static_cast<Real>(site_.gravity_mps2), imu_eff_);
    t_state_us_ = imu.t_us;
    apply_constraints(imu.t_us);
    check_health();
  }
  prev_imu_ = imu;
  have_prev_imu_ = true;
  return Status::kOk;
}

void Navigator::apply_constraints(uint64_t t_us) {
  if (t_us - last_constraint_us_ < cfg_.constraint_period_us) return;
  last_constraint_us_ = t_us;
  if (height_on_) (void)fuse(mm_height(ekf_.state(), height_ref_m_, height_sigma_m_));
  if (!cfg_.ground_constraints || cv_mode_) return;
  rest_.evaluate();
  // The IMU's spread alone cannot tell rest from constant velocity or a steady
  // brake: the filter speed must be small and the mean specific force vertical.
  const Vec3 f_nav = ekf_.dcm() * (rest_.accel_mean() - ekf_.state().ba_body_mps2);
  const bool at_rest = rest_.at_rest() && ekf_.state().vel_nav_mps.norm() < kZuptMaxSpeed_mps &&
                       f_nav.head<2>().norm() < kRestMaxHorizAccel_mps2;
  if (at_rest) {
    for (int i = 0; i < 3; ++i) {
      (void)fuse(mm_zupt(ekf_.state(), i, cfg_.zupt_sigma));
    }
    for (int i = 0; i < 3; ++i) {
      (void)fuse(mm_zaru(ekf_.state(), rest_.gyro_mean(), i, cfg_.zaru_sigma));
    }
  } else {
    (void)fuse(mm_nhc(ekf_.state(), ekf_.dcm(), 1, cfg_.nhc_sigma_lat));
    (void)fuse(mm_nhc(ekf_.state(), ekf_.dcm(), 2, cfg_.nhc_sigma_vert));
  }
}

bool Navigator::fuse(const ScalarObs& obs) { return ekf_.update(obs).applied; }

void Navigator::check_health(bool symmetrise) {
  if (!ekf_.sanitise(symmetrise)) restart(true);
}

void Navigator::enter_cv_mode() {
  cv_mode_ = true;
  ErrVec sigma = ErrVec::Zero();
  sigma.segment<3>(ErrIdx::kAtt).setConstant(Real(0.1));
  sigma.segment<3>(ErrIdx::kBa).setConstant(cfg_.accel_bias_init);
  sigma.segment<3>(ErrIdx::kBg).setConstant(cfg_.gyro_bias_init);
  ekf_.decouple_inertial(sigma);
  // Body level; keep the yaw (used for the lever arm and the heading output).
  ekf_.mutable_state().q_nav_body = quat_from_yaw(quat_yaw(ekf_.state().q_nav_body));
  ekf_.refresh_dcm();
}

RangeReport Navigator::on_range(const UwbRange& range) {
  RangeReport rep;
  rep.t_us = range.t_us;
  rep.anchor_id = range.anchor_id;
  rep.tag_id = range.tag_id;
  rep.range_m = range.range_m;
  if (!configured_) return rep;
  ++diag_.ranges_received;
  const int ai = site_.find_anchor(range.anchor_id);
  int ti = site_.num_tags == 0 ? 0 : site_.find_tag(range.tag_id);
  if (ai < 0 || ti < 0 || static_cast<size_t>(ti) >= kMaxTags || !std::isfinite(range.range_m)) {
    ++diag_.ranges_rejected;
    ++cycle_rejected_;
    return rep;
  }
  AnchorStatus& as = anchor_status_[ai];
  as.last_t_us = range.t_us;
  as.last_range_m = range.range_m;

  RangeContext ctx;
  ctx.range = range;
  ctx.anchor_index = ai;
  ctx.anchor_pos_nav_m = site_.anchors[ai].pos_nav_m;
  const Real r_nom = cfg_.uwb_sigma_m * cfg_.uwb_sigma_m;
  ctx.meas_var_m2 = static_cast<float>(r_nom);

  if (phase_ == Phase::kRunning) {
    if (!cv_mode_ && !imu_alive(range.t_us)) enter_cv_mode();
    if (cv_mode_ && range.t_us > t_state_us_) {
      ekf_.predict_cv(seconds(diff_us(range.t_us, t_state_us_)), cfg_.cv_accel_psd);
      t_state_us_ = range.t_us;
      check_health();
      if (height_on_) apply_constraints(range.t_us);
      // Ground vehicles point where they go: heading from the velocity.
      const Vec3& v = ekf_.state().vel_nav_mps;
      if (cfg_.ground_constraints || site_.platform == Platform::kGround) {
        if (v.head<2>().norm() > Real(0.5)) {
          ekf_.mutable_state().q_nav_body = quat_from_yaw(std::atan2(v.y(), v.x()));
          ekf_.refresh_dcm();
        }
      }
    }
  }

  const bool running = phase_ == Phase::kRunning;
  RangePrediction pred;
  if (running) {
    const Real dt_r = seconds(diff_us(range.t_us, t_state_us_));
    pred = mm_range_predict(ekf_.state(), ekf_.dcm(), cv_mode_ ? Vec3::Zero() : last_gyro_body_radps_, lever(ti),
                            to_vec3(ctx.anchor_pos_nav_m), dt_r);
  }
  Real s_nom = Real(0);
  if (running && pred.valid) {
    s_nom = ekf_.prepare(pred.h) + r_nom;
    const Real innov = static_cast<Real>(range.range_m) - pred.range_m;
    ctx.tag_pos_nav_m = to_vec3f(pred.tag_pos_nav_m);
    ctx.predicted_range_m = static_cast<float>(pred.range_m);
    ctx.innovation_m = static_cast<float>(innov);
    ctx.innovation_var_m2 = static_cast<float>(s_nom);
    ctx.speed_mps = static_cast<float>(ekf_.state().vel_nav_mps.head<2>().norm());
    if (prev_tag_valid_[ai][ti]) {
      ctx.dist_since_prev_m = static_cast<float>((pred.tag_pos_nav_m - prev_tag_pos_[ai][ti]).norm());
    }
    const Real sig_h = std::sqrt(ekf_.cov()(0, 0) + ekf_.cov()(1, 1));
    // Without IMU the prediction carries no independent motion information
    // (the consistency evidence of seed 000 eq. 3 needs an inertial distance).
    ctx.filter_ready = !cv_mode_ && sig_h < cfg_.degraded_sigma;
  }

  const GatingDecision d = gating_.assess(ctx);
  bool used = false;
  // Hard guard behind the gating layer: a range this far off is a gross error
  // whatever the policy says (a drifted filter is re-initialised by the
  // divergence monitor instead of being dragged by blunders).
  const Real innov_abs = running && pred.valid ? std::fabs(static_cast<Real>(range.range_m) - pred.range_m) : Real(0);
  // The gating layer's escape (robust mode with inflated R) exists for a filter
  // that drifted away from its own gate: the hard guard must not undo it.
  const bool escape = gating_.escape_active() && d.use;
  const bool gross = !escape && innov_abs > kHardGateSigma * std::sqrt(s_nom) && innov_abs > kHardGateMin_m;
  if (running && pred.valid && d.use && !gross) {
    const Real scale = std::isfinite(d.r_scale) && d.r_scale >= 1.0F ? static_cast<Real>(d.r_scale) : Real(1);
    used = ekf_.update_prepared(static_cast<Real>(range.range_m) - pred.range_m, r_nom * scale).applied;
  }
  gating_.on_result(ctx, d, used);

  rep.innovation_m = ctx.innovation_m;
  rep.innovation_var_m2 = ctx.innovation_var_m2;
  rep.p_svm = d.p_svm;
  rep.p_mc = d.p_mc;
  rep.p_fused = d.p_fused;
  rep.nlos = d.nlos;
  rep.used = used;

  as.last_innovation_m = ctx.innovation_m;
  as.last_p_nlos = d.p_fused;
  if (d.nlos) {
    ++as.nlos_count;
  } else {
    ++as.los_count;
  }
  as.nlos_state = d.nlos;

  if (running) {
    if (used) {
      ++as.used_count;
      ++diag_.ranges_used;
      ++cycle_used_;
      diag_.last_range_used_t_us = range.t_us;
    } else {
      ++diag_.ranges_rejected;
      ++cycle_rejected_;
    }
    if (pred.valid) {
      prev_tag_pos_[ai][ti] = pred.tag_pos_nav_m;
      prev_tag_valid_[ai][ti] = true;
      const Real innov = static_cast<Real>(range.range_m) - pred.range_m;
      monitor_divergence(range.t_us, innov * innov / s_nom);
    }
    check_health(false);
    if (cv_mode_ && imu_alive(range.t_us)) {
      // IMU recovery: build the LS track and try the heading in the background.
      if (init_track(ai, ti, range) && levelled_) try_heading(range.t_us);
      if (cv_mode_ && levelled_) yaw_bank_on_range(ai, ti, range);
    }
  } else {
    init_on_range(ai, ti, range);
  }
  return rep;
}

void Navigator::monitor_divergence(uint64_t t_us, Real nis) {
  monitor_t_us_[monitor_head_] = t_us;
  monitor_bad_[monitor_head_] = !(nis <= cfg_.diverge_nis);
  monitor_head_ = (monitor_head_ + 1) % kMonitorCapacity;
  if (monitor_count_ < kMonitorCapacity) ++monitor_count_;
  if (!monitor_bad_[(monitor_head_ + kMonitorCapacity - 1) % kMonitorCapacity]) return;  // only a bad range can tip it
  size_t n = 0;
  size_t bad = 0;
  uint64_t oldest = t_us;
  for (size_t k = 0; k < monitor_count_; ++k) {
    const size_t i = (monitor_head_ + kMonitorCapacity - 1 - k) % kMonitorCapacity;
    const uint64_t age = t_us - monitor_t_us_[i];
    // The window, or with sparse ranging the last kMonitorMinRanges ranges.
    if (age > cfg_.diverge_window_us && (n >= kMonitorMinRanges || age > kMonitorMaxSpanUs)) break;
    ++n;
    if (monitor_bad_[i]) ++bad;
    oldest = monitor_t_us_[i];
  }
  // Judge only a full window with enough ranges (a short burst of NLOS is the gate's business).
  const bool window_covered = t_us - oldest >= cfg_.diverge_window_us * 3 / 4 || n >= kMonitorCapacity;
  if (n >= kMonitorMinRanges && window_covered &&
      static_cast<Real>(bad) >= cfg_.diverge_fraction * static_cast<Real>(n)) {
    ++diag_.reinits;
    // Keep the attitude and gyro bias (the IMU solution rarely diverges in
    // attitude first); re-acquire position and heading from UWB.
    const Quat q = ekf_.state().q_nav_body;
    const Vec3 bg = ekf_.state().bg_body_radps;
    const bool had_imu = !cv_mode_;
    const uint64_t window_us = window_us_;  // the fix window learnt for this ranging rate
    restart(false);
    window_us_ = window_us;
    after_failure_ = true;
    if (had_imu) {
      q_init_ = q;
      bg_init_ = bg;
      levelled_ = true;
    }
  }
}

NavOutput Navigator::output(uint64_t t_us) {
  NavOutput out;
  out.t_us = t_us;
  out.resets = diag_.resets;
  out.ranges_used = cycle_used_;
  out.ranges_rejected = cycle_rejected_;
  cycle_used_ = 0;
  cycle_rejected_ = 0;
  if (!configured_) {
    out.status = NavStatus::kInvalid;
    return out;
  }
  if (phase_ == Phase::kRunning && !cv_mode_ && !imu_alive(t_us) && diff_us(t_us, t_state_us_) > 0 &&
      t_us - t_state_us_ > cfg_.imu_timeout_us) {
    enter_cv_mode();
  }
  constexpr float kUnknownSigma_m = 1e3F;
  if (phase_ != Phase::kRunning) {
    out.status = after_failure_ ? NavStatus::kInvalid : NavStatus::kInitialising;
    if (have_fix_) out.pos_nav_m = to_vec3f(last_fix_origin_nav_m_);
    out.pos_sigma_m = Vec3f{kUnknownSigma_m, kUnknownSigma_m, kUnknownSigma_m};
    out.vel_sigma_mps = Vec3f{kUnknownSigma_m, kUnknownSigma_m, kUnknownSigma_m};
    return out;
  }
  const NominalState& x = ekf_.state();
  const ErrCov& p = ekf_.cov();
  // Extrapolate to the output time (the state is at the last IMU sample or range).
  const Real dt = seconds(diff_us(t_us, t_state_us_));
  const Real dt_c = std::fmin(std::fmax(dt, Real(-0.1)), Real(0.5));
  const Vec3 pos = x.pos_nav_m + x.vel_nav_mps * dt_c;
  out.pos_nav_m = to_vec3f(pos);
  out.vel_nav_mps = to_vec3f(x.vel_nav_mps);
  for (int i = 0; i < 4; ++i) out.q_nav_body[i] = static_cast<float>(x.q_nav_body(i));
  Real var_p[3];
  for (int i = 0; i < 3; ++i) {
    // Position variance at the output time: P_pp + 2 dt P_pv + dt^2 P_vv.
    var_p[i] = p(i, i) + Real(2) * dt_c * p(i, 3 + i) + dt_c * dt_c * p(3 + i, 3 + i);
    var_p[i] = std::fmax(var_p[i], Real(0));
  }
  out.pos_sigma_m = Vec3f{static_cast<float>(std::sqrt(var_p[0])), static_cast<float>(std::sqrt(var_p[1])),
                          static_cast<float>(std::sqrt(var_p[2]))};
  const Real cxy = p(0, 1) + dt_c * (p(0, 4) + p(3, 1)) + dt_c * dt_c * p(3, 4);
  const Real denom = std::sqrt(var_p[0] * var_p[1]);
  out.pos_xy_corr = denom > Real(0) ? static_cast<float>(std::fmin(std::fmax(cxy / denom, Real(-1)), Real(1))) : 0.0F;
  out.vel_sigma_mps = Vec3f{static_cast<float>(std::sqrt(p(3, 3))), static_cast<float>(std::sqrt(p(4, 4))),
                            static_cast<float>(std::sqrt(p(5, 5)))};
  out.heading_rad = static_cast<float>(quat_yaw(x.q_nav_body));
  out.mode = cv_mode_ ? NavMode::kUwbOnly : NavMode::kInertial;

  const uint64_t last_uwb_us =
      diag_.last_range_used_t_us > running_since_us_ ? diag_.last_range_used_t_us : running_since_us_;
  const bool uwb_outage = diff_us(t_us, last_uwb_us) > static_cast<int64_t>(cfg_.uwb_timeout_us);
  const Real sigma_h = std::sqrt(var_p[0] + var_p[1]);
  if (uwb_outage || cv_mode_ || !(sigma_h < cfg_.degraded_sigma)) {
    out.status = NavStatus::kDegraded;
  } else {
    out.status = NavStatus::kValid;
  }
  // Never publish a non-finite number.
  const bool finite = pos.allFinite() && x.vel_nav_mps.allFinite() && x.q_nav_body.allFinite() &&
                      std::isfinite(out.pos_sigma_m.x) && std::isfinite(out.pos_sigma_m.y) &&
                      std::isfinite(out.pos_sigma_m.z) && std::isfinite(out.pos_xy_corr) &&
                      std::isfinite(out.vel_sigma_mps.x) && std::isfinite(out.vel_sigma_mps.y) &&
                      std::isfinite(out.vel_sigma_mps.z) && std::isfinite(out.heading_rad);
  if (!finite) {
    restart(true);
    NavOutput bad;
    bad.t_us = t_us;
    bad.status = NavStatus::kInvalid;
    bad.resets = diag_.resets;
    bad.pos_sigma_m = Vec3f{kUnknownSigma_m, kUnknownSigma_m, kUnknownSigma_m};
    bad.vel_sigma_mps = bad.pos_sigma_m;
    return bad;
  }
  return out;
}

void Navigator::state_vector(float out[16]) const {
  const NominalState& x = ekf_.state();
  for (int i = 0; i < 3; ++i) {
    out[i] = static_cast<float>(x.pos_nav_m(i));
    out[3 + i] = static_cast<float>(x.vel_nav_mps(i));
    out[10 + i] = static_cast<float>(x.ba_body_mps2(i));
    out[13 + i] = static_cast<float>(x.bg_body_radps(i));
  }
  for (int i = 0; i < 4; ++i) out[6 + i] = static_cast<float>(x.q_nav_body(i));
}

void Navigator::covariance_diagonal(float out[kErrorStateSize]) const {
  for (size_t i = 0; i < kErrorStateSize; ++i) {
    out[i] = static_cast<float>(ekf_.cov()(static_cast<int>(i), static_cast<int>(i)));
  }
}

float Navigator::covariance(size_t row, size_t col) const {
  if (row >= kErrorStateSize || col >= kErrorStateSize) return kNaNf;
  return static_cast<float>(ekf_.cov()(static_cast<int>(row), static_cast<int>(col)));
}

}  // namespace uwbnav
