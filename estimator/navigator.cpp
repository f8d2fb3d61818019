// Navigator: the running filter - IMU prediction, gated sequential range
// updates at each range's own time with the range-error states and a learned
// ranging noise, ground-vehicle constraints, the modes (inertial, ranges only
// while aligning, recovering or without IMU), divergence recovery without a
// reset, health checks and the 10 ms output.
#include "estimator/navigator.hpp"

#include <cmath>

#include "estimator/mm_height.hpp"
#include "estimator/mm_nhc.hpp"
#include "estimator/mm_position.hpp"
#include "estimator/mm_range.hpp"
#include "estimator/mm_zupt.hpp"

namespace uwbnav {
namespace {

Real seconds(int64_t dt_us) { return static_cast<Real>(dt_us) * Real(1e-6); }

int64_t diff_us(uint64_t a, uint64_t b) { return static_cast<int64_t>(a) - static_cast<int64_t>(b); }

// Iterated range update (iterated_range_innovation): re-linearise when the
// range circle bends away by more than this many range sigmas over the
// first-order step across the line of sight; at most this many times; done
// when the position step moves less than this.
constexpr Real kIekfCurvSigma = Real(0.5);
constexpr int kIekfMaxIter = 3;
constexpr Real kIekfSettle_m = Real(0.01);
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
// Ground vehicle without IMU: correlation time of roll and pitch about level [s].
constexpr Real kLevelTau_s = Real(1);
// Divergence monitor: fewest ranges judged; with sparse ranging the window
// stretches back to cover them (up to kMonitorMaxSpanUs).
constexpr size_t kMonitorMinRanges = 10;
constexpr uint64_t kMonitorMaxSpanUs = 30000000;
// Noise learning (docs/ekf.md "Learned ranging noise"): half squared
// differences of consecutive innovations of a pair, winsorised at kLearnClip R;
// E[min(z^2, 9)] = 0.995 of a standard normal, which the sample is divided by.
constexpr Real kLearnClip = Real(9);
constexpr Real kLearnClipMean = Real(0.995);
// Sage-Husa samples: innovations are also truncated near 3 sigma by the gate,
// E[z^2 | |z| < 3] = 0.9733; a sample only counts while H P H^T is small beside R.
constexpr Real kLearnClipMeanTrunc = Real(0.9733);
constexpr Real kLearnMaxHphRatio = Real(4);
// Innovations of a pair are differenced over at least kLearnLagUs (real UWB
// errors are correlated over a fraction of a second: consecutive differences
// would see only the fast part) and at most kLearnMaxPairGapUs [us].
constexpr uint64_t kLearnLagUs = 500000;
constexpr uint64_t kLearnMaxPairGapUs = 2000000;
// Integrity check: period, oldest range used, chi-square threshold (2 dof, 99.9 %).
constexpr uint64_t kIntegrityPeriodUs = 1000000;
constexpr uint64_t kIntegrityMaxAgeUs = 500000;
constexpr Real kIntegrityChi2 = Real(13.8);
constexpr Real kIntegrityShortSigma = Real(3);
// Short-range test: a range this many sigmas shorter than predicted counts,
// kShortMinRanges of them from two anchors or more fail; |z| below
// kShortResetSigma clears the count.
constexpr Real kShortSigma = Real(5);
constexpr Real kShortResetSigma = Real(3);
constexpr uint32_t kShortMinRanges = 3;
// ... or kShortAnchorRun consecutive ranges of one anchor fail, whatever the
// other anchors say (a position error across their lines of sight is
// invisible to them).
constexpr uint8_t kShortAnchorRun = 5;
// Correlation time of the measured horizontal acceleration in the CV model [s].
constexpr Real kCvAccelCorrTime_s = Real(1);
// Distance over which a pair's own scale error decorrelates in the offset's random walk [m].
constexpr Real kScaleCorrDist_m = Real(20);
// Range offsets are learnt only from innovations within this many sigmas.
constexpr Real kLearnOffsetMaxZ = Real(1.5);
// Range offsets are learnt only above this horizontal speed [m/s].
constexpr Real kLearnOffsetMinSpeed_mps = Real(0.2);
// Pseudo-samples the prior uwb.sigma counts for at start.
constexpr Real kLearnPriorCount = Real(10);
// Ground vehicles point where they go: heading of the ranges-only filter from its
// velocity once faster than this (reversing is slower) and well determined.
constexpr Real kCvHeadingMinSpeed_mps = Real(2);
constexpr Real kCvHeadingSlip_rad = Real(0.05);
// Recovery: re-anchoring holds position and velocity to this at least [m, m/s];
// inflation brings them up to these variances [m^2, (m/s)^2, rad^2].
constexpr Real kInflatePosVar_m2 = Real(1.0);
constexpr Real kInflateVelVar_m2ps2 = Real(1.0);
constexpr Real kInflateYawVar_rad2 = Real(0.04);
constexpr Real kReanchorVelSigma_mps = Real(1.5);
#if UWBNAV_RBF_BRIDGE
// Outage bridging: one pseudo-measurement per period [us]; innovations beyond
// this many sigmas of S are not fused (the network is off the mark).
constexpr uint64_t kBridgePeriodUs = 1000000;
constexpr Real kBridgeGateSigma = Real(5);
#endif

}  // namespace

Navigator::Navigator() {
  for (auto& row : prev_tag_pos_) {
    for (auto& v : row) v.setZero();
  }
  for (auto& a : anchor_slot_) a = -1;
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
  // A commissioned offset must be finite; an uncalibrated site has none.
  for (auto& row : site_.range_offset_m) {
    for (float& v : row) {
      if (!std::isfinite(v)) v = 0.0F;
    }
  }
  params_ = params;
  // A new site or IMU: the bias instability is learned again from the parameters
  // (the IMU filter's start closes the learning window).
  for (int b = 0; b < 2; ++b) rw_var_gain_[b] = corr_ratio_[b] = Real(1);
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
#if UWBNAV_COOP
  for (NeighbourSlot& n : neighbours_) n = NeighbourSlot{};
#endif
  for (size_t i = 0; i < kMaxAnchors; ++i) {
    anchor_status_[i] = AnchorStatus{};
    if (i < site_.num_anchors) anchor_status_[i].anchor_id = site_.anchors[i].id;
  }
  for (auto& row : pair_) {
    for (auto& p : row) p = PairRange{};
  }
  for (auto& b : range_rate_) b = RangeRateBlock{};  // indices may name other anchors now
  r_los_m2_ = cfg_.uwb_sigma_m * cfg_.uwb_sigma_m;
  r_diff_m2_ = r_los_m2_;
  r_sh_m2_ = r_los_m2_;
  r_count_ = Real(0);
  r_sh_count_ = Real(0);
  diag_.uwb_sigma_m = static_cast<float>(cfg_.uwb_sigma_m);
  configured_ = true;
  started_ = false;
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
  c.bias_rw_max_gain = static_cast<Real>(params[ParamId::kImuBiasRwMaxGain]);
  const Real sigma_prior = static_cast<Real>(params[ParamId::kUwbSigma]);
  c.uwb_sigma_min_m = static_cast<Real>(params[ParamId::kUwbSigmaMin]);
  c.uwb_sigma_max_m = std::fmax(static_cast<Real>(params[ParamId::kUwbSigmaMax]), c.uwb_sigma_min_m);
  c.noise_window = static_cast<Real>(params[ParamId::kUwbNoiseWindow]);
  c.learn_noise = params[ParamId::kUwbLearnNoise] > 0.5F;
  // A changed prior (or learning switched off) restarts the estimate from it.
  if (sigma_prior != c.uwb_sigma_m || !c.learn_noise) {
    c.uwb_sigma_m = sigma_prior;
    r_los_m2_ = sigma_prior * sigma_prior;
    r_diff_m2_ = r_los_m2_;
    r_sh_m2_ = r_los_m2_;
    r_count_ = Real(0);
    r_sh_count_ = Real(0);
  }
  c.anchor_bias_sigma = static_cast<Real>(params[ParamId::kUwbAnchorBiasSigma]);
  c.tag_bias_sigma = static_cast<Real>(params[ParamId::kUwbTagBiasSigma]);
  c.scale_sigma = static_cast<Real>(params[ParamId::kUwbScaleSigma]);
  c.survey_sigma = static_cast<Real>(params[ParamId::kUwbSurveySigma]);
  c.bias_rw = static_cast<Real>(params[ParamId::kUwbBiasRw]);
  c.imu_timeout_us = param_us(params[ParamId::kInImuTimeoutUs]);
  c.uwb_timeout_us = param_us(params[ParamId::kInUwbTimeoutUs]);
  c.ground_constraints = params[ParamId::kEkfGroundConstraints] > 0.5F && site_.platform == Platform::kGround;
  c.nhc_sigma_lat = static_cast<Real>(params[ParamId::kEkfNhcSigmaLat]);
  c.nhc_sigma_vert = static_cast<Real>(params[ParamId::kEkfNhcSigmaVert]);
  c.pitch_gradient_rad_per_mps2 = static_cast<Real>(params[ParamId::kEkfPitchGradient]) * (kPi / Real(180));
  c.zupt_sigma = static_cast<Real>(params[ParamId::kEkfZuptSigma]);
  c.zaru_sigma = static_cast<Real>(params[ParamId::kEkfZaruSigma]);
  c.height_mode = static_cast<int>(std::lround(params[ParamId::kEkfHeightMode]));
  c.height_sigma = static_cast<Real>(params[ParamId::kEkfHeightSigma]);
  c.origin_height = static_cast<Real>(params[ParamId::kEkfOriginHeight]);
  c.constraint_period_us = param_us(1e6F / params[ParamId::kEkfConstraintRate]);
  c.cv_accel_psd = static_cast<Real>(params[ParamId::kEkfCvAccelPsd]);
  c.cv_yaw_psd = static_cast<Real>(params[ParamId::kEkfCvYawPsd]);
  c.cv_vel_tau = static_cast<Real>(params[ParamId::kEkfCvVelTau]);
  c.cv_vel_tau_us = param_us(params[ParamId::kEkfCvVelTau] * 1e6F);
  c.cv_speed_sigma = static_cast<Real>(params[ParamId::kEkfCvSpeedSigma]);
  c.cv_turn_psd = static_cast<Real>(params[ParamId::kEkfCvTurnPsd]);
  c.level_sigma = static_cast<Real>(params[ParamId::kEkfLevelSigma]);
  c.init_window_us = param_us(params[ParamId::kEkfInitWindow] * 1e6F);
  c.init_redundancy_wait_us = param_us(params[ParamId::kEkfInitRedundancyWait] * 1e6F);
  c.init_heading_dist = static_cast<Real>(params[ParamId::kEkfInitHeadingDist]);
  c.init_heading_timeout_us = param_us(params[ParamId::kEkfInitHeadingTimeout] * 1e6F);
  c.planar_spread = static_cast<Real>(params[ParamId::kEkfPlanarSpread]);
  c.diverge_nis = static_cast<Real>(params[ParamId::kEkfDivergeNis]);
  c.diverge_fraction = static_cast<Real>(params[ParamId::kEkfDivergeFraction]);
  c.diverge_window_us = param_us(params[ParamId::kEkfDivergeWindow] * 1e6F);
  c.recover_memory_us = param_us(params[ParamId::kEkfRecoverMemory] * 1e6F);
  c.degraded_sigma = static_cast<Real>(params[ParamId::kEkfDegradedSigma]);
  c.init_speed = static_cast<Real>(params[ParamId::kEkfInitSpeed]);
  c.init_yaw_sigma = static_cast<Real>(params[ParamId::kEkfInitYawSigma]);
  c.rbf_mode = static_cast<RbfMode>(std::lround(params[ParamId::kEkfRbfBridge]));
#if UWBNAV_GNSS
  c.gnss_enable = params[ParamId::kGnssEnable] > 0.5F;
  c.gnss_min_rank = static_cast<int>(std::lround(params[ParamId::kGnssMinQuality]));
  c.gnss_min_sv = static_cast<int>(std::lround(params[ParamId::kGnssMinSv]));
  c.gnss_max_sigma = static_cast<Real>(params[ParamId::kGnssMaxSigma]);
  c.gnss_sigma_scale = static_cast<Real>(params[ParamId::kGnssSigmaScale]);
  c.gnss_corr_time = static_cast<Real>(params[ParamId::kGnssCorrTime]);
  c.gnss_gate_sigma = static_cast<Real>(params[ParamId::kGnssGateSigma]);
  c.gnss_max_latency_us = param_us(params[ParamId::kGnssMaxLatency] * 1e6F);
  c.gnss_use_vel = params[ParamId::kGnssUseVel] > 0.5F;
#endif
#if UWBNAV_COOP
  c.coop_enable = params[ParamId::kCoopEnable] > 0.5F;
  c.coop_max_age_us = param_us(params[ParamId::kCoopMaxAge] * 1e6F);
  c.coop_max_sigma = static_cast<Real>(params[ParamId::kCoopMaxSigma]);
  c.coop_gate_sigma = static_cast<Real>(params[ParamId::kCoopGateSigma]);
  c.coop_accept_dependent = params[ParamId::kCoopAcceptDependent] > 0.5F;
  c.coop_hold_us = param_us(params[ParamId::kCoopHold] * 1e6F);
  c.coop_extrap_accel = static_cast<Real>(params[ParamId::kCoopExtrapAccel]);
  c.coop_corr_time = static_cast<Real>(params[ParamId::kCoopCorrTime]);
  c.coop_occluder_m = static_cast<Real>(params[ParamId::kCoopOccluderM]);
#endif
#if UWBNAV_RBF_BRIDGE
  bridge_.configure(c.rbf_mode);
#endif
  imu_eff_ = c.imu;
  apply_bias_rw_gains();
  rest_.configure(static_cast<Real>(params[ParamId::kEkfRestWindow]), static_cast<Real>(params[ParamId::kEkfRestAccelStd]),
                  static_cast<Real>(params[ParamId::kEkfRestGyroMax]));
  if (configured_) gating_.update_params(params);
}

const NavDiagnostics& Navigator::diagnostics() const { return diag_; }
size_t Navigator::num_anchors() const { return site_.num_anchors; }
const AnchorStatus& Navigator::anchor_status(size_t index) const {
  return anchor_status_[index < kMaxAnchors ? index : kMaxAnchors - 1];
}

AnchorOffset Navigator::anchor_offset(size_t index) const {
  AnchorOffset out;
  if (phase_ != Phase::kRunning || index >= kMaxAnchors || anchor_slot_[index] < 0) return out;
  const int i = ErrIdx::kAnchorBias + anchor_slot_[index];
  out.offset_m = static_cast<float>(ekf_.state().range_err(i - ErrIdx::kCore));
  out.sigma_m = static_cast<float>(std::sqrt(ekf_.cov()(i, i)));
  return out;
}

float Navigator::range_scale() const { return static_cast<float>(ekf_.state().range_scale()); }

void Navigator::reset() {
  ++diag_.operator_resets;
  restart(false);
  after_failure_ = false;
}

Vec3 Navigator::lever(int tag_index) const {
  if (tag_index < 0 || static_cast<size_t>(tag_index) >= site_.num_tags) return Vec3::Zero();
  return to_vec3(site_.tags[tag_index].lever_body_m);
}

Vec3 Navigator::model_lever(int tag_index) const {
  // Ranges-only filter with an unknown heading: the state is the tags'
  // centroid horizontally, so each tag sits at the centroid plus its vertical offset.
  const Vec3 lev = lever(tag_index);
  if (!cv_mode_ || cv_yaw_known_) return lev;
  const Mat3& c = ekf_.dcm();
  return c.transpose() * Vec3(0, 0, (c * lev).z());
}

Real Navigator::survey_sigma_m() const {
  // A commissioned offset already holds the survey error's projection on the
  // commissioning drive's lines of sight; what it leaves as the line of sight
  // turns is what the commissioning measured (docs/commissioning.md
  // "Systematic sigma"). Uncalibrated, or not measured: the survey's own sigma.
  const Real sys_m = site_.range_systematic_sigma_m;
  return std::isfinite(site_.range_offset_sigma_m) && std::isfinite(sys_m) ? sys_m : cfg_.survey_sigma;
}

Real Navigator::anchor_bias_prior_var() const {
  // Antenna delay (or the commissioned offset's residual) plus the survey error
  // along whatever line of sight the anchor is first seen on.
  const Real cal = site_.range_offset_sigma_m;
  const Real ad = std::isfinite(cal) ? cal : cfg_.anchor_bias_sigma;
  const Real survey = survey_sigma_m();
  return ad * ad + survey * survey;
}

Real Navigator::tag_bias_prior_var() const {
  const Real cal = site_.range_offset_sigma_m;
  const Real td = std::isfinite(cal) ? cal : cfg_.tag_bias_sigma;
  return td * td;
}

Real Navigator::known_offset_m(int anchor_index, int tag_index) const {
  if (anchor_index < 0 || tag_index < 0 || static_cast<size_t>(anchor_index) >= kMaxAnchors ||
      static_cast<size_t>(tag_index) >= kMaxTags) {
    return Real(0);
  }
  return static_cast<Real>(site_.range_offset_m[anchor_index][tag_index]);
}

Real Navigator::cv_accel_psd(uint64_t t_us) const {
  // The constant-velocity model's white acceleration must cover the vehicle's
  // actual acceleration: an IMU that is present (aligning, recovering) measures
  // its horizontal magnitude in the levelled frame, which enters with a 1 s
  // correlation time on top of the parameter (a car pulling away at 2 m/s^2
  // otherwise outruns a filter tuned for cruising).
  if (!imu_alive(t_us) || !levelled_) return cfg_.cv_accel_psd;
  return std::sqrt(cfg_.cv_accel_psd * cfg_.cv_accel_psd + accel_h_ms_ * kCvAccelCorrTime_s);
}

Navigator::CvModel Navigator::cv_model(uint64_t t_us) const {
  // Without an IMU nothing measures the acceleration: the velocity is a
  // mean-reverting prior (integrated Ornstein-Uhlenbeck, time constant
  // ekf.cv_vel_tau) whose stationary 1-sigma per axis, q sqrt(tau/2), covers
  // the platform's speeds (ekf.cv_speed_sigma): a pedestrian or a vehicle does
  // not hold its velocity through a long gap, and the claimed sigma stays
  // bounded by what the platform can do. With an IMU present (aligning,
  // recovering) its measured horizontal acceleration drives the white
  // acceleration instead, and a mean reversion would pull against a vehicle
  // pulling away: constant velocity (tau 0).
  CvModel m;
  m.accel_psd = cv_accel_psd(t_us);
  // A multicopter does not pull away like a car, and it cannot keep flying in
  // one direction: its velocity is the mean-reverting prior with an IMU too.
  if (imu_alive(t_us) && site_.platform != Platform::kAir) return m;
  m.vel_tau_s = cfg_.cv_vel_tau;
  m.accel_psd = std::fmax(m.accel_psd, cfg_.cv_speed_sigma * std::sqrt(Real(2) / m.vel_tau_s));
  // With a heading, the turn rate is a state too (no gyro measures it).
  if (cv_yaw_known_) m.turn_psd = cfg_.cv_turn_psd;
  // Nothing measures gravity: a ground vehicle's tilt is a prior about level,
  // in the centroid form (heading unknown) too. There the tags' vertical lever
  // still carries the attitude into the ranges, and without the prior the
  // tilt drifted (trolley3:6: 0.2 deg at 20 s, 150 deg from 60 s on), which put the
  // tags below the floor and grew the published sigma through the lever
  // circle: an honest-looking sigma for a wrong reason.
  if (site_.platform == Platform::kGround) m.level_sigma_rad = cfg_.level_sigma;
  return m;
}

bool Navigator::imu_alive(uint64_t t_us) const {
  return diag_.imu_samples > 0 && diff_us(t_us, diag_.last_imu_t_us) <= static_cast<int64_t>(cfg_.imu_timeout_us);
}

void Navigator::apply_bias_rw_gains() {
  const Real max_var_gain = cfg_.bias_rw_max_gain * cfg_.bias_rw_max_gain;
  for (Real& g : rw_var_gain_) g = std::fmin(std::fmax(g, Real(1)), max_var_gain);
  const Real gyro_gain = std::sqrt(rw_var_gain_[BiasWindow::kGyro]);
  const Real accel_gain = std::sqrt(rw_var_gain_[BiasWindow::kAccel]);
  imu_eff_.gyro_bias_rw = cfg_.imu.gyro_bias_rw * gyro_gain;
  imu_eff_.accel_bias_rw = cfg_.imu.accel_bias_rw * accel_gain;
  diag_.gyro_bias_rw_gain = static_cast<float>(gyro_gain);
  diag_.accel_bias_rw_gain = static_cast<float>(accel_gain);
}

void Navigator::learn_bias_instability(Real dt_s) {
  // Covariance matching (Mehra 1972) on the bias states, one window at a time
  // (BiasWindow): the window's summed corrections against the variance the
  // model gave them, ratio 1 when the bias walks as imu.*_bias_rw says. A bias
  // that wanders faster leaves corrections that add up: the ratio exceeds 1.
  // The gyro's ratio also pools the tilt corrections (a gyro walk the filter
  // explains as tilt). The windows' ratio, averaged with forgetting, moves the
  // random-walk variance gain per window by its square root (gyro) or fourth
  // root (accelerometer; damped: the gain changes the variance it is compared
  // with), between 1 (the parameters are the floor: a data-sheet figure) and
  // imu.bias_rw_max_gain^2.
  if (!(cfg_.bias_rw_max_gain > Real(1))) return;
  const NominalState& x = ekf_.state();
  const ErrCov& p = ekf_.cov();
  if (bias_win_.is_open()) {
    bias_win_.predicted(dt_s);
    // 5 s of IMU filter per window (tuning seeds 1-20: 10 and 20 s learn too
    // slowly to matter within a drive; docs/ekf.md).
    constexpr Real kWindow_s = Real(5);
    if (bias_win_.predicted_s() < kWindow_s) return;
    constexpr Real kForget = Real(0.7);    // weight of the previous windows' mean ratio
    constexpr Real kRatioMax = Real(100);  // one axis' ratio in one window at most
    const Real rw[2] = {imu_eff_.gyro_bias_rw, imu_eff_.accel_bias_rw};
    for (int b = 0; b < 2; ++b) {
      const Real ratio =
          bias_win_.ratio(static_cast<BiasWindow::Bias>(b), x, p, rw[b], kRatioMax, ekf_.tilt_tally());
      if (ratio < Real(0)) continue;  // no axis updated in the window
      corr_ratio_[b] = kForget * corr_ratio_[b] + (Real(1) - kForget) * ratio;
      // Square root for the gyro (pooled with the tilt; measured on tuning
      // seeds, docs/ekf.md), fourth root for the accelerometer.
      const Real step = std::sqrt(corr_ratio_[b]);
      rw_var_gain_[b] *= b == BiasWindow::kGyro ? step : std::sqrt(step);
    }
    apply_bias_rw_gains();
  }
  // A window starts: the biases, their variances and the tilt tally from here.
  bias_win_.open(x, p);
  ekf_.clear_tilt_tally();
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

  if (phase_ != Phase::kRunning || cv_mode_) {
    // Before the first fix and while the ranges-only filter publishes, the IMU
    // prepares the hand-over (levelling, relative attitude, yaw bank); an IMU
    // that comes back after a gap starts that preparation again.
    if (gap && phase_ == Phase::kRunning) begin_imu_recovery();
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
    if (phase_ == Phase::kRunning && !cv_mode_) {
      bridge_outage(imu.t_us, f_mean, w_mean, dt);
      learn_bias_instability(dt);
    }
  }
  prev_imu_ = imu;
  have_prev_imu_ = true;
  return Status::kOk;
}

void Navigator::apply_constraints(uint64_t t_us) {
  if (t_us - last_constraint_us_ < cfg_.constraint_period_us) return;
  last_constraint_us_ = t_us;
  if (height_on_) (void)fuse(mm_height(ekf_.state(), height_ref_m_, height_sigma_m_));
  if (cv_mode_) {
    // Ranges only. An IMU that is present (aligning, recovering) still tells
    // rest, on any platform (imu_still: quiet and unchanged specific force
    // since rest was confirmed by the LS track), with a slow filter. The rest
    // check ran at the same rate on the latest IMU sample (init_on_imu).
    if (imu_alive(t_us) && levelled_) {
      const bool slow =
          ekf_.state().vel_nav_mps.norm() < kZuptMaxSpeed_mps + Real(2) * std::sqrt(ekf_.cov()(3, 3));
      cv_rest_latched_ = imu_still_now_ && slow;
      if (cv_rest_latched_) {
        for (int i = 0; i < 3; ++i) (void)fuse(mm_zupt(ekf_.state(), i, cfg_.zupt_sigma));
        return;
      }
    }
    // Ground vehicles: the non-holonomic constraint ties the heading to the
    // velocity once the heading is known (lever arms of several tags, or the
    // direction of travel).
    if (cfg_.ground_constraints && cv_yaw_known_) {
      (void)fuse(mm_nhc(ekf_.state(), ekf_.dcm(), 1, cfg_.nhc_sigma_lat));
    }
    return;
  }
  if (site_.platform == Platform::kAir) {
    // The platform's speed prior (the ranges-only model's stationary velocity,
    // ekf.cv_speed_sigma per axis) as a pseudo-measurement once per velocity
    // correlation time (ekf.cv_vel_tau, so that successive ones are about
    // independent): it carries nothing while ranges hold the velocity to
    // centimetres per second, and bounds an IMU filter whose velocity the
    // sparse ranges no longer hold (a multicopter does not fly off at 50 m/s).
    if (last_speed_prior_us_ == 0 || t_us - last_speed_prior_us_ >= cfg_.cv_vel_tau_us) {
      last_speed_prior_us_ = t_us;
      for (int i = 0; i < 2; ++i) (void)fuse(mm_zupt(ekf_.state(), i, cfg_.cv_speed_sigma));
    }
  }
  if (!cfg_.ground_constraints) return;
  rest_.evaluate();
  // The IMU's spread alone cannot tell rest from constant velocity or a steady
  // brake: the filter speed must be small and the mean specific force vertical.
  const Vec3 f_nav = ekf_.dcm() * (rest_.accel_mean() - ekf_.state().ba_body_mps2);
  const bool at_rest = rest_.at_rest() && ekf_.state().vel_nav_mps.norm() < kZuptMaxSpeed_mps &&
                       f_nav.head<2>().norm() < kRestMaxHorizAccel_mps2;
  hold_rest_force_magnitude(at_rest);
  if (at_rest) {
    for (int i = 0; i < 3; ++i) {
      (void)fuse(mm_zupt(ekf_.state(), i, cfg_.zupt_sigma));
    }
    for (int i = 0; i < 3; ++i) {
      (void)fuse(mm_zaru(ekf_.state(), rest_.gyro_mean(), i, cfg_.zaru_sigma));
    }
  } else {
    (void)fuse(mm_nhc(ekf_.state(), ekf_.dcm(), 1, cfg_.nhc_sigma_lat));
    // Vertical NHC in the road frame: the suspension pitches the body nose
    // down by k a_lon when braking (k = ekf.pitch_gradient; a_lon from the
    // IMU sample before this one, along the horizontal heading: the rest
    // window's mean lags by a quarter second).
    const Vec3 f_now_nav = ekf_.dcm() * (to_vec3(prev_imu_.accel_body_mps2) - ekf_.state().ba_body_mps2);
    const Vec3 fwd_nav = ekf_.dcm().col(0);
    const Real fwd_h = fwd_nav.head<2>().norm();
    const Real a_lon_mps2 = fwd_h > Real(0.5) ? f_now_nav.head<2>().dot(fwd_nav.head<2>()) / fwd_h : Real(0);
    const Real road_pitch_rad = -cfg_.pitch_gradient_rad_per_mps2 * a_lon_mps2;
    (void)fuse(mm_nhc(ekf_.state(), ekf_.dcm(), 2, cfg_.nhc_sigma_vert, road_pitch_rad));
  }
}

void Navigator::set_rest_force_reference(const Vec3& up_body) {
  // The vertical balance was learnt here: the bias now, the body's vertical u.
  rest_force_up_body_ = up_body;
  rest_force_ref_bias_body_mps2_ = ekf_.state().ba_body_mps2;
  rest_force_curvature_mps2_ = Real(0);
  rest_force_ref_valid_ = true;
}

void Navigator::hold_rest_force_magnitude(bool at_rest) {
  // At rest the specific force is f = C^T g + b_a, so its magnitude gives
  // |f - b_a| = g: a sphere in bias space about f. The error state learns that
  // balance (zero-velocity updates at rest; the levelling with the vertical
  // constraints after it) as the sphere's tangent plane, normal to the body's
  // vertical u of the moment. When the vehicle turns, the horizontal bias and
  // the tilt separate (levelling took the one for the other) and the bias can
  // move across that plane by 1 m/s^2 with a consumer IMU; the sphere bends
  // away from the plane by d^2 / (g + sqrt(g^2 - d^2)) ~ d^2 / (2 g) along u,
  // 0.02-0.06 m/s^2, which the filter then reads as a vertical acceleration
  // under a bias sigma below 1 mm/s^2. Through the vertical NHC that tilts the
  // body and drives the along-track velocity (tuning outage:42 and :68: 7 and
  // 2.8 m off after 30 and 10 s without ranges, 40 and 22 % inside 2 sigma).
  // The bias moves along u by that term, the exact sphere's in place of the
  // plane's (a nominal-state projection, Simon and Chia 2002: the covariance
  // keeps the plane's information); moves along u, which other updates make
  // (the bias's walk), pass through unchanged.
  if (at_rest) {
    set_rest_force_reference(ekf_.dcm().row(2).transpose());
    return;
  }
  if (!rest_force_ref_valid_) return;
  const Real g = static_cast<Real>(site_.gravity_mps2);
  const Vec3& u = rest_force_up_body_;
  Vec3& ba = ekf_.mutable_state().ba_body_mps2;
  const Vec3 moved = ba - rest_force_ref_bias_body_mps2_;
  const Real d2 = (moved - u.dot(moved) * u).squaredNorm();  // NaN stays NaN
  // A move beyond 4 sigma of the bias prior on both horizontal axes is no
  // bias's but a diverging filter's: the projection would feed it (tried with
  // a tilt prior of sigma_b / g: tuning outage:39 rolled to 15 deg). What it
  // added goes, and so does the reference, until the next rest.
  const Real d2_max = Real(32) * cfg_.accel_bias_init * cfg_.accel_bias_init;
  const bool plausible = d2 < d2_max && d2 < Real(0.25) * g * g;  // false for NaN
  const Real curvature = plausible ? d2 / (g + std::sqrt(g * g - d2)) : Real(0);
  const Vec3 shift = (curvature - rest_force_curvature_mps2_) * u;
  ba += shift;
  // Not a correction of an update: the bias-instability window must not count it.
  bias_win_.shifted(BiasWindow::kAccel, shift);
  rest_force_curvature_mps2_ = curvature;
  if (!plausible) rest_force_ref_valid_ = false;
}

bool Navigator::fuse(const ScalarObs& obs) {
  // The ranges-only filter without an IMU learns no range error: its ranges
  // treat them as consider states (docs/ekf.md "Range errors"), and so do its
  // pseudo-measurements (height, NHC). Through the cross covariances those
  // consider updates build, a full update would move every offset with each
  // height innovation (measured on a self-calibrated trolley at rest: anchor
  // offsets 0.23 m off within 1 s, two anchors then gated out for good).
  return ekf_.update(obs, ranges_only_without_imu(t_state_us_)).applied;
}

void Navigator::bridge_outage(uint64_t t_us, const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps,
                              Real dt_s) {
#if UWBNAV_RBF_BRIDGE
  // Seed 004 fig. 3 on the error-state filter (docs/ekf.md "Outage bridging"):
  // the network learns while ranges are fused and, during an outage, gives a
  // horizontal position pseudo-measurement with its own error variance. Its
  // successive predictions share most of their error (same shadow, same
  // weights), so the k-th of an outage is fused with k times its variance:
  // N of them carry the information of H_N = 1 + 1/2 + ... + 1/N (< 4 for a
  // 30 s outage) predictions instead of N. A compromise, not a bound: the
  // share of the error inside the claimed 2 sigma (uwbnav eval outage) checks it.
  if (cfg_.rbf_mode == RbfMode::kOff) return;
  const uint64_t last_fix = diag_.last_range_used_t_us > running_since_us_ ? diag_.last_range_used_t_us : 0;
  bridge_.on_imu(t_us, accel_mean_body_mps2, gyro_mean_body_radps, dt_s, static_cast<Real>(site_.gravity_mps2),
                 ekf_.state(), last_fix);
  const bool outage = last_fix != 0 && t_us > last_fix && t_us - last_fix > cfg_.uwb_timeout_us;
  if (outage && (bridge_last_us_ == 0 || t_us - bridge_last_us_ >= kBridgePeriodUs)) {
    RbfBridge::Correction c;
    if (bridge_.predict(t_us, c)) {
      bridge_last_us_ = t_us;
      if (cfg_.rbf_mode == RbfMode::kOn) {
        ++bridge_count_;
        const Real z[2] = {c.pos_x_nav_m, c.pos_y_nav_m};
        const Real var[2] = {c.var_x_m2, c.var_y_m2};
        for (int axis = 0; axis < 2; ++axis) {
          const ScalarObs obs =
              mm_position(ekf_.state(), axis, z[axis], static_cast<Real>(bridge_count_) * var[axis]);
          const Real s_var = ekf_.innovation_variance(obs.h, obs.r_var);
          if (!(obs.r_var > Real(0)) ||
              !(obs.innovation * obs.innovation <= kBridgeGateSigma * kBridgeGateSigma * s_var)) {
            continue;
          }
          if (fuse(obs)) bridge_.note_fused();
        }
        check_health(false);
      }
    }
  }
  diag_.rbf = bridge_.diag();
#else
  (void)t_us;
  (void)accel_mean_body_mps2;
  (void)gyro_mean_body_radps;
  (void)dt_s;
#endif
}

void Navigator::check_health(bool after_predict) {
  if (!(after_predict ? ekf_.sanitise_after_predict() : ekf_.sanitise(false))) restart(true);
}

void Navigator::enter_cv_mode(NavMode reason) {
  // The IMU filter leaves: position, velocity, heading and range errors carry
  // on in the ranges-only model; tilt is levelled, IMU biases are dropped.
  cv_mode_ = true;
  cv_reason_ = reason;
  cv_yaw_known_ = true;
  cv_turn_rad_ = Real(0);
  ErrVec sigma = ErrVec::Zero();
  const Real yaw_sigma = std::sqrt(ekf_.cov()(ErrIdx::kAtt + 2, ErrIdx::kAtt + 2));
  sigma.segment<3>(ErrIdx::kAtt) = Vec3(Real(0.05), Real(0.05), yaw_sigma);
  sigma.segment<3>(ErrIdx::kBa).setConstant(cfg_.accel_bias_init);
  sigma.segment<3>(ErrIdx::kBg).setConstant(cfg_.gyro_bias_init);
  ekf_.decouple_inertial(sigma);
  ekf_.mutable_state().q_nav_body = quat_from_yaw(quat_yaw(ekf_.state().q_nav_body));
  ekf_.refresh_dcm();
  heading_wait_since_us_ = 0;
  if (reason == NavMode::kUwbOnly) cv_start_turn_rate();
}

int Navigator::lend_bias_slot(int anchor_index, uint64_t t_us) {
  if (anchor_index < 0 || static_cast<size_t>(anchor_index) >= kMaxAnchors) return -1;
  if (anchor_slot_[anchor_index] >= 0) return anchor_slot_[anchor_index];
  // A free slot, else the one whose anchor was ranged longest ago: its offset
  // estimate is dropped (marginalised), the new anchor starts from the prior.
  int best = 0;
  for (int s = 0; s < kBiasSlots; ++s) {
    if (slots_[s].anchor_index < 0) {
      best = s;
      break;
    }
    if (slots_[s].last_t_us < slots_[best].last_t_us) best = s;
  }
  if (slots_[best].anchor_index >= 0) anchor_slot_[slots_[best].anchor_index] = -1;
  slots_[best] = BiasSlot{};
  slots_[best].anchor_index = anchor_index;
  slots_[best].last_t_us = t_us;
  anchor_slot_[anchor_index] = static_cast<int8_t>(best);
  ekf_.reset_state(ErrIdx::kAnchorBias + best, anchor_bias_prior_var());
  return best;
}

void Navigator::range_error_process_noise(int slot, int anchor_index, int tag_index, uint64_t t_us,
                                          const Vec3& tag_pos_nav_m) {
  // The offsets drift slowly (random walk), and an anchor's offset changes as the
  // line of sight turns (survey error -u.da) and as the distance changes (the
  // pair's own scale error): docs/ekf.md "Range errors". Both are deterministic
  // in the geometry; a random walk in the angle turned and the distance changed
  // by each pair since its previous range (correlation lengths 1 rad and
  // kScaleCorrDist_m) carries them honestly without states of their own, and
  // never raises the offset's variance above its prior.
  const Real rw2 = cfg_.bias_rw * cfg_.bias_rw;
  if (slot >= 0) {
    BiasSlot& s = slots_[slot];
    Real q = t_us > s.last_t_us && s.last_t_us != 0 ? rw2 * seconds(diff_us(t_us, s.last_t_us)) : Real(0);
    if (prev_tag_valid_[anchor_index][tag_index]) {
      const Vec3 anchor = to_vec3(site_.anchors[anchor_index].pos_nav_m);
      const Vec3 d_now = tag_pos_nav_m - anchor;
      const Vec3 d_prev = prev_tag_pos_[anchor_index][tag_index] - anchor;
      const Real n_now = d_now.norm();
      const Real n_prev = d_prev.norm();
      if (n_now > Real(1e-3) && n_prev > Real(1e-3)) {
        const Real survey = survey_sigma_m();
        q += survey * survey * (d_now / n_now - d_prev / n_prev).norm() +
             cfg_.scale_sigma * cfg_.scale_sigma * kScaleCorrDist_m * std::fabs(n_now - n_prev);
      }
    }
    const int i = ErrIdx::kAnchorBias + slot;
    const Real room = anchor_bias_prior_var() - ekf_.cov()(i, i);
    if (room > Real(0) && q > Real(0)) ekf_.add_variance(i, std::fmin(q, room));
    s.last_t_us = t_us;
  }
  if (tag_index >= 0 && static_cast<size_t>(tag_index) < kMaxTags) {
    uint64_t& t_prev = tag_bias_t_us_[tag_index];
    if (t_prev != 0 && t_us > t_prev) ekf_.add_variance(ErrIdx::kTagBias + tag_index, rw2 * seconds(diff_us(t_us, t_prev)));
    t_prev = t_us;
  }
}

void Navigator::learn_noise(int anchor_index, int tag_index, uint64_t t_us, Real innovation, Real hph, bool fused) {
  // The LOS ranging variance R the filter uses is the larger of two on-line
  // estimates (docs/ekf.md "Learned ranging noise"), each averaged over
  // uwb.noise_window samples from fused ranges, squares winsorised at 3 sigma,
  // bounded by uwb.sigma_min/max:
  //  - differenced: half the squared change of a pair's innovation over at least
  //    kLearnLagUs, in which the pair's offset, survey and scale errors and the
  //    filter's own error cancel: the white part of the ranging error, right
  //    even while the offset states are pessimistic (consider);
  //  - Sage-Husa: nu^2 - H P H^T, which also sees ranging errors correlated
  //    over seconds (real multipath) that the differences miss, but reads a
  //    pessimistic covariance as missing noise (hence the max, not either alone).
  if (!fused) return;
  const Real lo = cfg_.uwb_sigma_min_m * cfg_.uwb_sigma_min_m;
  const Real hi = cfg_.uwb_sigma_max_m * cfg_.uwb_sigma_max_m;
  if (cfg_.learn_noise && hph < kLearnMaxHphRatio * r_los_m2_) {
    const Real s = hph + r_los_m2_;
    const Real sample = std::fmin(innovation * innovation, kLearnClip * s) / kLearnClipMeanTrunc - hph;
    if (r_sh_count_ < cfg_.noise_window) r_sh_count_ += Real(1);
    r_sh_m2_ += (sample - r_sh_m2_) / (r_sh_count_ + kLearnPriorCount);
    r_sh_m2_ = std::fmin(std::fmax(r_sh_m2_, lo), hi);
  }
  PrevInnovation& ref = prev_innov_[anchor_index][tag_index];
  if (ref.t_us == 0 || t_us <= ref.t_us || t_us - ref.t_us > kLearnMaxPairGapUs) {
    ref = PrevInnovation{t_us, static_cast<float>(innovation)};
  } else if (t_us - ref.t_us >= kLearnLagUs) {
    const Real d = innovation - static_cast<Real>(ref.innovation_m);
    ref = PrevInnovation{t_us, static_cast<float>(innovation)};
    if (cfg_.learn_noise) {
      const Real sample = std::fmin(Real(0.5) * d * d, kLearnClip * r_los_m2_) / kLearnClipMean;
      if (r_count_ < cfg_.noise_window) r_count_ += Real(1);
      r_diff_m2_ += (sample - r_diff_m2_) / (r_count_ + kLearnPriorCount);
      r_diff_m2_ = std::fmin(std::fmax(r_diff_m2_, lo), hi);
    }
  }
  if (!cfg_.learn_noise) return;
  r_los_m2_ = std::fmax(r_diff_m2_, r_sh_m2_);
  diag_.uwb_sigma_m = static_cast<float>(std::sqrt(r_los_m2_));
}

bool Navigator::advance_cv(uint64_t t_us) {
  if (!cv_mode_ || t_us <= t_state_us_) return true;
  const CvModel m = cv_model(t_us);
  const Real dt_cv = seconds(diff_us(t_us, t_state_us_));
  // A levelled IMU's turn about the vertical since the last step turns a
  // ground vehicle's velocity and heading (none accumulates without one).
  const Real turn_rad = imu_alive(t_us) ? cv_turn_rad_ : Real(0);
  cv_turn_rad_ = Real(0);
  ekf_.predict_cv(dt_cv, m.accel_psd, cfg_.cv_yaw_psd, m.vel_tau_s, m.turn_psd, turn_rad);
  if (m.level_sigma_rad > Real(0)) ekf_.predict_level(dt_cv, m.level_sigma_rad, kLevelTau_s);
  t_state_us_ = t_us;
  check_health();
  if (phase_ != Phase::kRunning) return false;
  apply_constraints(t_us);
  // Ground vehicles point where they go: a well-determined velocity gives the
  // heading of the ranges-only filter (from then on the NHC keeps it).
  const Vec3& v = ekf_.state().vel_nav_mps;
  const Real speed = v.head<2>().norm();
  const Real vel_sigma = std::sqrt(ekf_.cov()(ErrIdx::kVel, ErrIdx::kVel) + ekf_.cov()(ErrIdx::kVel + 1, ErrIdx::kVel + 1));
  if (!cv_yaw_known_ && cfg_.ground_constraints && speed > kCvHeadingMinSpeed_mps && vel_sigma < Real(0.25) * speed) {
    cv_set_yaw(std::atan2(v.y(), v.x()), std::atan2(vel_sigma, speed) + kCvHeadingSlip_rad);
  }
  return true;
}

RangeReport Navigator::on_range(const UwbRange& range) {
  RangeReport rep;
  rep.t_us = range.t_us;
  rep.anchor_id = range.anchor_id;
  rep.tag_id = range.tag_id;
  rep.range_m = range.range_m;
  if (!configured_) return rep;
  ++diag_.ranges_received;
#if UWBNAV_COOP
  if (is_vehicle_id(range.anchor_id)) return on_neighbour_range(range, rep);
#endif
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
  const bool jumped = range_jumped(pair_[ai][ti], range.t_us, range.range_m);
  pair_[ai][ti] = PairRange{range.t_us, range.range_m, true, jumped};
  range_rate_on_range(ai, ti, range.t_us, range.range_m);

  if (phase_ != Phase::kRunning) {
    // No filter yet: the first LS fix starts the ranges-only filter at once.
    TrackFix fix;
    if (init_track(ai, ti, range)) {
      fix = last_fix_per_tag_[ti];
      start_cv_filter(range.t_us, fix, site_.has_imu ? NavMode::kAligning : NavMode::kUwbOnly, Vec2::Zero());
    }
    ++diag_.ranges_rejected;
    ++cycle_rejected_;
    return rep;
  }

  if (!cv_mode_ && !imu_alive(range.t_us)) enter_cv_mode(NavMode::kUwbOnly);
  if (!advance_cv(range.t_us)) return rep;

  const int slot = lend_bias_slot(ai, range.t_us);
  RangeErrorSlots es;
  es.tag_index = ti;
  es.anchor_slot = slot;
  es.known_offset_m = known_offset_m(ai, ti);
  RangeContext ctx;
  ctx.range = range;
  ctx.anchor_index = ai;
  ctx.anchor_pos_nav_m = site_.anchors[ai].pos_nav_m;
  const Real dt_r = seconds(diff_us(range.t_us, t_state_us_));
  const RangePrediction pred =
      mm_range_predict(ekf_.state(), ekf_.dcm(), cv_mode_ ? Vec3::Zero() : last_gyro_body_radps_, model_lever(ti),
                       to_vec3(ctx.anchor_pos_nav_m), dt_r, es);
  // Heading unknown (centroid form) without an IMU: the tag lies on its
  // lever's circle about the tags' centroid, uniform in azimuth, so its
  // horizontal offset rho adds rho^2 / 2 along the horizontal line of sight to
  // the range's variance (as in the published sigma and the integrity check).
  // Not while an IMU aligns: measured on the real multicopter (miluv, 1 range
  // per second) it weakens the sparse ranges the in-flight alignment needs
  // (RMSE 1.33 -> 2.22 m), and that filter hands over to the IMU filter anyway.
  const bool without_imu = ranges_only_without_imu(range.t_us);
  Real r_nom = r_los_m2_;
  if (without_imu && !cv_yaw_known_ && pred.valid) {
    const Real rho2 = (lever(ti) - mean_lever()).head<2>().squaredNorm();
    r_nom += Real(0.5) * rho2 * pred.los_nav.head<2>().squaredNorm();
  }
  ctx.meas_var_m2 = static_cast<float>(r_nom);
  Real s_nom = Real(0);
  Real hph = Real(0);
  if (pred.valid) {
    range_error_process_noise(slot, ai, ti, range.t_us, pred.tag_pos_nav_m);
    hph = ekf_.prepare(pred.h);
    s_nom = hph + r_nom;
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
    ctx.filter_ready = sig_h < cfg_.degraded_sigma;
    // Its range errors are consider states for the whole drive: a long
    // innovation may be a pair's unlearned offset (docs/nlos.md). The aligning
    // filter (IMU present) fuses ranges as consider too, but for seconds only,
    // and keeps the full evidence: clipped there as well, tuning seeds 1-60
    // gave 44 drives better and 39 worse (air_indoor worst 0.271 -> 0.343 m).
    ctx.innovation_is_evidence = !without_imu;
    ctx.inertial = !cv_mode_;
  }

  const GatingDecision d = gating_.assess(ctx);
  bool used = false;
  const Real innov = pred.valid ? static_cast<Real>(range.range_m) - pred.range_m : Real(0);
  // Hard guard behind the gating layer: a range this far off is a gross error
  // whatever the policy says (a drifted filter is recovered by the divergence
  // monitor instead of being dragged by blunders). The gating layer's escape
  // (robust mode) exists for a filter that drifted from its own gate: the
  // guard must not undo it.
  const bool escape = gating_.escape_active() && d.use;
  const bool gross = !escape && std::fabs(innov) > kHardGateSigma * std::sqrt(s_nom) && std::fabs(innov) > kHardGateMin_m;
  const Real scale = std::isfinite(d.r_scale) && d.r_scale >= 1.0F ? static_cast<Real>(d.r_scale) : Real(1);
  if (pred.valid && d.use && !gross) {
    // Offsets are learnt only from ranges the gate trusts, fused by a filter in
    // its nominal model, while the vehicle moves: an NLOS range let in by the
    // robust mode or fused while the heading is unknown would otherwise be
    // remembered as an antenna offset, and at rest an offset cannot be told
    // from the vehicle's position or from the steady NLOS bias of an anchor
    // hidden behind something while the vehicle waits. Such ranges treat the
    // range errors as consider states (docs/ekf.md "Range errors").
    const bool nominal = !cv_mode_;
    const bool moving = ekf_.state().vel_nav_mps.head<2>().norm() > kLearnOffsetMinSpeed_mps;
    // A symmetric window on the innovation keeps the learnt offsets unbiased:
    // the gate removes long (NLOS-like) ranges only, so learning from every
    // fused range would see the short side of the noise and drift negative.
    const bool central = std::fabs(innov) < kLearnOffsetMaxZ * std::sqrt(s_nom);
    const bool learn_offsets = nominal && moving && central && !escape && !d.bound;
    const Real r_add = std::isfinite(d.r_add_m2) && d.r_add_m2 > 0.0F ? static_cast<Real>(d.r_add_m2) : Real(0);
    const Real r_var = r_nom * scale + r_add;
    const Real excess = std::isfinite(d.excess_m) ? static_cast<Real>(d.excess_m) : Real(0);
    const Real innov_fused = iterated_range_innovation(pred, static_cast<Real>(range.range_m) - excess, innov - excess,
                                                       hph, r_var, ti, ai, dt_r, es);
    used = ekf_.update_prepared(innov_fused, r_var, !learn_offsets).applied;
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

  if (used) {
    ++as.used_count;
    ++diag_.ranges_used;
    ++cycle_used_;
    diag_.last_range_used_t_us = range.t_us;
#if UWBNAV_RBF_BRIDGE
    if (!cv_mode_) bridge_.on_fix(range.t_us, ekf_.state());
    bridge_last_us_ = 0;
    bridge_count_ = 0;
#endif
  } else {
    ++diag_.ranges_rejected;
    ++cycle_rejected_;
  }
  if (pred.valid) {
    prev_tag_pos_[ai][ti] = pred.tag_pos_nav_m;
    prev_tag_valid_[ai][ti] = true;
    learn_noise(ai, ti, range.t_us, innov, hph, used && !escape && !d.bound);
    monitor_divergence(range.t_us, innov * innov / s_nom);
    if (phase_ == Phase::kRunning) short_range_test(range.t_us, ai, innov, s_nom);
  }
  check_health(false);
  if (phase_ == Phase::kRunning) integrity_check(range.t_us, ti);
  if (phase_ == Phase::kRunning && cv_mode_) {
    if (imu_alive(range.t_us)) {
      align_in_background(ai, ti, range);
    } else if (!cv_yaw_known_ && site_.num_tags > 1) {
      // Several tags and no IMU: the heading comes from the tags' baseline.
      if (init_track(ai, ti, range)) try_heading(range.t_us);
    }
  }
  return rep;
}

Real Navigator::iterated_range_innovation(const RangePrediction& first, Real range_m, Real innovation_m, Real hph_m2,
                                          Real r_var_m2, int tag_index, int anchor_index, Real dt_s,
                                          const RangeErrorSlots& slots) {
  // Iterated update (IEKF: Gauss-Newton on the scalar range; Bell & Cathey,
  // IEEE TAC 1993). The first-order update takes the range as linear in the
  // position; where its correction dp moves the tag across the line of sight
  // by d, the range circle bends away by d^2 / (2 r) over that step, and where
  // that exceeds kIekfCurvSigma range sigmas the step is recomputed from the
  // prior with the range re-linearised at the corrected position, until the
  // position step settles (kIekfSettle_m) or after kIekfMaxIter
  // re-linearisations. The range is linear in every other state to well
  // within its noise (velocity over a few ms, attitude through a lever arm,
  // additive offsets), so only the position is moved: with x_i = x + dp_i,
  //   innovation_i = z - h(x_i) + H_i,p dp_i,
  // fused with the Jacobian H_i of the last prepare(), applies the Gauss-Newton
  // step dx_{i+1} to the prior and takes the covariance from H_i. The
  // iteration only ever shrinks the first-order position step: where it would
  // lengthen it (the circle bending towards the step, a mirror position of
  // two anchors) the first-order update stands. Nominal ranges (centimetre
  // steps) return at the first test. Element loops, not Eigen block
  // expressions: this runs rarely and its code counts against the M4F flash
  // budget (docs/footprint.md).
  const Real s0 = hph_m2 + r_var_m2;
  if (!(s0 > Real(0)) || !first.valid) return innovation_m;
  const Real curv_max = kIekfCurvSigma * std::sqrt(r_var_m2);
  const ErrVec& k = ekf_.prepared_cov_h();
  Real c = innovation_m / s0;  // the position step is c P_p H^T of the last prepare()
  Real innov = innovation_m;
  Real u[3] = {first.los_nav(0), first.los_nav(1), first.los_nav(2)};
  Real r = first.geometric_m;
  Real first_step2 = Real(0);
  for (int i = 0; i < 3; ++i) first_step2 += k(ErrIdx::kPos + i) * k(ErrIdx::kPos + i) * c * c;
  for (int it = 0; it < kIekfMaxIter; ++it) {
    Real dp[3], along = Real(0), step2 = Real(0);
    for (int i = 0; i < 3; ++i) {
      dp[i] = k(ErrIdx::kPos + i) * c;
      along += u[i] * dp[i];
      step2 += dp[i] * dp[i];
    }
    if (!((step2 - along * along) / (Real(2) * r) > curv_max)) break;
    // The prediction at x + dp, on the filter's own state (no copy of it):
    // its position is moved and restored bit for bit.
    Vec3& pos = ekf_.mutable_state().pos_nav_m;
    const Vec3 pos0 = pos;
    for (int i = 0; i < 3; ++i) pos(i) += dp[i];
    const RangePrediction pi = mm_range_predict(ekf_.state(), ekf_.dcm(), cv_mode_ ? Vec3::Zero() : last_gyro_body_radps_,
                                                model_lever(tag_index), to_vec3(site_.anchors[anchor_index].pos_nav_m),
                                                dt_s, slots);
    pos = pos0;
    if (!pi.valid) break;
    Real innov_i = range_m - pi.range_m;
    for (int i = 0; i < 3; ++i) innov_i += pi.h(ErrIdx::kPos + i) * dp[i];
    const Real s = ekf_.prepare(pi.h) + r_var_m2;  // k is now P H_i^T
    const Real c_i = innov_i / s;
    Real next2 = Real(0), moved2 = Real(0);
    for (int i = 0; i < 3; ++i) {
      const Real n = k(ErrIdx::kPos + i) * c_i;
      next2 += n * n;
      moved2 += (n - dp[i]) * (n - dp[i]);
      u[i] = pi.los_nav(i);
    }
    if (!(next2 <= first_step2)) {
      (void)ekf_.prepare(first.h);
      return innovation_m;
    }
    c = c_i;
    innov = innov_i;
    r = pi.geometric_m;
    ++diag_.iterated_updates;
    if (moved2 < kIekfSettle_m * kIekfSettle_m) break;
  }
  return innov;
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
    recover(t_us);
  }
}

void Navigator::integrity_check(uint64_t t_us, int tag_index) {
  // Seed 001 RAIM turned on the filter itself (docs/ekf.md "Integrity check"):
  // at most every kIntegrityPeriodUs, an LS fix from the latest range of each
  // anchor to this tag, each moved to now along its line of sight with the
  // filter's velocity, with at least two degrees of freedom so that the fix can
  // check itself and exclude one bad range. A filter whose tag position differs
  // from that fix by more than the two covariances explain (chi-square, 2 dof,
  // 99.9 %) has left its ranges - typically by rejecting, as NLOS, the very
  // ranges that would correct it: it is re-anchored to the fix.
  if (last_integrity_us_ != 0 && t_us - last_integrity_us_ < kIntegrityPeriodUs) return;
  last_integrity_us_ = t_us;
  const NominalState& x = ekf_.state();
  const Real dt = seconds(diff_us(t_us, t_state_us_));
  const Vec3 lev = model_lever(tag_index);
  const Vec3 tag_nav = x.pos_nav_m + x.vel_nav_mps * dt + ekf_.dcm() * lev;
  const Real vel_var = ekf_.cov()(3, 3) + ekf_.cov()(4, 4);
  LsRange ranges[kMaxAnchors];
  size_t n = 0;
  Real min_z_short = Real(0);
  for (size_t a = 0; a < site_.num_anchors; ++a) {
    const PairRange& pr = pair_[a][tag_index];
    if (!pr.valid || t_us < pr.t_us || t_us - pr.t_us > kIntegrityMaxAgeUs) continue;
    const Vec3 anchor = to_vec3(site_.anchors[a].pos_nav_m);
    const Vec3 diff = tag_nav - anchor;
    const Real dist = diff.norm();
    if (!(dist > Real(1e-3))) continue;
    const Real age_s = seconds(diff_us(t_us, pr.t_us));
    const Real moved = (diff / dist).dot(x.vel_nav_mps) * age_s;
    ranges[n].anchor_pos_nav_m = site_.anchors[a].pos_nav_m;
    ranges[n].range_m = static_cast<float>(static_cast<Real>(pr.range_m) -
                                           known_offset_m(static_cast<int>(a), tag_index) + moved);
    ranges[n].sigma_m =
        static_cast<float>(std::sqrt(r_los_m2_ + anchor_bias_prior_var() + vel_var * age_s * age_s));
    // NLOS only lengthens a range: a filter that has left its ranges shows a
    // range clearly shorter than its predicted distance.
    const Vec3 u = diff / dist;
    Real var_short = static_cast<Real>(ranges[n].sigma_m) * static_cast<Real>(ranges[n].sigma_m);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) var_short += u(i) * ekf_.cov()(ErrIdx::kPos + i, ErrIdx::kPos + j) * u(j);
    }
    const Real z_short = (static_cast<Real>(ranges[n].range_m) - dist) / std::sqrt(var_short);
    if (z_short < min_z_short) min_z_short = z_short;
    ++n;
  }
  LsOptions opt;
  opt.two_d = planar_;
  opt.known_z_m = static_cast<float>(tag_nav.z());
  opt.has_initial_guess = true;
  opt.initial_guess_nav_m = to_vec3f(tag_nav);
  if (n < (opt.two_d ? 4U : 5U)) return;  // two degrees of freedom at least
  LsFix ls;
  if (robust_ls_fix(ranges, n, opt, ls) != Status::kOk) return;  // the epoch itself is inconsistent
  // The fix must pass its own chi-square at 99.9 % (stricter than the start-up
  // test): an epoch with an NLOS range left in is no reference.
  constexpr Real kChi2_999[8] = {Real(10.83), Real(13.82), Real(16.27), Real(18.47),
                                 Real(20.52), Real(22.46), Real(24.32), Real(26.12)};
  if (ls.dof < 1 || !ls.converged || static_cast<Real>(ls.weighted_ssr) > kChi2_999[ls.dof > 8 ? 7 : ls.dof - 1]) return;
  const Real dx = static_cast<Real>(ls.pos_nav_m.x) - tag_nav.x();
  const Real dy = static_cast<Real>(ls.pos_nav_m.y) - tag_nav.y();
  Vec3 lev_nav = ekf_.dcm() * lev;
  // Heading unknown: the tag lies anywhere on its lever's circle about the
  // tags' centroid (the state); otherwise the heading's variance turns the lever.
  const Real lever_var = cv_mode_ && !cv_yaw_known_
                             ? (lever(tag_index) - mean_lever()).head<2>().squaredNorm()
                             : lev_nav.head<2>().squaredNorm() * ekf_.cov()(ErrIdx::kAtt + 2, ErrIdx::kAtt + 2);
  const Real cxx = static_cast<Real>(ls.cov_nav_m2[0][0]) + ekf_.cov()(0, 0) + lever_var;
  const Real cyy = static_cast<Real>(ls.cov_nav_m2[1][1]) + ekf_.cov()(1, 1) + lever_var;
  const Real cxy = static_cast<Real>(ls.cov_nav_m2[0][1]) + ekf_.cov()(0, 1);
  const Real det = cxx * cyy - cxy * cxy;
  if (!(det > Real(0))) return;
  const Real chi2 = (cyy * dx * dx - Real(2) * cxy * dx * dy + cxx * dy * dy) / det;
  if (!(chi2 > kIntegrityChi2)) return;
  if (!(min_z_short < -kIntegrityShortSigma)) return;  // explained by NLOS-lengthened ranges
  ++diag_.integrity_fails;
  cover_gap(t_us, dx * dx + dy * dy);
}

void Navigator::cover_gap(uint64_t t_us, Real gap_m2) {
  // The filter's claim does not cover its distance to what the ranges say:
  // enlarge the claim to cover it (the gate then lets the ranges that would
  // correct the filter back in). Repeated failures escalate through recover().
  const bool recent = last_recovery_us_ != 0 && t_us - last_recovery_us_ < cfg_.recover_memory_us;
  if (recent) {
    recover(t_us);  // which marks the filter unverified too
    return;
  }
  gating_.on_filter_unverified();
  ++diag_.inflations;
  last_recovery_us_ = t_us;
  recovery_level_ = 1;
  ekf_.inflate_to(ErrIdx::kPos, 2, gap_m2);
  ekf_.inflate_to(ErrIdx::kVel, 2, gap_m2 * Real(0.25));
}

void Navigator::clear_short_range_test() {
  short_count_ = 0;
  short_anchor_mask_ = 0;
  short_gap_m2_ = Real(0);
  for (auto& r : short_run_) r = 0;
}

void Navigator::short_range_test(uint64_t t_us, int anchor_index, Real innovation_m, Real innovation_var_m2) {
  // NLOS only lengthens a range (docs/ekf.md "Short-range test"): a range
  // shorter than predicted by more than kShortSigma standard deviations has a
  // probability of about 3e-7 from a consistent filter. Such ranges from at
  // least two anchors in a row, with no consistent range in between, say the
  // filter has left its ranges; this test needs no simultaneous ranges, so it
  // also watches sparse ranging, where the integrity check's LS fix never forms.
  // A consistent range from one anchor does not clear another anchor's run:
  // an error across its own line of sight is invisible to it.
  if (!(innovation_var_m2 > Real(0))) return;
  const bool indexed = anchor_index >= 0 && static_cast<size_t>(anchor_index) < kMaxAnchors;
  const Real z = innovation_m / std::sqrt(innovation_var_m2);
  if (!(z < -kShortSigma)) {
    if (std::fabs(z) < kShortResetSigma) {
      short_count_ = 0;
      short_anchor_mask_ = 0;
      short_gap_m2_ = Real(0);
      if (indexed) short_run_[anchor_index] = 0;
    }
    return;  // long ranges may be NLOS: they neither count nor clear
  }
  ++short_count_;
  short_anchor_mask_ |= 1U << (anchor_index < 31 ? anchor_index : 31);
  short_gap_m2_ = std::fmax(short_gap_m2_, innovation_m * innovation_m);
  Real run_gap_m2 = Real(0);
  bool anchor_run = false;
  if (indexed) {
    uint8_t& run = short_run_[anchor_index];
    if (run < kShortAnchorRun) ++run;
    anchor_run = run >= kShortAnchorRun;
    run_gap_m2 = innovation_m * innovation_m;
  }
  const bool two_anchors = (short_anchor_mask_ & (short_anchor_mask_ - 1U)) != 0U;
  if (!anchor_run && (short_count_ < kShortMinRanges || !two_anchors)) return;
  ++diag_.short_range_fails;
  const Real gap = std::fmax(short_gap_m2_, run_gap_m2);
  clear_short_range_test();
  cover_gap(t_us, gap);
}

void Navigator::recover(uint64_t t_us, uint8_t min_level) {
  // Recovery without a reset (docs/ekf.md "Recovery"): each divergence that
  // follows the previous one within recover_memory escalates one step. Output
  // continues throughout; nothing here discards the solution.
  const bool recent = last_recovery_us_ != 0 && t_us - last_recovery_us_ < cfg_.recover_memory_us;
  uint8_t level = recent ? static_cast<uint8_t>(recovery_level_ + 1) : uint8_t(1);
  if (level < min_level) level = min_level;
  last_recovery_us_ = t_us;
  recovery_level_ = level > 3 ? uint8_t(3) : level;
  gating_.on_filter_unverified();
#if UWBNAV_RBF_BRIDGE
  // The filter was inconsistent (and may jump now): windows in flight measure nothing.
  bridge_.restart_shadows();
#endif
  monitor_head_ = 0;
  monitor_count_ = 0;
  clear_short_range_test();
  const Real anchor_var = anchor_bias_prior_var();
  if (level == 1) {
    // 1. Inflate: the covariance was too small for what the ranges say.
    ++diag_.inflations;
    ekf_.inflate_to(ErrIdx::kPos, 2, kInflatePosVar_m2);
    ekf_.inflate_to(ErrIdx::kVel, 2, kInflateVelVar_m2ps2);
    if (!cv_mode_) ekf_.inflate_to(ErrIdx::kAtt + 2, 1, kInflateYawVar_rad2);
    ekf_.inflate_to(ErrIdx::kTagBias, static_cast<int>(kMaxTags), tag_bias_prior_var());
    ekf_.inflate_to(ErrIdx::kAnchorBias, kBiasSlots, anchor_var);
    return;
  }
  // A fresh LS fix from the latest range of each anchor, for steps 2 and 3.
  TrackFix fix;
  int tag = -1;
  const size_t n_tags = site_.num_tags == 0 ? 1 : site_.num_tags;
  for (size_t t = 0; t < n_tags && t < kMaxTags && tag < 0; ++t) {
    if (try_ls_fix(t_us, static_cast<int>(t), fix)) tag = static_cast<int>(t);
  }
  if (tag < 0) {
    // Nothing to re-anchor to: inflate again.
    ++diag_.inflations;
    ekf_.inflate_to(ErrIdx::kPos, 2, kInflatePosVar_m2);
    ekf_.inflate_to(ErrIdx::kVel, 2, kInflateVelVar_m2ps2);
    return;
  }
  if (level == 2) {
    // 2. Re-anchor position and velocity to the fix; attitude and IMU biases
    // stay, the range errors go back to their priors.
    ++diag_.reanchors;
    NominalState& x = ekf_.mutable_state();
    x.pos_nav_m = fix.tag_pos_nav_m - ekf_.dcm() * model_lever(tag);
    const Real pos_h = std::sqrt(Real(0.5)) * fix.sigma_h_m + Real(0.05);
    const Real pos_v = fix.sigma_v_m > Real(0) ? fix.sigma_v_m : std::sqrt(ekf_.cov()(2, 2));
    for (int i = 0; i < 3; ++i) ekf_.reset_state(ErrIdx::kPos + i, i < 2 ? pos_h * pos_h : pos_v * pos_v);
    for (int i = 0; i < 2; ++i) ekf_.reset_state(ErrIdx::kVel + i, kReanchorVelSigma_mps * kReanchorVelSigma_mps);
    ekf_.inflate_to(ErrIdx::kTagBias, static_cast<int>(kMaxTags), tag_bias_prior_var());
    ekf_.inflate_to(ErrIdx::kAnchorBias, kBiasSlots, anchor_var);
    if (!cv_mode_) ekf_.inflate_to(ErrIdx::kAtt + 2, 1, kInflateYawVar_rad2);
    return;
  }
  // 3. Re-align (counted as a re-initialisation). The IMU filter's heading is
  // not trusted any more: the ranges-only filter, re-anchored to the fix,
  // publishes (recovering) while levelling and heading are acquired again;
  // attitude and gyro bias seed the relative attitude. A diverged ranges-only
  // filter simply starts again from the fix, from zero velocity (its velocity
  // is what diverged). The IMU filter's horizontal velocity is the restarted
  // filter's prior mean (at the start's sigma): the ranges observe the
  // nav-frame velocity whatever the heading, and a zero mean claimed a car
  // driving at 5.6 m/s to 2.8 sigma (docs/ekf.md "Ladder").
  ++diag_.reinits;
  const NavMode reason = cv_mode_ ? cv_reason_ : NavMode::kRecovering;
  Vec2 vel_prior_mps = Vec2::Zero();
  if (!cv_mode_) {
    if (ekf_.state().vel_nav_mps.allFinite()) vel_prior_mps = ekf_.state().vel_nav_mps.head<2>();
    q_init_ = ekf_.state().q_nav_body;
    bg_init_ = ekf_.state().bg_body_radps;
    bg_ref_ = bg_init_;
    ba_init_ = ekf_.state().ba_body_mps2;
    levelled_ = true;
    levelled_t_us_ = t_us;  // the gyro bias's drift of that attitude counts from now
    // That attitude comes from a filter that failed, not from a rest window:
    // it is handed over again with the moving-levelling uncertainty.
    levelled_at_rest_ = false;
    // The track's relative yaws refer to the old levelled attitude.
    track_head_ = 0;
    track_count_ = 0;
    for (auto& f : last_fix_per_tag_) f = TrackFix{};
  }
  // A ranges-only filter that re-starts keeps the LS track: its fixes do not
  // depend on the filter, and it is the evidence of motion the rest check needs.
  heading_avg_ = HeadingAverage{};
  gsf_.reset();
  start_cv_filter(t_us, fix, reason, vel_prior_mps);
  recovery_level_ = 3;
  last_recovery_us_ = t_us;
}

NavOutput Navigator::output(uint64_t t_us) {
  NavOutput out;
  out.t_us = t_us;
  out.resets = diag_.resets;
  out.ranges_used = cycle_used_;
  out.ranges_rejected = cycle_rejected_;
  cycle_used_ = 0;
  cycle_rejected_ = 0;
  constexpr float kUnknownSigma_m = kNaNf;
  out.pos_nav_m = Vec3f{kNaNf, kNaNf, kNaNf};
  out.vel_nav_mps = Vec3f{kNaNf, kNaNf, kNaNf};
  out.pos_sigma_m = Vec3f{kUnknownSigma_m, kUnknownSigma_m, kUnknownSigma_m};
  out.vel_sigma_mps = out.pos_sigma_m;
  out.heading_rad = kNaNf;
  if (!configured_) {
    out.status = NavStatus::kInvalid;
    return out;
  }
  if (phase_ == Phase::kRunning && !cv_mode_ && !imu_alive(t_us) && diff_us(t_us, t_state_us_) > 0 &&
      t_us - t_state_us_ > cfg_.imu_timeout_us) {
    enter_cv_mode(NavMode::kUwbOnly);
  }
  if (phase_ != Phase::kRunning) {
    // No filter: never a position that is not an estimate (NaN, status says why).
    out.status = after_failure_ ? NavStatus::kInvalid : NavStatus::kInitialising;
    out.mode = NavMode::kNone;
    return out;
  }
  const NominalState& x = ekf_.state();
  const ErrCov& p = ekf_.cov();
  // Extrapolate to the output time (the state is at the last IMU sample or range).
  const Real dt = seconds(diff_us(t_us, t_state_us_));
  // The IMU filter is at most one IMU interval old; the ranges-only model needs
  // no sensor to move on and is extrapolated over any gap (a UWB outage), its
  // covariance growing exactly as the constant-velocity prediction would.
  const Real dt_c = cv_mode_ ? std::fmax(dt, Real(0)) : std::fmin(std::fmax(dt, Real(-0.1)), Real(0.5));
  // The ranges-only model extrapolates with its own transition (cv_step); the
  // IMU filter with the constant velocity of the last interval.
  CvStep st;
  st.f_pv = dt_c;
  if (cv_mode_ && dt_c > Real(0)) {
    const CvModel m = cv_model(t_us);
    st = cv_step(dt_c, m.accel_psd, m.vel_tau_s);
  }
  const Vec3 pos = x.pos_nav_m + x.vel_nav_mps * st.f_pv;
  out.pos_nav_m = to_vec3f(pos);
  out.vel_nav_mps = to_vec3f(x.vel_nav_mps * st.f_vv);
  for (int i = 0; i < 4; ++i) out.q_nav_body[i] = static_cast<float>(x.q_nav_body(i));
  Real var_p[3];
  for (int i = 0; i < 3; ++i) {
    // Position variance at the output time: P_pp + 2 f P_pv + f^2 P_vv + Q_pp
    // (Q_pp: the ranges-only model's process noise since the last range).
    var_p[i] = p(i, i) + Real(2) * st.f_pv * p(i, 3 + i) + st.f_pv * st.f_pv * p(3 + i, 3 + i) + st.q_pp;
    var_p[i] = std::fmax(var_p[i], Real(0));
  }
  Real cxy = p(0, 1) + st.f_pv * (p(0, 4) + p(3, 1)) + st.f_pv * st.f_pv * p(3, 4);
  if (cv_mode_ && !cv_yaw_known_) {
    // Heading unknown: the body origin lies anywhere on the circle of the
    // horizontal lever arm about the tags' centroid (uniform azimuth).
    Vec3 lev = ekf_.dcm() * mean_lever();
    const Real lever_var = Real(0.5) * lev.head<2>().squaredNorm();
    var_p[0] += lever_var;
    var_p[1] += lever_var;
  }
  out.pos_sigma_m = Vec3f{static_cast<float>(std::sqrt(var_p[0])), static_cast<float>(std::sqrt(var_p[1])),
                          static_cast<float>(std::sqrt(var_p[2]))};
  const Real denom = std::sqrt(var_p[0] * var_p[1]);
  out.pos_xy_corr = denom > Real(0) ? static_cast<float>(std::fmin(std::fmax(cxy / denom, Real(-1)), Real(1))) : 0.0F;
  Real var_v[3];
  for (int i = 0; i < 3; ++i) var_v[i] = std::fmax(st.f_vv * st.f_vv * p(3 + i, 3 + i) + st.q_vv, Real(0));
  out.vel_sigma_mps = Vec3f{static_cast<float>(std::sqrt(var_v[0])), static_cast<float>(std::sqrt(var_v[1])),
                            static_cast<float>(std::sqrt(var_v[2]))};
  out.heading_rad = static_cast<float>(quat_yaw(x.q_nav_body));
  // The heading is an estimate once a filter carries it (IMU filter, or the
  // ranges-only filter with a heading); in the centroid form it is arbitrary.
  if (!(cv_mode_ && !cv_yaw_known_)) {
    out.heading_sigma_rad = static_cast<float>(std::sqrt(std::fmax(p(ErrIdx::kAtt + 2, ErrIdx::kAtt + 2), Real(0))));
  }
  if (cv_mode_) {
    out.mode = cv_reason_ == NavMode::kRecovering ? NavMode::kRecovering
                                                  : (imu_alive(t_us) ? NavMode::kAligning : NavMode::kUwbOnly);
  } else {
    out.mode = NavMode::kInertial;
  }

  uint64_t last_uwb_us =
      diag_.last_range_used_t_us > running_since_us_ ? diag_.last_range_used_t_us : running_since_us_;
#if UWBNAV_GNSS
  // A fused GNSS fix aids the filter as a range does: no outage while fixes come.
  if (diag_.last_gnss_used_t_us > last_uwb_us) last_uwb_us = diag_.last_gnss_used_t_us;
#endif
#if UWBNAV_COOP
  // So does a fused range to a neighbour vehicle.
  if (diag_.last_neighbour_used_t_us > last_uwb_us) last_uwb_us = diag_.last_neighbour_used_t_us;
#endif
  const bool uwb_outage = diff_us(t_us, last_uwb_us) > static_cast<int64_t>(cfg_.uwb_timeout_us);
  const Real sigma_h = std::sqrt(var_p[0] + var_p[1]);
  // Nominal: the IMU filter, or the ranges-only filter on a vehicle without IMU.
  const bool nominal_mode = out.mode == NavMode::kInertial || (out.mode == NavMode::kUwbOnly && !site_.has_imu);
  if (uwb_outage || !nominal_mode || !(sigma_h < cfg_.degraded_sigma)) {
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
    bad.mode = NavMode::kNone;
    bad.resets = diag_.resets;
    bad.pos_nav_m = Vec3f{kNaNf, kNaNf, kNaNf};
    bad.vel_nav_mps = bad.pos_nav_m;
    bad.pos_sigma_m = bad.pos_nav_m;
    bad.vel_sigma_mps = bad.pos_nav_m;
    bad.heading_rad = kNaNf;
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
