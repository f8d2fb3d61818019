// Navigator start-up and alignment without truth: LS-Taylor fix from the first
// ranges (seed 003 eq. 1-4; 2-D for planar anchor layouts) starts the
// ranges-only (constant-velocity) filter at once, so a solution is published
// from the first fix; levelling, heading (two tags, UWB track chords, yaw bank)
// are acquired in the background and hand the same filter over to the IMU
// model, keeping position, velocity and the range-error states.
#include <cmath>

#include "estimator/navigator.hpp"
#include "estimator/trig.hpp"

namespace uwbnav {
namespace {

constexpr uint64_t kMaxWindowUs = 10000000;       // LS fix: oldest range used [us]
// A pair's consecutive ranges that differ by more than this many sigmas of
// their difference (sqrt(2 R) = sqrt(2) sigma), beyond the start's motion
// bound, disagree.
constexpr Real kRangeJumpSigma = Real(5);
constexpr Real kWindowSpanFactor = Real(1.5);      // LS fix: window = this x the span of the newest needed ranges
constexpr uint64_t kLevelWithoutRestUs = 3000000;  // level from the mean specific force after this [us]
constexpr uint64_t kTwoTagSyncUs = 200000;        // two-tag fixes closer than this pair up [us]
constexpr uint64_t kTrackMaxSpanUs = 20000000;    // heading chord: longest time span [us]
constexpr Real kMinChord_m = Real(0.5);            // heading: shortest chord of the LS track [m]
constexpr Real kChordMinSpeed_mps = Real(1);       // heading: the ranges-only filter must see at least this speed [m/s]
constexpr Real kMaxChordSpreadRad = Real(0.35);    // heading: largest disagreement between chords [rad]
constexpr Real kChordMaxAccel_mps2 = Real(5);      // heading: speed a vehicle can gain per second of a chord [m/s^2]
constexpr Real kMinBaseline_m = Real(0.1);         // two-tag heading: shortest horizontal baseline [m]
constexpr uint64_t kHeadingSampleGapUs = 300000;  // two-tag heading average: shortest interval between samples (independent fixes) [us]
constexpr uint64_t kHeadingMaxGapUs = 2000000;    // two-tag heading average: a longer pause starts it again [us]
constexpr int kHeadingMinSamples = 5;              // two-tag heading average: fewest samples handed over
constexpr Real kHeadingMaxSigma_rad = Real(0.3);   // two-tag heading average: largest 1-sigma handed over [rad]
constexpr Real kCvTurnRateSigma_radps = Real(0.5);  // ranges-only turn rate without IMU: prior 1-sigma [rad/s]
constexpr Real kHeadingOffsetDop = Real(1.5);      // two-tag heading average: horizontal DOP of a tag fix under range offsets
constexpr Real kWeakHeightFactor = Real(5);        // auto height mode, non-planar anchors: sigma multiplier
constexpr uint64_t kTrackSpacingUs = 200000;      // track: shortest interval between stored fixes (5 Hz) [us]
constexpr uint64_t kTrackFreshUs = 1000000;       // rest check: newest LS fix at most this old, else no evidence [us]
constexpr uint64_t kTrackSpeedWindowUs = 2000000; // rest check: LS track span whose slope is the speed [us]
constexpr Real kRestTrackSpeed_mps = Real(0.1);    // rest check: confirm only if the track's speed lower bound is below [m/s]
constexpr Real kRestHoldTrackSpeed_mps = Real(0.3);  // rest check: a confirmed rest ends above this lower bound [m/s]
constexpr uint64_t kYawBankMinIntervalUs = 25000;  // yaw bank: shortest interval between range updates [us]
constexpr int kYawBankMinUpdates = 10;             // yaw bank: fewest ranges before it may start the filter
constexpr Real kYawBankCorrTime_s = Real(1);       // yaw bank: correlation time turning bias/tilt into white noise [s]
constexpr Real kTiltSigmaRest_rad = Real(0.01);    // tilt 1-sigma after levelling at rest [rad]
constexpr Real kTiltSigmaMoving_rad = Real(0.05);  // tilt 1-sigma when levelled on the move [rad]
constexpr Real kLevelGain_radps = Real(0.2);       // air, aligning: tilt correction gain toward the specific force (5 s) [1/s]
constexpr Real kLevelBiasGain_radps2 = Real(0.01); // ... and its gyro-bias integral gain [1/s^2]
// Air, aligning: tilt 1-sigma of the complementary filter. Its reference is the
// specific force averaged over about 1/kLevelGain = 5 s: a multicopter's mean
// horizontal acceleration over 5 s (about 0.8 m/s^2, 0.08 rad) and the gyro
// bias it has not yet learnt (0.5 deg/s over 5 s, 0.04 rad).
constexpr Real kTiltSigmaAir_rad = Real(0.1);
constexpr Real kStartHeightSigma_m = Real(1);     // first 3-D fix: 1-sigma of the start height prior between mirror solutions [m]
constexpr Real kExcludedRangeCost = Real(9);      // first 3-D fix: cost of each range a mode left out, against wssr (a 3-sigma residual; set a priori, not tuned) [-]
constexpr Real kSameModeDist_m = Real(0.01);      // first 3-D fix: a mirror solve that converged within this of the fix found the fix again [m]
constexpr Real kMaxLinearYawSigma_rad = Real(0.5); // largest yaw 1-sigma the IMU filter is started with
constexpr Real kAccelEmaTau_s = Real(0.5);             // horizontal acceleration EMA time constant [s]
constexpr Real kRestMaxForceChange_mps2 = Real(0.1);   // rest held: largest change of the mean specific force [m/s^2]
constexpr Real kRestMaxGyroChange_radps = Real(0.005); // rest held: largest change of the mean gyro, 2.5 sigma of the rest bias's 0.002 rad/s [rad/s]
constexpr Real kCvStartVelSigma_mps = Real(2);     // ranges-only start: horizontal velocity 1-sigma [m/s]
constexpr Real kCvStartVelSigmaV_mps = Real(0.5);  // ... vertical [m/s]

// Chi-square bound of a weighted SSR with dof degrees of freedom (~99.9 % for small dof).
Real wssr_bound(Real dof) { return Real(10) + Real(6) * dof; }

// Vertical 1-sigma the start gives a 2-D fix (height assumed, not measured):
// a ground vehicle's tag height is known to the suspension's travel [m].
Real two_d_sigma_v_m(Platform platform) { return platform == Platform::kGround ? Real(0.2) : Real(1.0); }

// Chi-square acceptance of an LS fix with dof degrees of freedom.
bool ls_consistent(const LsFix& ls) {
  if (ls.dof == 0) return static_cast<Real>(ls.gdop) <= Real(10);
  return static_cast<Real>(ls.weighted_ssr) <= wssr_bound(static_cast<Real>(ls.dof));
}

}  // namespace

void Navigator::restart(bool counted_reset) {
  if (counted_reset) {
    ++diag_.resets;
    after_failure_ = true;
  }
  phase_ = Phase::kWaitFix;
#if UWBNAV_GNSS
  gnss_prev_fused_us_ = 0;
#endif
#if UWBNAV_COOP
  for (NeighbourSlot& n : neighbours_) {
    n.prev_fused_us = 0;
    n.used = false;
  }
#endif
  cv_mode_ = false;
  cv_yaw_known_ = false;
  cv_turn_rad_ = Real(0);
  height_on_ = false;
  levelled_ = false;
  levelled_at_rest_ = false;
  dv_rest_valid_ = false;
  q_init_ = Quat(1, 0, 0, 0);
  bg_init_.setZero();
  bg_ref_.setZero();
  ba_init_.setZero();
  accel_h_ms_ = Real(0);
  rest_ref_valid_ = false;
  imu_still_now_ = false;
  // The latest ranges per pair are kept: the next range can fix again at once.
  for (auto& row : prev_tag_valid_) {
    for (auto& v : row) v = false;
  }
  for (auto& f : last_fix_per_tag_) f = TrackFix{};
  heading_avg_ = HeadingAverage{};
  for (auto& t : last_fix_try_us_) t = 0;
  gsf_last_update_us_ = 0;
  track_head_ = 0;
  track_count_ = 0;
  monitor_head_ = 0;
  monitor_count_ = 0;
  clear_short_range_test();
  first_imu_t_us_ = 0;
  heading_wait_since_us_ = 0;
  last_constraint_us_ = 0;
  last_speed_prior_us_ = 0;
  last_level_check_us_ = 0;
  recovery_level_ = 0;
  have_fix_ = false;
  fix_wait_from_us_ = 0;
  for (auto& s : slots_) s = BiasSlot{};
  for (auto& a : anchor_slot_) a = -1;
  for (auto& t : tag_bias_t_us_) t = 0;
  for (auto& row : prev_innov_) {
    for (auto& v : row) v = PrevInnovation{};
  }
  gating_.reset();
  gsf_.reset();
#if UWBNAV_RBF_BRIDGE
  // The network learnt the drift of this filter's estimates (biases, tilt): gone with it.
  bridge_.reset();
  bridge_last_us_ = 0;
  bridge_count_ = 0;
#endif
  ekf_.init(NominalState{}, ErrVec::Ones());
}

void Navigator::init_on_imu(const ImuSample& imu) {
  const Vec3 w_mean = Real(0.5) * (to_vec3(imu.gyro_body_radps) + to_vec3(prev_imu_.gyro_body_radps));
  const Real dt = static_cast<Real>(imu.t_us - prev_imu_.t_us) * Real(1e-6);
  if (levelled_) {
    // Attitude with an arbitrary (relative) yaw until the heading is known.
    Vec3 w_corr = Vec3::Zero();
    if (site_.platform == Platform::kAir) {
      // A multicopter's specific force points along its thrust, i.e. up on
      // average: a complementary filter (Mahony, proportional and integral)
      // keeps the levelled attitude's tilt and the gyro bias from drifting
      // while it flies without a heading; only roll and pitch are corrected
      // (the correction is perpendicular to the vertical). A ground vehicle's
      // specific force is not vertical in turns and braking: it is re-levelled
      // at rest instead.
      const Vec3 f = to_vec3(imu.accel_body_mps2);
      const Real fn = f.norm();
      if (fn > Real(0.5) * static_cast<Real>(site_.gravity_mps2)) {
        const Vec3 up_body = quat_to_dcm(q_init_).transpose() * Vec3(0, 0, 1);
        const Vec3 e = (f / fn).cross(up_body);
        w_corr = kLevelGain_radps * e;
        bg_init_ -= kLevelBiasGain_radps2 * e * dt;
      }
    }
    const Vec3 dtheta = (w_mean - bg_init_ + w_corr) * dt;
    if (gsf_.active()) {
      const Vec3 f_mean = Real(0.5) * (to_vec3(imu.accel_body_mps2) + to_vec3(prev_imu_.accel_body_mps2));
      gsf_.accumulate(quat_to_dcm(quat_mul(q_init_, quat_exp(Real(0.5) * dtheta))) * f_mean, dt);
    }
    q_init_ = quat_normalised(quat_mul(q_init_, quat_exp(dtheta)));
    const Mat3 c_lvl = quat_to_dcm(q_init_);
    // A ground vehicle's velocity turns with its body: the vertical component
    // of the gyro's rotation turns the ranges-only filter's velocity (advance_cv).
    if (site_.platform != Platform::kAir) cv_turn_rad_ += c_lvl.row(2).dot(dtheta);
    // Horizontal acceleration (levelled frame) for the ranges-only model's noise.
    const Vec3 f_lvl = c_lvl * to_vec3(imu.accel_body_mps2);
    const Real a = std::fmin(dt / kAccelEmaTau_s, Real(1));
    accel_h_ms_ += a * (f_lvl.head<2>().squaredNorm() - accel_h_ms_);
    if (dv_rest_valid_) {
      // Velocity gained since the latest rest (moved_since_rest).
      dv_rest_lvl_mps_ += f_lvl.head<2>() * dt;
      turn_rest_rad_ += ((w_mean - bg_init_) * dt).norm();
    }
  }
  // Judge rest at the constraint rate (O(window) each time).
  if (imu.t_us - last_level_check_us_ < cfg_.constraint_period_us) return;
  last_level_check_us_ = imu.t_us;
  rest_.evaluate();
  // The IMU alone cannot tell rest from constant velocity or constant
  // acceleration: the UWB track must agree that the vehicle stands still,
  // and the specific force must not have moved since rest was confirmed.
  imu_still_now_ = imu_still(imu.t_us);
  if (imu_still_now_) {
    dv_rest_lvl_mps_ = Vec2::Zero();
    turn_rest_rad_ = Real(0);
    dv_rest_valid_ = site_.platform == Platform::kGround;
    // Levelling (roll, pitch) and gyro bias from the rest window; keep the relative yaw.
    const Real yaw_rel = levelled_ ? quat_yaw(q_init_) : Real(0);
    q_init_ = quat_mul(quat_from_yaw(yaw_rel), quat_level(rest_.accel_mean()));
    bg_init_ = rest_.gyro_mean();
    bg_ref_ = bg_init_;
    levelled_ = true;
    levelled_at_rest_ = true;
    levelled_t_us_ = imu.t_us;
  } else if (!levelled_ && rest_.window_full() && first_imu_t_us_ != 0 &&
             imu.t_us - first_imu_t_us_ > kLevelWithoutRestUs) {
    q_init_ = quat_level(rest_.accel_mean());  // never at rest: mean specific force as vertical
    levelled_ = true;
    levelled_t_us_ = imu.t_us;
  }
}

bool Navigator::imu_still(uint64_t t_us) {
  // At rest the body frame does not turn, so the specific force measured in it
  // is constant: rest is confirmed once by a quiet IMU window and an LS track
  // that does not move, then held while the window mean stays within
  // kRestMaxForceChange of the force at confirmation and the track does not
  // show the vehicle driving. A smooth pull-away keeps the IMU window quiet and
  // would otherwise be levelled away as tilt; a cruise at constant velocity is
  // just as quiet (measured: rest latched at 1.2 m/s, the ranges-only filter
  // held at zero speed and re-started 52 times in 3 min). Single NLOS jumps of
  // the track stay below the hold's higher bar. Call after rest_.evaluate().
  if (!rest_.at_rest()) {
    rest_ref_valid_ = false;
    return false;
  }
  const Real speed_bound = speed_lower_bound(t_us);
  if (!rest_ref_valid_) {
    if (speed_bound > kRestTrackSpeed_mps) return false;
    // A multicopter can turn on the spot at a steady rate, which no IMU window
    // tells from a gyro bias: once a rest has measured the bias, a later rest
    // of an air platform must find it again, within 3 sigma of the turn-on prior
    // (tuning drive outage:28 yaws at up to 0.8 rad/s while hovering).
    if (site_.platform == Platform::kAir && levelled_at_rest_ &&
        !((rest_.gyro_mean() - bg_ref_).cwiseAbs().maxCoeff() < Real(3) * cfg_.gyro_bias_init)) {
      return false;
    }
    // A steady acceleration leaves the IMU window as quiet as rest, and the
    // track's speed bound lags a pull-away by a second or more. The body
    // cannot come to rest at a new tilt without the gyro seeing it turn: once
    // levelled, a new rest must find the mean specific force along the vertical
    // of the gyro-propagated attitude (within twice the levelling's tilt sigma
    // plus 3 sigma of the gyro bias's drift since). Measured without the check
    // (tuning drive outage:8): rest confirmed 0.9 s into a 2 m/s^2 pull-away,
    // the attitude re-levelled 10 deg nose-down and handed to the IMU filter.
    if (levelled_ && !force_along_levelled_vertical(t_us)) return false;
    if (moved_since_rest(t_us)) return false;
    rest_ref_body_mps2_ = rest_.accel_mean();
    rest_ref_gyro_body_radps_ = rest_.gyro_mean();
    rest_ref_valid_ = true;
    return true;
  }
  if (speed_bound > kRestHoldTrackSpeed_mps || moved_since_rest(t_us)) {
    rest_ref_valid_ = false;
    return false;
  }
  // Held: the body frame has not turned (gyro mean = bias, which does not move
  // in seconds) and the specific force measured in it has not changed. A noisy
  // gyro's window mean moves by itself: 4 sigma of the norm of the difference
  // of two window means of white noise (density N over T: N sqrt(2/T) per axis).
  const Real window_s = std::fmax(rest_.window_span_s(), Real(0.05));
  const Real gyro_change_max =
      std::fmax(kRestMaxGyroChange_radps, Real(4) * imu_eff_.gyro_noise * std::sqrt(Real(6) / window_s));
  return (rest_.accel_mean() - rest_ref_body_mps2_).norm() < kRestMaxForceChange_mps2 &&
         (rest_.gyro_mean() - rest_ref_gyro_body_radps_).norm() < gyro_change_max;
}

bool Navigator::force_along_levelled_vertical(uint64_t t_us) const {
  const Vec3 f = rest_.accel_mean();
  const Real fn = f.norm();
  if (!(fn > Real(0))) return false;
  const Vec3 up_body = quat_to_dcm(q_init_).row(2).transpose();  // nav up in the body frame
  const Real sin_angle = (f / fn).cross(up_body).norm();
  const Real since_s = t_us > levelled_t_us_ ? static_cast<Real>(t_us - levelled_t_us_) * Real(1e-6) : Real(0);
  const Real allowed = Real(2) * levelled_tilt_sigma() + Real(3) * levelled_gyro_bias_sigma().maxCoeff() * since_s;
  return sin_angle < sin_cos(std::fmin(allowed, Real(1.5))).sin;
}

bool Navigator::moved_since_rest(uint64_t t_us) const {
  // A cruise at constant velocity leaves the IMU window as quiet as rest, and
  // the ranges may not show the speed either: two anchors in view with the
  // vehicle crossing the line between them see range rates near zero (measured,
  // held-out drive ground_blocked:77: a rest held since the start resumed
  // 0.5 s into a 3.2 m/s cruise after a pull-away, once the specific force was
  // back at the rest's; the ranges-only filter stopped 1 m from that
  // line and then tracked the mirror image of the drive across it, 19 m off
  // for 10 s). The pull-away itself is in the IMU: a ground vehicle levelled
  // at rest integrates its horizontal specific force in the levelled frame
  // into the velocity it has gained since (strapdown without position). The
  // levelling absorbed the horizontal accelerometer bias into the tilt, so
  // that bias returns only as the body turns (at most |b_a| per radian turned),
  // and the rest gyro bias tilts the frame by sigma_bg t: the velocity error
  // after t seconds is at most sigma_ba min(turn, 2) t + g sigma_bg t^2 / 2.
  // A velocity gain beyond 3 such sigmas (plus the track's rest speed) is a
  // vehicle that has not stopped since; the bound grows with t^2, so after a
  // long drive the check gives way to the track's evidence alone.
  if (!dv_rest_valid_ || !levelled_at_rest_ || t_us < levelled_t_us_) return false;
  const Real t_s = static_cast<Real>(t_us - levelled_t_us_) * Real(1e-6);
  const Real g = static_cast<Real>(site_.gravity_mps2);
  const Real sigma_mps = cfg_.accel_bias_init * std::fmin(turn_rest_rad_, Real(2)) * t_s +
                         Real(0.5) * g * levelled_gyro_bias_sigma().maxCoeff() * t_s * t_s;
  return dv_rest_lvl_mps_.norm() > kRestTrackSpeed_mps + Real(3) * sigma_mps;
}

Real Navigator::speed_lower_bound(uint64_t t_us) const {
  // Evidence of motion for the rest check: the LS track needs three anchors
  // at once; a single anchor's range rate bounds the speed from below too
  // (|dr/dt| <= tag speed), and keeps telling a constant-speed cruise from
  // rest while two of four anchors are blocked (measured without it: rest
  // latched at 2 m/s on a road with two anchors in view, the ranges-only
  // filter held at zero speed 21 m behind, 35 re-alignments in 11 min).
  return std::fmax(track_speed_bound(t_us), range_rate_speed_bound(t_us));
}

bool Navigator::range_jumped(const PairRange& prev, uint64_t t_us, float range_m) const {
  // A gross outlier (short as well as long) or the onset of an NLOS episode
  // in the latest range of a pair bends the first fix, and the filter
  // started from it then rejects that anchor's good ranges as NLOS (drive
  // ground_nlos:62, tuning seeds 61-99: a range 3.6 m short among the first fix's four put
  // the start 4.3 m off at a claimed 0.8 m, 14 s before it came back). Seed
  // 000's consistency model (eq. 3-6) before the navigator's first fix: the
  // change of a pair's range beyond the travel the fix itself allows for
  // (ekf.init_speed times the time between the ranges) and kRangeJumpSigma
  // sigmas of the difference of two ranges is an error of one of the two, and
  // while the redundancy wait lasts the first fix leaves the pair out until
  // its next range agrees with the latest (try_ls_fix); an outlier keeps its
  // pair out for two ranges. Once the wait is over every pair counts again:
  // a vehicle moving fast from the start has its pairs with the largest range
  // rates jump, and where too few pairs remain its first fix comes at the end
  // of the wait. Tried and not
  // kept: weighing such a range down by the jump instead (tuning seeds 1-60:
  // 5 drives better, 10 worse; ground_nlos:62 started 1.6 m off at a claimed
  // 1.1 m). Pairs with a single range, or ranges more than kMaxWindowUs
  // apart, pass.
  if (started_ || !prev.valid || t_us <= prev.t_us || t_us - prev.t_us > kMaxWindowUs) return false;
  const Real dt_s = static_cast<Real>(static_cast<uint32_t>(t_us - prev.t_us)) * Real(1e-6);
  const Real bound_m = kRangeJumpSigma * std::sqrt(Real(2) * r_los_m2_) + cfg_.init_speed * dt_s;
  return std::fabs(static_cast<Real>(range_m) - static_cast<Real>(prev.range_m)) > bound_m;
}

void Navigator::range_rate_on_range(int anchor_index, int tag_index, uint64_t t_us, float range_m) {
  RangeRateBlock& b = range_rate_[anchor_index];
  const bool gap = b.tag_index < 0 || t_us < b.t0_us ||
                   t_us - b.t0_us > kTrackSpeedWindowUs + kTrackFreshUs ||
                   static_cast<Real>(t_us - b.t0_us) * Real(1e-6) - static_cast<Real>(b.t_last_s) > (static_cast<Real>(kTrackFreshUs) * Real(1e-6));
  if (gap || t_us - b.t0_us > kTrackSpeedWindowUs) {
    // Block complete (its bound is kept for the next one) or stale (no evidence).
    const float bound = gap ? 0.0F : static_cast<float>(range_rate_bound(b));
    b = RangeRateBlock{};
    b.prev_bound_mps = bound;
    b.t0_us = t_us;
    b.r0_m = range_m;
    b.tag_index = static_cast<int8_t>(tag_index);
  }
  if (tag_index != b.tag_index) return;
  const float t = static_cast<float>(t_us - b.t0_us) * 1e-6F;
  const float r = range_m - b.r0_m;
  b.t_last_s = t;
  b.st += t;
  b.sr += r;
  b.stt += t * t;
  b.str += t * r;
  b.srr += r * r;
  ++b.n;
}

Real Navigator::range_rate_bound(const RangeRateBlock& b) const {
  // |LS slope| less three of its standard deviations; the ranges' sigma is the
  // larger of the learnt LOS noise and the fit's own residual scatter (an NLOS
  // step inside the block widens the bound instead of faking motion).
  if (b.n < 3) return Real(0);
  const Real n = static_cast<Real>(b.n);
  const Real t_mean = static_cast<Real>(b.st) / n;
  const Real r_mean = static_cast<Real>(b.sr) / n;
  const Real stt = static_cast<Real>(b.stt) - n * t_mean * t_mean;
  const Real str = static_cast<Real>(b.str) - n * t_mean * r_mean;
  const Real srr = static_cast<Real>(b.srr) - n * r_mean * r_mean;
  if (!(stt > Real(1e-6))) return Real(0);
  const Real slope = str / stt;
  const Real resid_var = n > Real(2) ? std::fmax(srr - slope * str, Real(0)) / (n - Real(2)) : Real(0);
  const Real var = std::fmax(r_los_m2_, resid_var);
  return std::fmax(std::fabs(slope) - Real(3) * std::sqrt(var / stt), Real(0));
}

Real Navigator::range_rate_speed_bound(uint64_t t_us) const {
  // Per anchor: the running block once it spans half the window (and its
  // newest range is fresh), else the previous block if it ended within half a
  // window. The second largest bound over the anchors: one anchor's range can
  // drift under a growing NLOS bias (measured with the largest: rest not
  // confirmed at a start in NLOS, the ranges-only filter pulled 13 m away).
  Real best = Real(0), second = Real(0);
  const size_t n = site_.num_anchors < kMaxAnchors ? site_.num_anchors : kMaxAnchors;
  for (size_t i = 0; i < n; ++i) {
    const RangeRateBlock& b = range_rate_[i];
    if (b.tag_index < 0 || t_us < b.t0_us) continue;
    const Real age_s = static_cast<Real>(t_us - b.t0_us) * Real(1e-6);
    const Real span_s = static_cast<Real>(b.t_last_s);
    Real bound = Real(0);
    if (span_s >= (static_cast<Real>(kTrackSpeedWindowUs / 2) * Real(1e-6)) && age_s - span_s <= (static_cast<Real>(kTrackFreshUs) * Real(1e-6))) {
      bound = range_rate_bound(b);
    } else if (age_s <= (static_cast<Real>(kTrackSpeedWindowUs / 2) * Real(1e-6))) {
      bound = static_cast<Real>(b.prev_bound_mps);
    }
    if (bound > best) {
      second = best;
      best = bound;
    } else if (bound > second) {
      second = bound;
    }
  }
  return second;
}

Real Navigator::track_speed_bound(uint64_t t_us) const {
  // Lower bound of the horizontal speed the LS track shows over the last
  // kTrackSpeedWindowUs: the least-squares slope of the fixes of the newest
  // tag against time, less three of its standard deviations (fix sigmas taken
  // as independent). Zero when the track is too short or stale to tell: no
  // evidence of motion (sparse ranging forms few fixes; rest is then judged by
  // the IMU alone, as before).
  if (track_count_ == 0) return Real(0);
  const size_t newest = (track_head_ + kTrackCapacity - 1) % kTrackCapacity;
  const TrackFix& fn = track_[newest];
  if (t_us - fn.t_us > kTrackFreshUs) return Real(0);
  // Two passes over at most kTrackCapacity fixes: means, then the slope sums.
  Real n = Real(0), t_mean = Real(0), sig2 = Real(0);
  Vec3 p_mean = Vec3::Zero();
  uint64_t oldest_us = fn.t_us;
  for (size_t k = 0; k < track_count_; ++k) {
    const TrackFix& f = track_[(newest + kTrackCapacity - k) % kTrackCapacity];
    if (fn.t_us - f.t_us > kTrackSpeedWindowUs) break;
    if (f.tag_index != fn.tag_index) continue;
    const Real dt = -static_cast<Real>(static_cast<uint32_t>(fn.t_us - f.t_us)) * Real(1e-6);
    n += Real(1);
    t_mean += dt;
    p_mean += f.tag_pos_nav_m;
    sig2 += f.sigma_h_m * f.sigma_h_m;
    oldest_us = f.t_us;
  }
  if (n < Real(3) || fn.t_us - oldest_us < kTrackSpeedWindowUs / 2) return Real(0);
  t_mean /= n;
  p_mean /= n;
  sig2 /= n;
  Real stt = Real(0);
  Vec3 stp = Vec3::Zero();
  for (size_t k = 0; k < track_count_; ++k) {
    const TrackFix& f = track_[(newest + kTrackCapacity - k) % kTrackCapacity];
    if (fn.t_us - f.t_us > kTrackSpeedWindowUs) break;
    if (f.tag_index != fn.tag_index) continue;
    const Real dt = -static_cast<Real>(static_cast<uint32_t>(fn.t_us - f.t_us)) * Real(1e-6) - t_mean;
    stt += dt * dt;
    stp += dt * (f.tag_pos_nav_m - p_mean);
  }
  if (!(stt > Real(0))) return Real(0);
  const Real speed = stp.head<2>().norm() / stt;
  const Real speed_sigma = std::sqrt(sig2 / stt);
  return std::fmax(speed - Real(3) * speed_sigma, Real(0));
}

bool Navigator::try_ls_fix(uint64_t t_us, int tag_index, TrackFix& fix, size_t min_dof, bool accept_rejected) {
  const bool skip_jumped = !started_ && cfg_.init_redundancy_wait_us > 0 && !accept_rejected;
  // The latest range of each anchor, youngest first (n <= kMaxAnchors).
  LsRange ranges[kMaxAnchors];
  uint64_t age_us[kMaxAnchors];
  size_t n = 0;
  for (size_t a = 0; a < site_.num_anchors; ++a) {
    const PairRange& pr = pair_[a][tag_index];
    if (!pr.valid || t_us < pr.t_us || t_us - pr.t_us > kMaxWindowUs) continue;
    // While the first fix waits for redundancy, a pair whose latest ranges disagree waits too (range_jumped).
    if (pr.jumped && skip_jumped) continue;
    size_t k = n++;
    while (k > 0 && age_us[k - 1] > t_us - pr.t_us) {
      ranges[k] = ranges[k - 1];
      age_us[k] = age_us[k - 1];
      --k;
    }
    age_us[k] = t_us - pr.t_us;
    ranges[k].anchor_pos_nav_m = site_.anchors[a].pos_nav_m;
    ranges[k].range_m = pr.range_m - static_cast<float>(known_offset_m(static_cast<int>(a), tag_index));
  }
  // Window: the span of the newest ranges a fix needs, with some margin (sparse
  // ranging takes seconds to hear enough anchors; dense ranging a few ms).
  const size_t needed = (planar_ ? 2 : 3) + min_dof;
  if (n < 3) return false;
  const uint64_t span_us = age_us[(n < needed ? n : needed) - 1];
  // Ages are below kMaxWindowUs (10 s): through uint32_t, no soft-double conversion on the M4F.
  uint64_t window_us =
      static_cast<uint32_t>(kWindowSpanFactor * static_cast<Real>(static_cast<uint32_t>(span_us)));
  if (window_us < cfg_.init_window_us) window_us = cfg_.init_window_us;
  const Real sigma = std::sqrt(r_los_m2_);
  size_t m = 0;
  Real oldest_s = Real(0);
  for (size_t i = 0; i < n; ++i) {
    if (age_us[i] > window_us) break;
    oldest_s = static_cast<Real>(static_cast<uint32_t>(age_us[i])) * Real(1e-6);
    // A range taken earlier saw the vehicle elsewhere: inflate by speed x age.
    const Real smear = cfg_.init_speed * static_cast<Real>(static_cast<uint32_t>(age_us[i])) * Real(1e-6);
    ranges[m] = ranges[i];
    ranges[m].sigma_m = static_cast<float>(std::sqrt(sigma * sigma + smear * smear + anchor_bias_prior_var()));
    ++m;
  }
  // Waiting for redundancy: no solve before the window holds enough ranges
  // (the exclusion in robust_ls_fix may then leave one of them out).
  if (min_dof > 1 && m < needed) return false;
  const Vec3 lev = lever(tag_index);
  const Vec3 lever_level = quat_to_dcm(q_init_) * lev;  // yaw does not change the vertical part
  LsOptions opt;
  opt.known_z_m = static_cast<float>(cfg_.origin_height + (levelled_ ? lever_level.z() : lev.z()));
  LsFix ls;
  // 3-D when the layout allows it; 2-D (known height) for planar layouts or
  // when the 3-D geometry is singular - never as a way around a 3-D fix that
  // failed its own consistency test (the height assumption would absorb it).
  Status st = Status::kSingular;
  if (!planar_ && m >= 4) st = robust_ls_fix(ranges, m, opt, ls);
  if (st != Status::kOk && st != Status::kRejected && m >= 3) {
    opt.two_d = true;
    st = robust_ls_fix(ranges, m, opt, ls);
  }
  // A first fix that waited its time may be one its own ranges reject (an NLOS
  // range among just enough anchors): taken with the uncertainty its residuals
  // show (the variance factor below), the best estimate there is.
  // (dof >= 2: one degree of freedom gives a variance factor from a single draw.)
  const bool take_rejected = accept_rejected && st == Status::kRejected && ls.converged && ls.dof >= 2;
  if (st != Status::kOk && !take_rejected) return false;
  Real factor_ssr = static_cast<Real>(ls.weighted_ssr);  // the variance factor's numerator and dof
  Real factor_dof = static_cast<Real>(ls.dof);
  // The navigator's first consistent 3-D fix (not after a restart: the vehicle
  // may be anywhere by then), under the start height prior z0 = the tag at
  // ekf.origin_height (1-sigma kStartHeightSigma_m): of the modes below, the one
  // with the smallest wssr + ((z - z0) / sigma_z0)^2 is kept (the largest
  // posterior). Anchors at about one height leave a mirror solution on their
  // other side (a multicopter on the floor below anchors at 1.4-2.8 m fixes as
  // well 3.5 m up), and which one Gauss-Newton finds depends on the linear start.
  bool height_switched = false;
  Real mode_spread_h_m2 = Real(0);  // the other modes' spread about the chosen one: horizontal, vertical [m^2]
  Real mode_spread_v_m2 = Real(0);
  if (st == Status::kOk && !opt.two_d && !have_fix_ && !started_) {
    Real z_anchors_m = Real(0);
    for (size_t i = 0; i < m; ++i) z_anchors_m += static_cast<Real>(ranges[i].anchor_pos_nav_m.z);
    z_anchors_m /= static_cast<Real>(m);
    LsOptions mirror_opt = opt;
    mirror_opt.has_initial_guess = true;
    mirror_opt.initial_guess_nav_m = ls.pos_nav_m;
    mirror_opt.initial_guess_nav_m.z = static_cast<float>(Real(2) * z_anchors_m - static_cast<Real>(ls.pos_nav_m.z));
    const Real z0_m = static_cast<Real>(opt.known_z_m);
    auto cost = [z0_m](const LsFix& f) {
      const Real dz = (static_cast<Real>(f.pos_nav_m.z) - z0_m) / kStartHeightSigma_m;
      return static_cast<Real>(f.weighted_ssr) + dz * dz;
    };
    // The modes are compared whatever ranges each left out (robust_ls_fix
    // leaves out at most one; dof counts the ranges it used minus the
    // unknowns): wssr falls with every range left out, so each one costs
    // kExcludedRangeCost, a 3-sigma residual (tuning drive air_indoor:98: 4 of
    // 6 anchors NLOS on the pad, the fix from all six 4.2 m up at cost 23.6;
    // its mirror at z -0.8 m (the truth 0.1 m), one range left out, at
    // 12.4 + 9 was not compared before). The 2-D mode lies at z0: its cost is
    // its wssr.
    auto penalised = [m, &cost](const LsFix& f, bool two_d) {
      const Real left_out = static_cast<Real>(m) - static_cast<Real>(f.dof) - (two_d ? Real(2) : Real(3));
      return cost(f) + kExcludedRangeCost * left_out;
    };
    // Modes: 0 the fix, 1 its mirror, 2 the tag at z0; cost < 0: no such mode.
    Vec3 mode_pos_m[3] = {to_vec3(ls.pos_nav_m), Vec3::Zero(), Vec3::Zero()};
    Real mode_cost[3] = {penalised(ls, false), Real(-1), Real(-1)};
    int chosen = 0;
    LsFix mirror;
    if (robust_ls_fix(ranges, m, mirror_opt, mirror) == Status::kOk && mirror.converged &&
        (to_vec3(mirror.pos_nav_m) - mode_pos_m[0]).norm() >= kSameModeDist_m) {
      mode_pos_m[1] = to_vec3(mirror.pos_nav_m);
      mode_cost[1] = penalised(mirror, false);
      if (mode_cost[1] < mode_cost[chosen]) {
        ls = mirror;
        chosen = 1;
      }
    }
    // The third mode is the prior's own: the tag at z0 (a 2-D fix). NLOS
    // excess on anchors around and below the tag is absorbed by a 3-D fix
    // moving up (tuning drive air_indoor:24: 3 of 6 anchors NLOS, 6.2 m up at
    // a claimed sigma_z of 0.27 m, with a consistent wssr). Its wssr carries
    // the one degree of freedom more that the prior term adds to the others.
    // It competes even where its ranges reject it (the variance factor below
    // then sizes it): the NLOS excess that lifted the 3-D fix shows there.
    LsOptions floor_opt = opt;
    floor_opt.two_d = true;
    LsFix on_floor;
    const Status floor_st = robust_ls_fix(ranges, m, floor_opt, on_floor);
    if ((floor_st == Status::kOk || floor_st == Status::kRejected) && on_floor.converged) {
      mode_pos_m[2] = to_vec3(on_floor.pos_nav_m);
      mode_cost[2] = penalised(on_floor, true);
      if (mode_cost[2] < mode_cost[chosen]) {
        ls = on_floor;
        opt.two_d = true;
        chosen = 2;
      }
    }
    height_switched = chosen != 0;
    // The modes the choice passed over keep their share of the posterior,
    // weight exp(-(cost - cost_chosen)/2) each against the chosen one's 1:
    // their spread about the chosen position joins its covariance (moment
    // matching of the Gaussian mixture about the chosen mean, Bar-Shalom, Li &
    // Kirubarajan 2001, 1.4.16; the modes' own covariances taken as equal), so
    // a close call starts with the uncertainty it has.
    Real mass = Real(1);
    for (int j = 0; j < 3; ++j) {
      if (j == chosen || mode_cost[j] < Real(0)) continue;
      const Vec3 d = mode_pos_m[j] - mode_pos_m[chosen];
      const Real w = std::exp(-Real(0.5) * (mode_cost[j] - mode_cost[chosen]));
      mass += w;
      mode_spread_h_m2 += w * d.head<2>().squaredNorm();
      mode_spread_v_m2 += w * d.z() * d.z();
    }
    mode_spread_h_m2 /= mass;
    mode_spread_v_m2 /= mass;
    factor_ssr = static_cast<Real>(ls.weighted_ssr);
    factor_dof = static_cast<Real>(ls.dof);
    if (!opt.two_d) {
      // A 3-D start far from the start height is as suspect as large residuals:
      // the prior joins the consistency test (one degree of freedom more) and
      // the variance factor. While the fix waits for redundancy (min_dof > 1),
      // such a fix is refused and the next ranges are awaited.
      factor_ssr = cost(ls);
      factor_dof += Real(1);
      if (min_dof > 1 && factor_ssr > wssr_bound(factor_dof)) return false;
    }
  }
  fix.t_us = t_us;
  fix.tag_pos_nav_m = to_vec3(ls.pos_nav_m);
  // A posteriori variance factor of the adjustment: residuals larger than the
  // ranges' sigmas explain (an NLOS range the test let through, a wrong local
  // solution) scale the fix's covariance up, never down.
  const Real var_factor = factor_dof > Real(0) ? std::fmax(Real(1), factor_ssr / factor_dof) : Real(1);
  fix.sigma_h_m = std::sqrt(var_factor * static_cast<Real>(ls.cov_nav_m2[0][0] + ls.cov_nav_m2[1][1]) + mode_spread_h_m2);
  // A 2-D fix has no vertical sigma (the start takes the platform's), unless
  // it won over 3-D modes, whose spread it then carries too.
  fix.sigma_v_m = !opt.two_d ? std::sqrt(var_factor * static_cast<Real>(ls.cov_nav_m2[2][2]) + mode_spread_v_m2)
                  : mode_spread_v_m2 > Real(0)
                      ? std::sqrt(two_d_sigma_v_m(site_.platform) * two_d_sigma_v_m(site_.platform) + mode_spread_v_m2)
                      : Real(-1);
  fix.yaw_rel_rad = quat_yaw(q_init_);
  fix.tag_index = tag_index;
  fix.age_s = oldest_s;
  if (!std::isfinite(fix.sigma_h_m) || !std::isfinite(fix.sigma_v_m)) return false;
  if (height_switched) ++diag_.start_height_switches;
  return true;
}

Status Navigator::robust_ls_fix(LsRange* ranges, size_t n, const LsOptions& opt, LsFix& ls) const {
  // A fix must agree with its own ranges (chi-square). When it does not, one
  // range is NLOS or stale: leave each range out in turn (seed 001 RAIM
  // exclusion, by the smallest remaining statistic rather than the largest
  // residual, which an LS fix spreads over the good ranges) and keep the best
  // consistent subset that still has redundancy. At most n + 1 solves.
  const Status st = ls_taylor_solve(ranges, n, opt, ls);
  if (st != Status::kOk) return st;
  if (ls.converged && ls_consistent(ls)) return Status::kOk;
  const size_t unknowns = opt.two_d ? 2 : 3;
  // After the exclusion two degrees of freedom must remain: with one, a second
  // bad range is detectable but the choice of the excluded one is a guess
  // (measured: spurious 0.5 m jumps of the LS track at rest, read as motion).
  if (n < unknowns + 3) return Status::kRejected;
  LsRange subset[kLsMaxRanges];
  LsFix best;
  LsFix cand;  // ls_taylor_solve resets it on every call
  bool found = false;
  for (size_t skip = 0; skip < n; ++skip) {
    size_t m = 0;
    for (size_t i = 0; i < n; ++i) {
      if (i != skip) subset[m++] = ranges[i];
    }
    if (ls_taylor_solve(subset, m, opt, cand) != Status::kOk || !cand.converged || !ls_consistent(cand)) continue;
    if (!found || cand.weighted_ssr < best.weighted_ssr) {
      best = cand;
      found = true;
    }
  }
  if (!found) return Status::kRejected;
  ls = best;
  return Status::kOk;
}

bool Navigator::init_track(int anchor_index, int tag_index, const UwbRange& range) {
  const uint64_t t = range.t_us;
  if (fix_wait_from_us_ == 0) fix_wait_from_us_ = t;
  // The track is kept at ~10 Hz: a fix per range would cost an LS solve per
  // range while aligning (the worst 10 ms cycle on the M4F).
  uint64_t& last_try = last_fix_try_us_[tag_index];
  if (have_fix_ && last_try != 0 && t >= last_try && t - last_try < kTrackSpacingUs) return false;
  last_try = t;
  // The first fix after a (re)start waits up to ekf.init_redundancy_wait for
  // the redundancy the site's anchors allow: two ranges more than the unknowns
  // detect an NLOS range, three let the test leave it out (seed 001
  // exclusion), where one only bends the fix. Once that wait is over, a fix its
  // ranges reject is taken at the size its residuals give it. A wait of 0
  // turns both off: the first consistent fix.
  size_t min_dof = 1;
  bool accept_rejected = false;
  if (!have_fix_ && cfg_.init_redundancy_wait_us > 0) {
    const bool waiting = t < fix_wait_from_us_ || t - fix_wait_from_us_ < cfg_.init_redundancy_wait_us;
    const size_t unknowns = planar_ ? 2U : 3U;
    if (waiting && site_.num_anchors >= unknowns + 2U) {
      min_dof = site_.num_anchors >= unknowns + 3U ? 3U : 2U;
    }
    accept_rejected = !waiting;
  }
  TrackFix fix;
  if (!try_ls_fix(t, tag_index, fix, min_dof, accept_rejected)) return false;
  (void)anchor_index;
  have_fix_ = true;
  started_ = true;
  // Thin the track to ~10 Hz so the ring spans the first metres even when slow.
  const TrackFix& prev = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];
  if (track_count_ == 0 || fix.t_us - prev.t_us >= kTrackSpacingUs || prev.tag_index != fix.tag_index) {
    track_[track_head_] = fix;
    track_head_ = (track_head_ + 1) % kTrackCapacity;
    if (track_count_ < kTrackCapacity) ++track_count_;
  }
  last_fix_per_tag_[tag_index] = fix;
  return true;
}

void Navigator::begin_imu_recovery() {
  levelled_ = false;
  levelled_at_rest_ = false;
  dv_rest_valid_ = false;
  q_init_ = Quat(1, 0, 0, 0);
  bg_init_.setZero();
  bg_ref_.setZero();
  ba_init_.setZero();
  track_head_ = 0;
  track_count_ = 0;
  for (auto& f : last_fix_per_tag_) f = TrackFix{};
  heading_avg_ = HeadingAverage{};
  first_imu_t_us_ = 0;
  heading_wait_since_us_ = 0;
  gsf_.reset();
  if (cv_mode_ && cv_reason_ == NavMode::kUwbOnly) cv_reason_ = NavMode::kAligning;
}

void Navigator::align_in_background(int anchor_index, int tag_index, const UwbRange& range) {
  // While the ranges-only filter publishes, the IMU filter is prepared: LS track,
  // levelling (init_on_imu), then a heading from two tags, the track chords
  // (ground) or the yaw bank. Whichever answers first hands the filter over.
  const uint64_t t = range.t_us;
  const bool got_fix = init_track(anchor_index, tag_index, range);
  if (!levelled_) return;
  if (heading_wait_since_us_ == 0) heading_wait_since_us_ = t;
  if (got_fix) try_heading(t);
  if (!cv_mode_) return;
  yaw_bank_on_range(anchor_index, tag_index, range);
  if (!cv_mode_) return;
  // Ground vehicles only: an air platform keeps publishing the ranges-only
  // solution until its yaw bank is confident (measured on the real PX4 drone of
  // miluv: an IMU filter started with a 0.5 rad yaw at 0.8 ranges/s diverged
  // to 100 m within 30 s, while the ranges-only solution stayed within 2 m).
  if (site_.platform == Platform::kGround && t - heading_wait_since_us_ > cfg_.init_heading_timeout_us && gsf_.active() &&
      gsf_.updates() >= kYawBankMinUpdates && gsf_.yaw_sigma() < kMaxLinearYawSigma_rad) {
    // No heading source answered in time: a yaw the linearisation can carry is enough.
    const Real yaw_sigma = std::fmin(std::fmax(gsf_.yaw_sigma(), Real(0.02)), kMaxLinearYawSigma_rad);
    start_filter(t, gsf_.yaw_mean(), yaw_sigma);
  }
}

Real Navigator::levelled_tilt_sigma() const {
  // A rest window's levelling holds while the vehicle stands; once a
  // multicopter flies, its complementary filter holds the tilt instead, with
  // that filter's error (the mean horizontal acceleration over 1/k_p).
  if (levelled_at_rest_ && (site_.platform != Platform::kAir || imu_still_now_)) return kTiltSigmaRest_rad;
  return site_.platform == Platform::kAir ? kTiltSigmaAir_rad : kTiltSigmaMoving_rad;
}

Vec3 Navigator::levelled_gyro_bias_sigma() const {
  // The gyro bias handed to the IMU filter is the reference value (the rest
  // window's mean gyro, 1-sigma 2 mrad/s; else imu.gyro_bias_init about the
  // failed filter's bias or zero) moved by the multicopter's levelling
  // integral while it flew. Nothing checks that integral (it also absorbs
  // tilt and thrust-axis errors): each axis's move counts as uncertainty,
  // so a bias the integral made up is handed over with the sigma of its size
  // and the ranges correct it instead of the filter coasting on it.
  const Real base = levelled_at_rest_ ? std::fmin(cfg_.gyro_bias_init, Real(0.002)) : cfg_.gyro_bias_init;
  const Vec3 moved = bg_init_ - bg_ref_;
  return (moved.array().square() + base * base).sqrt().matrix();
}

YawGsf::Noise Navigator::yaw_bank_noise() const {
  // The models estimate neither accelerometer bias nor tilt: both enter as
  // white acceleration with a 1 s correlation time, on top of the measured
  // accelerometer noise; the start yaw walks with gyro noise and bias. The
  // gyro bias's uncertainty about the vertical turns the yaw; the levelling
  // integral's move about the horizontal axes, if wrong, holds the
  // complementary filter's tilt off by (bias error) / k_p.
  YawGsf::Noise nz;
  const Vec3 up_body = quat_to_dcm(q_init_).row(2).transpose();
  const Real bg_vert2 = up_body.cwiseProduct(levelled_gyro_bias_sigma()).squaredNorm();
  const Vec3 moved = bg_init_ - bg_ref_;
  const Real up_moved = up_body.dot(moved);
  const Real moved_horiz2 = std::fmax(moved.squaredNorm() - up_moved * up_moved, Real(0));
  const Real tilt = levelled_tilt_sigma();
  const Real tilt2 = tilt * tilt + moved_horiz2 / (kLevelGain_radps * kLevelGain_radps);
  const Real g = static_cast<Real>(site_.gravity_mps2);
  const Real ba = cfg_.accel_bias_init;
  nz.accel_psd = std::sqrt(imu_eff_.accel_noise * imu_eff_.accel_noise + (ba * ba + g * g * tilt2) * kYawBankCorrTime_s);
  nz.yaw_psd = std::sqrt(imu_eff_.gyro_noise * imu_eff_.gyro_noise + bg_vert2 * kYawBankCorrTime_s);
  return nz;
}

void Navigator::yaw_bank_on_range(int anchor_index, int tag_index, const UwbRange& range) {
  const Mat3 c_lvl = quat_to_dcm(q_init_);
  if (!gsf_.active()) {
    if (!have_fix_ || track_count_ == 0) return;
    // Seed at the newest fix (this range is part of it).
    const TrackFix& fix = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];
    const Real pos_v = fix.sigma_v_m > Real(0) ? fix.sigma_v_m : two_d_sigma_v_m(site_.platform);
    const Real vel_sigma = levelled_at_rest_ && !(speed_lower_bound(range.t_us) > kRestTrackSpeed_mps) ? Real(0.2) : cfg_.init_speed;
    gsf_.start(fix.tag_pos_nav_m, c_lvl * lever(fix.tag_index), Real(0),
               fix.sigma_h_m * std::sqrt(Real(0.5)) + Real(0.05), pos_v, std::fmax(vel_sigma, Real(0.2)));
    return;
  }
  // At most one bank update per kYawBankMinIntervalUs: eight small EKFs per
  // range would dominate a 10 ms cycle with dense ranging (measured on the
  // M4F), and the heading needs geometry over seconds, not every range.
  if (gsf_last_update_us_ != 0 && range.t_us >= gsf_last_update_us_ &&
      range.t_us - gsf_last_update_us_ < kYawBankMinIntervalUs) {
    return;
  }
  gsf_last_update_us_ = range.t_us;
  gsf_.propagate(static_cast<Real>(site_.gravity_mps2), yaw_bank_noise());
  const Real range_m = static_cast<Real>(range.range_m) - known_offset_m(anchor_index, tag_index);
  const Real sigma = std::sqrt(r_los_m2_ + anchor_bias_prior_var() + tag_bias_prior_var());
  if (!gsf_.update_range(to_vec3(site_.anchors[anchor_index].pos_nav_m), c_lvl * lever(tag_index), range_m, sigma)) {
    return;
  }
  // Ground vehicles get their heading from the track (try_heading), which is
  // honest about its uncertainty; the bank's yaw sigma is optimistic early on
  // (measured: 0.3-1.1 m errors at a claimed 5 cm after such a start), so on
  // the ground it is only the fallback after the heading timeout.
  const bool bank_may_start = site_.platform == Platform::kAir;
  if (bank_may_start && gsf_.updates() >= kYawBankMinUpdates && gsf_.yaw_sigma() < cfg_.init_yaw_sigma) {
    start_filter(range.t_us, gsf_.yaw_mean(), std::fmax(gsf_.yaw_sigma(), Real(0.02)));
  }
}

void Navigator::try_heading(uint64_t t_us) {
  // (a) Two tags at known lever arms: the nav-frame baseline against the body one.
  for (size_t i = 0; i < site_.num_tags && i < kMaxTags; ++i) {
    for (size_t j = i + 1; j < site_.num_tags && j < kMaxTags; ++j) {
      const TrackFix& fi = last_fix_per_tag_[i];
      const TrackFix& fj = last_fix_per_tag_[j];
      if (fi.tag_index < 0 || fj.tag_index < 0) continue;
      const uint64_t dt_ij = fi.t_us > fj.t_us ? fi.t_us - fj.t_us : fj.t_us - fi.t_us;
      if (dt_ij > kTwoTagSyncUs || t_us - fi.t_us > kTwoTagSyncUs || t_us - fj.t_us > kTwoTagSyncUs) continue;
      const Vec3 b_nav = fj.tag_pos_nav_m - fi.tag_pos_nav_m;
      const Vec3 b_rel = quat_to_dcm(q_init_) * (lever(static_cast<int>(j)) - lever(static_cast<int>(i)));
      const Real len = b_rel.head<2>().norm();
      const Real sig = std::sqrt(fi.sigma_h_m * fi.sigma_h_m + fj.sigma_h_m * fj.sigma_h_m);
      const Real yaw0 = wrap_pi(std::atan2(b_nav.y(), b_nav.x()) - std::atan2(b_rel.y(), b_rel.x()));
      const Real yaw_sigma = std::atan2(Real(2) * sig, len) + Real(0.02);
      if (levelled_ && imu_alive(t_us)) {
        if (len < kMinBaseline_m || len < Real(4) * sig) continue;
        start_filter(t_us, yaw0, yaw_sigma);
        return;
      }
      // Without IMU the ranges-only filter then carries the heading itself:
      // from one pair of fixes when the baseline is long enough, else from the
      // average of independent pairs (a short baseline, as on a trolley).
      if (cv_mode_ && !cv_yaw_known_ && len >= kMinBaseline_m) {
        const Real yaw_abs = wrap_pi(yaw0 + quat_yaw(q_init_));
        if (len >= Real(4) * sig) {
          cv_set_yaw(yaw_abs, yaw_sigma);
          return;
        }
        if (average_two_tag_heading(t_us, yaw_abs, yaw_sigma, len)) return;
      }
    }
  }
  // (b) Ground vehicles move forward: each chord of the LS track points along
  // the body x axis at mid-chord, whose gyro-relative yaw is known; the
  // length-weighted circular mean of (chord direction - relative yaw) over the
  // first metres is the start yaw. Works on curved tracks too.
  if (site_.platform != Platform::kGround || track_count_ < 2 || !levelled_) return;
  // Only while the ranges-only filter sees the vehicle drive: at rest, NLOS
  // jumps of the LS track look like chords too.
  Real speed = Real(0), speed_sigma = Real(0);
  if (cv_mode_) {
    speed = ekf_.state().vel_nav_mps.head<2>().norm();
    speed_sigma = std::sqrt(ekf_.cov()(ErrIdx::kVel, ErrIdx::kVel) + ekf_.cov()(ErrIdx::kVel + 1, ErrIdx::kVel + 1));
    if (!(speed > kChordMinSpeed_mps && speed > Real(2) * speed_sigma)) return;
  }
  const size_t newest = (track_head_ + kTrackCapacity - 1) % kTrackCapacity;
  const TrackFix& fn = track_[newest];
  const TrackFix* end = &fn;  // end of the chord being built (walking back in time)
  Real sum_c = Real(0), sum_s = Real(0), length = Real(0), sig_sum = Real(0);
  Real est_min = Real(10), est_max = Real(-10), first_est = Real(0);
  int chords = 0;
  for (size_t k = 1; k < track_count_ && length < cfg_.init_heading_dist; ++k) {
    const TrackFix& f = track_[(newest + kTrackCapacity - k) % kTrackCapacity];
    if (f.tag_index != fn.tag_index) continue;
    if (fn.t_us - f.t_us > kTrackMaxSpanUs) break;
    const Vec3 chord = end->tag_pos_nav_m - f.tag_pos_nav_m;
    const Real d = chord.head<2>().norm();
    // Each fix allowed for ekf.init_speed x the age of its ranges; the chord
    // says how fast the vehicle went between its ends (at least: its length
    // less twice the fixes' noise), and whatever it went faster moved the
    // vehicle while those ranges were taken (sparse ranging: metres). That
    // travel widens both fixes; it needs nothing but the track.
    const Real sig0_2 = end->sigma_h_m * end->sigma_h_m + f.sigma_h_m * f.sigma_h_m;
    const Real chord_dt_s = static_cast<Real>(static_cast<uint32_t>(end->t_us - f.t_us)) * Real(1e-6);
    const Real speed_lo =
        chord_dt_s > Real(0) ? std::fmax(d - Real(2) * std::sqrt(sig0_2), Real(0)) / chord_dt_s : Real(0);
    const Real excess_mps = std::fmax(speed_lo - cfg_.init_speed, Real(0));
    const Real smear2 = excess_mps * excess_mps * (end->age_s * end->age_s + f.age_s * f.age_s);
    const Real sig = std::sqrt(sig0_2 + smear2);
    if (d < kMinChord_m || d < Real(5) * sig) continue;
    if (cv_mode_) {
      // A chord longer than the vehicle can have driven in its time has a
      // wrong fix at one end (on a road's near-collinear anchors, the mirror
      // solution across the anchor line): the filter's speed, 3 sigma, the
      // speed a vehicle can have had more over the chord, and both fixes'
      // noise. Which end is wrong is not known: no heading from this track
      // until the chords walked for it no longer reach the wrong fix.
      const Real dt_s = static_cast<Real>(static_cast<uint32_t>(end->t_us - f.t_us)) * Real(1e-6);
      if (d > (speed + Real(3) * speed_sigma + kChordMaxAccel_mps2 * dt_s) * dt_s + Real(3) * sig) return;
    }
    const Real turn = wrap_pi(end->yaw_rel_rad - f.yaw_rel_rad);
    const Real est = std::atan2(chord.y(), chord.x()) - (f.yaw_rel_rad + Real(0.5) * turn);
    // Unwrap relative to the first chord's estimate before judging the spread.
    const Real rel = chords == 0 ? Real(0) : wrap_pi(est - first_est);
    if (chords == 0) first_est = est;
    est_min = std::fmin(est_min, rel);
    est_max = std::fmax(est_max, rel);
    const SinCos sc = sin_cos(est);
    sum_c += d * sc.cos;
    sum_s += d * sc.sin;
    length += d;
    sig_sum += sig;
    ++chords;
    end = &f;
  }
  if (length < cfg_.init_heading_dist || chords == 0) return;
  // Chords disagreeing by more than this are not forward driving (reversing, sliding).
  if (est_max - est_min > kMaxChordSpreadRad) return;
  const Real yaw0 = wrap_pi(std::atan2(sum_s, sum_c));
  // Yaw: chord direction noise, side slip allowance and the chords' spread.
  const Real yaw_sigma = std::atan2(Real(2) * sig_sum / static_cast<Real>(chords), length / static_cast<Real>(chords)) /
                             std::sqrt(static_cast<Real>(chords)) +
                         Real(0.03) + Real(0.5) * (est_max - est_min);
  if (imu_alive(t_us)) start_filter(t_us, yaw0, yaw_sigma);
}

void Navigator::setup_height(Real origin_z_m) {
  // Auto: firm on planar layouts (z unobservable), weak otherwise (z observable
  // near the anchors but not far from them; ramps stay within the weak sigma).
  height_on_ = cfg_.ground_constraints && cfg_.height_mode != 0;
  height_sigma_m_ = (cfg_.height_mode == 1 || planar_) ? cfg_.height_sigma : kWeakHeightFactor * cfg_.height_sigma;
  // Planar layouts fixed the height from the survey; otherwise hold the initial fix.
  height_ref_m_ = planar_ ? cfg_.origin_height : origin_z_m;
}

Vec3 Navigator::mean_lever() const {
  Vec3 sum = Vec3::Zero();
  const size_t n = site_.num_tags < kMaxTags ? site_.num_tags : kMaxTags;
  for (size_t i = 0; i < n; ++i) sum += lever(static_cast<int>(i));
  return n > 0 ? Vec3(sum / static_cast<Real>(n)) : sum;
}

void Navigator::cv_set_yaw(Real yaw_rad, Real yaw_sigma_rad) {
  // Until now the state's horizontal position was that of the tags' centroid
  // (lever arms unknown in azimuth); with a heading it becomes the body origin.
  NominalState& x = ekf_.mutable_state();
  const Quat q = quat_from_yaw(yaw_rad);
  Vec3 lev_nav = quat_to_dcm(q) * mean_lever();
  lev_nav.z() = Real(0);
  x.pos_nav_m -= lev_nav;
  x.q_nav_body = q;
  ekf_.refresh_dcm();
  ekf_.reset_state(ErrIdx::kAtt + 2, yaw_sigma_rad * yaw_sigma_rad);
  // The centroid-to-origin step carries the heading's uncertainty.
  const Real lever_var = lev_nav.squaredNorm() * yaw_sigma_rad * yaw_sigma_rad;
  ekf_.add_variance(ErrIdx::kPos, lever_var);
  ekf_.add_variance(ErrIdx::kPos + 1, lever_var);
  cv_yaw_known_ = true;
  heading_avg_ = HeadingAverage{};
  if (!imu_alive(t_state_us_)) cv_start_turn_rate();
}

void Navigator::cv_start_turn_rate() {
  // Without IMU the gyro-bias state carries the turn rate (body rate = -b_g,
  // EkfCore::predict_cv): it starts at zero with kCvTurnRateSigma_radps.
  ekf_.mutable_state().bg_body_radps.setZero();
  for (int i = 0; i < 3; ++i) {
    ekf_.reset_state(ErrIdx::kBg + i, i == 2 ? kCvTurnRateSigma_radps * kCvTurnRateSigma_radps : Real(0));
  }
}

bool Navigator::average_two_tag_heading(uint64_t t_us, Real yaw_rad, Real sigma_rad, Real baseline_m) {
  // Weighted circular mean of two-tag headings from fixes at least
  // kHeadingSampleGapUs apart (no range shared: independent noise). Without a
  // gyro a turn shows only as a sample the mean does not explain (beyond 3
  // sigma): the average starts again from it, as after a pause. The tags'
  // range offsets do not average out (they move a fix the same way for
  // seconds): their part stays in the handed-over sigma. Returns true when
  // the ranges-only filter took the heading.
  HeadingAverage& h = heading_avg_;
  if (h.n > 0 && t_us >= h.last_t_us && t_us - h.last_t_us < kHeadingSampleGapUs) return false;
  if (h.n > 0 && (t_us < h.last_t_us || t_us - h.last_t_us > kHeadingMaxGapUs)) h = HeadingAverage{};
  if (h.n > 0) {
    const Real mean = std::atan2(h.sum_s, h.sum_c);
    const Real dev = wrap_pi(yaw_rad - mean);
    if (dev * dev > Real(9) * (sigma_rad * sigma_rad + Real(1) / h.sum_w)) h = HeadingAverage{};
  }
  const Real w = Real(1) / (sigma_rad * sigma_rad);
  const SinCos sc = sin_cos(yaw_rad);
  h.sum_c += w * sc.cos;
  h.sum_s += w * sc.sin;
  h.sum_w += w;
  ++h.n;
  h.last_t_us = t_us;
  // Noise part of the mean: the fixes' claimed sigma (conservative: the LS
  // a-posteriori factor and the speed-age inflation), or - once there are
  // enough samples - twice the scatter the samples actually show, whichever
  // is smaller (circular variance of the weighted resultant length R, bounded
  // above without a logarithm: -2 ln R <= 2 (1 - R) / R).
  Real var_noise = Real(1) / h.sum_w;
  if (h.n >= kHeadingMinSamples) {
    const Real r = std::fmin(std::sqrt(h.sum_c * h.sum_c + h.sum_s * h.sum_s) / h.sum_w, Real(1));
    const Real var_scatter = r > Real(1e-3) ? Real(2) * (Real(1) - r) / r : Real(1e3);
    var_noise = std::fmin(var_noise, Real(4) * var_scatter / static_cast<Real>(h.n));
  }
  // Systematic part: survey errors move both tags' fixes alike and cancel in
  // the baseline; range offsets do not (each anchor-tag pair has its own on
  // real radios): the offsets' prior per range (the commissioned residual
  // when a calibration is loaded) through the fix's DOP, for each tag.
  const size_t n_anchors = site_.num_anchors > 0 ? site_.num_anchors : 1;
  const Real cal = site_.range_offset_sigma_m;
  const Real anchor_off = std::isfinite(cal) ? cal : cfg_.anchor_bias_sigma;
  const Real pair_var = anchor_off * anchor_off + tag_bias_prior_var();
  const Real offset_m = kHeadingOffsetDop * std::sqrt(Real(2) * pair_var / static_cast<Real>(n_anchors));
  const Real sigma_sys = std::atan2(offset_m, baseline_m);
  const Real sigma = std::sqrt(var_noise + sigma_sys * sigma_sys);
  if (h.n < kHeadingMinSamples || !(sigma < kHeadingMaxSigma_rad)) return false;
  cv_set_yaw(std::atan2(h.sum_s, h.sum_c), sigma);
  return true;
}

void Navigator::cv_forget_yaw() {
  // Back to the centroid form: the heading is no longer trusted.
  NominalState& x = ekf_.mutable_state();
  Vec3 lev_nav = ekf_.dcm() * mean_lever();
  lev_nav.z() = Real(0);
  x.pos_nav_m += lev_nav;
  cv_yaw_known_ = false;
  heading_avg_ = HeadingAverage{};
}

void Navigator::start_cv_filter(uint64_t t_us, const TrackFix& fix, NavMode reason, const Vec2& vel_h_prior_mps) {
  // Ranges-only filter from the first fix: the state's horizontal position is
  // the tags' centroid while the heading is unknown (cv_yaw_known_ false), so
  // an unknown heading never turns a lever arm the wrong way. The horizontal
  // velocity starts at the prior mean (a re-alignment's IMU filter velocity;
  // the centroid's differs from the body origin's by w x l, well inside the
  // 1-sigma of kCvStartVelSigma_mps), the vertical at zero as the height
  // model's prior.
  NominalState x;
  x.vel_nav_mps.head<2>() = vel_h_prior_mps;
  x.q_nav_body = levelled_ ? q_init_ : Quat(1, 0, 0, 0);
  const Mat3 c = quat_to_dcm(x.q_nav_body);
  const Vec3 lev = lever(fix.tag_index);
  const Vec3 centroid_offset = mean_lever() - lev;  // from this tag to the tags' centroid (body)
  Vec3 off_h = c * centroid_offset;
  off_h.z() = Real(0);
  x.pos_nav_m = fix.tag_pos_nav_m - Vec3(0, 0, (c * lev).z());
  ErrVec sigma = ErrVec::Zero();
  const Real pos_h = std::sqrt(Real(0.5) * fix.sigma_h_m * fix.sigma_h_m + off_h.squaredNorm()) + Real(0.02);
  const Real pos_v = fix.sigma_v_m > Real(0) ? fix.sigma_v_m : two_d_sigma_v_m(site_.platform);
  sigma.segment<3>(ErrIdx::kPos) = Vec3(pos_h, pos_h, pos_v);
  sigma.segment<3>(ErrIdx::kVel) = Vec3(kCvStartVelSigma_mps, kCvStartVelSigma_mps, kCvStartVelSigmaV_mps);
  sigma.segment<3>(ErrIdx::kAtt).setConstant(Real(0.1));
  sigma.segment<3>(ErrIdx::kBa).setConstant(cfg_.accel_bias_init);
  sigma.segment<3>(ErrIdx::kBg).setConstant(cfg_.gyro_bias_init);
  sigma(ErrIdx::kScale) = cfg_.scale_sigma;
  for (size_t i = 0; i < kMaxTags; ++i) sigma(ErrIdx::kTagBias + static_cast<int>(i)) = std::sqrt(tag_bias_prior_var());
  for (int i = 0; i < kBiasSlots; ++i) sigma(ErrIdx::kAnchorBias + i) = std::sqrt(anchor_bias_prior_var());
  ekf_.init(x, sigma);
  for (auto& s : slots_) s = BiasSlot{};
  for (auto& a : anchor_slot_) a = -1;
  for (auto& t : tag_bias_t_us_) t = 0;
  gating_.on_filter_restart();
  phase_ = Phase::kRunning;
  cv_mode_ = true;
  cv_turn_rad_ = Real(0);
  cv_reason_ = reason;
  cv_yaw_known_ = false;
  cv_rest_latched_ = false;
  t_state_us_ = t_us;
  running_since_us_ = t_us;
  after_failure_ = false;
  heading_wait_since_us_ = 0;
  setup_height(x.pos_nav_m.z());
}

void Navigator::start_filter(uint64_t t_us, Real yaw_rad, Real yaw_sigma_rad) {
  // Hand the running ranges-only filter over to the IMU model: position,
  // velocity and the range errors (with their covariance) carry on; attitude
  // comes from levelling plus the heading, the IMU biases start fresh.
  NominalState& x = ekf_.mutable_state();
  const Quat q = quat_normalised(quat_mul(quat_from_yaw(yaw_rad), q_init_));
  const Mat3 c = quat_to_dcm(q);
  if (!cv_yaw_known_) {
    // Centroid form -> body origin with the new heading; its uncertainty moves the origin.
    Vec3 lev_nav = c * mean_lever();
    lev_nav.z() = Real(0);
    x.pos_nav_m -= lev_nav;
    const Real lever_var = lev_nav.squaredNorm() * yaw_sigma_rad * yaw_sigma_rad;
    ekf_.add_variance(ErrIdx::kPos, lever_var);
    ekf_.add_variance(ErrIdx::kPos + 1, lever_var);
  }
  x.q_nav_body = q;
  x.ba_body_mps2 = ba_init_;
  x.bg_body_radps = bg_init_;
  // Any bias-learning window closes here, and the next IMU prediction opens the
  // first one: a window never spans a start of the IMU filter (its bias
  // variances start again).
  bias_win_.close();
  dv_rest_valid_ = false;  // the levelled frame is not propagated while the IMU filter runs
  ekf_.refresh_dcm();
  ErrVec sigma = ErrVec::Zero();
  const Real tilt = levelled_tilt_sigma();
  sigma.segment<3>(ErrIdx::kAtt) = Vec3(tilt, tilt, yaw_sigma_rad);
  sigma.segment<3>(ErrIdx::kBa).setConstant(cfg_.accel_bias_init);
  sigma.segment<3>(ErrIdx::kBg) = levelled_gyro_bias_sigma();
  ekf_.decouple_inertial(sigma);
  // A levelling at rest balanced the vertical at the start attitude: the
  // vertical constraints learn the bias on that tangent plane from here on.
  // Not after a re-alignment that carries a bias over (ba_init_): the
  // levelling read the raw specific force, so f - b_a is off the vertical
  // and the start is no point of the sphere; the next rest sets it. This is
  // the only way into the IMU filter, where the hold runs: a reference never
  // outlives the filter it was taken in.
  rest_force_ref_valid_ = false;
  if (levelled_at_rest_ && ba_init_.isZero()) set_rest_force_reference(c.row(2).transpose());
  gating_.on_filter_restart();
  phase_ = Phase::kRunning;
  cv_mode_ = false;
  cv_yaw_known_ = false;
  t_state_us_ = have_prev_imu_ ? prev_imu_.t_us : t_us;
  last_constraint_us_ = t_state_us_;
  after_failure_ = false;
  heading_wait_since_us_ = 0;
  gsf_.reset();
  setup_height(x.pos_nav_m.z());
}

}  // namespace uwbnav
