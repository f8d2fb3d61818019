// Navigator initialisation without truth: LS-Taylor fix from the first ranges
// (seed 003 eq. 1-4; 2-D for planar anchor layouts), levelling and gyro bias
// from a rest period, heading from the first metres of UWB track (ground) or
// from two tags, constant-velocity start when there is no IMU.
#include <cmath>

#include "estimator/navigator.hpp"

namespace uwbnav {
namespace {

constexpr uint64_t kMaxWindowUs = 10000000;       // fix window growth limit [us]
constexpr uint64_t kLevelWithoutRestUs = 3000000;  // level from the mean specific force after this [us]
constexpr uint64_t kTwoTagSyncUs = 200000;        // two-tag fixes closer than this pair up [us]
constexpr uint64_t kTrackMaxSpanUs = 20000000;    // heading chord: longest time span [us]
constexpr Real kMinChord_m = Real(0.5);            // heading: shortest chord of the LS track [m]
constexpr Real kMaxChordSpreadRad = Real(0.35);    // heading: largest disagreement between chords [rad]
constexpr Real kMinBaseline_m = Real(0.3);         // two-tag heading: shortest horizontal baseline [m]
constexpr Real kWeakHeightFactor = Real(5);        // auto height mode, non-planar anchors: sigma multiplier
constexpr uint64_t kTrackSpacingUs = 100000;      // track: shortest interval between stored fixes [us]
constexpr uint64_t kTrackFreshUs = 1000000;       // rest check: LS track span looked at [us]
constexpr Real kRestTrackDist_m = Real(0.1);       // rest check: allowed track motion beyond noise [m]

}  // namespace

void Navigator::restart(bool counted_reset) {
  if (counted_reset) {
    ++diag_.resets;
    after_failure_ = true;
  }
  phase_ = Phase::kWaitFix;
  cv_mode_ = false;
  height_on_ = false;
  levelled_ = false;
  levelled_at_rest_ = false;
  q_init_ = Quat(1, 0, 0, 0);
  bg_init_.setZero();
  for (auto& row : pair_) {
    for (auto& p : row) p = PairRange{};
  }
  for (auto& row : prev_tag_valid_) {
    for (auto& v : row) v = false;
  }
  for (auto& f : last_fix_per_tag_) f = TrackFix{};
  track_head_ = 0;
  track_count_ = 0;
  monitor_head_ = 0;
  monitor_count_ = 0;
  first_range_t_us_ = 0;
  first_imu_t_us_ = 0;
  window_us_ = cfg_.init_window_us;
  window_grow_t_us_ = 0;
  heading_wait_since_us_ = 0;
  last_constraint_us_ = 0;
  have_fix_ = false;
  gating_.reset();
  ekf_.init(NominalState{}, ErrVec::Ones());
}

void Navigator::init_on_imu(const ImuSample& imu) {
  const Vec3 w_mean = Real(0.5) * (to_vec3(imu.gyro_body_radps) + to_vec3(prev_imu_.gyro_body_radps));
  const Real dt = static_cast<Real>(imu.t_us - prev_imu_.t_us) * Real(1e-6);
  if (levelled_) {
    // Attitude with an arbitrary (relative) yaw until the heading is known.
    q_init_ = quat_normalised(quat_mul(q_init_, quat_exp((w_mean - bg_init_) * dt)));
  }
  // Judge rest at the constraint rate (O(window) each time).
  if (imu.t_us - last_constraint_us_ < cfg_.constraint_period_us) return;
  last_constraint_us_ = imu.t_us;
  rest_.evaluate();
  // The IMU alone cannot tell rest from constant velocity or constant
  // acceleration: the UWB track must agree that the vehicle stands still.
  if (rest_.at_rest() && !track_moving(imu.t_us)) {
    // Levelling (roll, pitch) and gyro bias from the rest window; keep the relative yaw.
    const Real yaw_rel = levelled_ ? quat_yaw(q_init_) : Real(0);
    q_init_ = quat_mul(quat_from_yaw(yaw_rel), quat_level(rest_.accel_mean()));
    bg_init_ = rest_.gyro_mean();
    levelled_ = true;
    levelled_at_rest_ = true;
  } else if (!levelled_ && rest_.window_full() && first_imu_t_us_ != 0 &&
             imu.t_us - first_imu_t_us_ > kLevelWithoutRestUs) {
    q_init_ = quat_level(rest_.accel_mean());  // never at rest: mean specific force as vertical
    levelled_ = true;
  }
}

bool Navigator::track_moving(uint64_t t_us) const {
  if (track_count_ == 0) return false;
  const size_t newest = (track_head_ + kTrackCapacity - 1) % kTrackCapacity;
  const TrackFix& fn = track_[newest];
  if (t_us - fn.t_us > kTrackFreshUs) return false;  // no recent fixes: no evidence of motion
  for (size_t k = 1; k < track_count_; ++k) {
    const TrackFix& f = track_[(newest + kTrackCapacity - k) % kTrackCapacity];
    if (f.tag_index != fn.tag_index) continue;
    if (fn.t_us - f.t_us > kTrackFreshUs) break;
    const Real d = (fn.tag_pos_nav_m - f.tag_pos_nav_m).head<2>().norm();
    if (d > Real(3) * (fn.sigma_h_m + f.sigma_h_m) + kRestTrackDist_m) return true;
  }
  return false;
}

bool Navigator::try_ls_fix(uint64_t t_us, int tag_index, TrackFix& fix) {
  LsRange ranges[kMaxAnchors];
  size_t n = 0;
  const Real sigma = cfg_.uwb_sigma_m;
  for (size_t a = 0; a < site_.num_anchors; ++a) {
    const PairRange& pr = pair_[a][tag_index];
    if (!pr.valid || t_us - pr.t_us > window_us_) continue;
    const Real age_s = static_cast<Real>(t_us - pr.t_us) * Real(1e-6);
    const Real smear = cfg_.init_speed * age_s;
    ranges[n].anchor_pos_nav_m = site_.anchors[a].pos_nav_m;
    ranges[n].range_m = pr.range_m;
    ranges[n].sigma_m = static_cast<float>(std::sqrt(sigma * sigma + smear * smear));
    ++n;
  }
  const Vec3 lev = lever(tag_index);
  const Vec3 lever_level = quat_to_dcm(q_init_) * lev;  // yaw does not change the vertical part
  LsOptions opt;
  opt.known_z_m = static_cast<float>(cfg_.origin_height + (levelled_ ? lever_level.z() : lev.z()));
  LsFix ls;
  Status st = Status::kSingular;
  if (!planar_ && n >= 4) st = ls_taylor_solve(ranges, n, opt, ls);
  if (st != Status::kOk && n >= 3) {
    opt.two_d = true;
    st = ls_taylor_solve(ranges, n, opt, ls);
  }
  if (st != Status::kOk || !ls.converged) return false;
  // Reject fixes that contradict their own ranges (NLOS or a stale range):
  // chi-square with dof degrees of freedom, ~99.9 % for small dof.
  if (ls.dof > 0 && static_cast<Real>(ls.weighted_ssr) > Real(10) + Real(6) * static_cast<Real>(ls.dof)) return false;
  if (ls.dof == 0 && static_cast<Real>(ls.gdop) > Real(10)) return false;
  fix.t_us = t_us;
  fix.tag_pos_nav_m = to_vec3(ls.pos_nav_m);
  fix.sigma_h_m = std::sqrt(static_cast<Real>(ls.cov_nav_m2[0][0] + ls.cov_nav_m2[1][1]));
  fix.yaw_rel_rad = quat_yaw(q_init_);
  fix.tag_index = tag_index;
  last_fix_sigma_z_m_ = opt.two_d ? Real(-1) : std::sqrt(static_cast<Real>(ls.cov_nav_m2[2][2]));
  return std::isfinite(fix.sigma_h_m);
}

bool Navigator::init_track(int anchor_index, int tag_index, const UwbRange& range) {
  const uint64_t t = range.t_us;
  pair_[anchor_index][tag_index] = PairRange{t, range.range_m, true};
  if (first_range_t_us_ == 0) {
    first_range_t_us_ = t;
    window_grow_t_us_ = t;
  }
  // Sparse ranging: widen the collection window while no fix comes (up to 10 s).
  if (!have_fix_ && t - window_grow_t_us_ > 3 * window_us_ && window_us_ < kMaxWindowUs) {
    window_us_ = window_us_ * 2 < kMaxWindowUs ? window_us_ * 2 : kMaxWindowUs;
    window_grow_t_us_ = t;
  }
  TrackFix fix;
  if (!try_ls_fix(t, tag_index, fix)) return false;
  have_fix_ = true;
  last_fix_origin_nav_m_ = fix.tag_pos_nav_m - quat_to_dcm(q_init_) * lever(tag_index);
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
  q_init_ = Quat(1, 0, 0, 0);
  bg_init_.setZero();
  track_head_ = 0;
  track_count_ = 0;
  for (auto& f : last_fix_per_tag_) f = TrackFix{};
  first_imu_t_us_ = 0;
}

void Navigator::init_on_range(int anchor_index, int tag_index, const UwbRange& range) {
  const uint64_t t = range.t_us;
  const bool got_fix = init_track(anchor_index, tag_index, range);
  if (!have_fix_) return;
  const TrackFix& fix = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];

  const bool imu_now = imu_alive(t);
  const bool imu_expected = site_.has_imu && t - first_range_t_us_ <= cfg_.imu_timeout_us;
  if (!imu_now && !imu_expected) {
    if (got_fix) start_cv_filter(t, fix);
    return;
  }
  if (!imu_now || !levelled_) return;
  if (phase_ == Phase::kWaitFix) {
    phase_ = Phase::kWaitHeading;
    heading_wait_since_us_ = t;
  }
  if (got_fix) try_heading(t);
  if (phase_ == Phase::kWaitHeading && t - heading_wait_since_us_ > cfg_.init_heading_timeout_us) {
    // No heading source: start with the relative yaw and a yaw sigma that says "unknown".
    const TrackFix& newest = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];
    start_filter(t, newest, Real(0), Real(1.5), Vec3::Zero(), Real(1));
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
      if (len < kMinBaseline_m || len < Real(4) * sig) continue;
      const Real yaw0 = wrap_pi(std::atan2(b_nav.y(), b_nav.x()) - std::atan2(b_rel.y(), b_rel.x()));
      start_filter(t_us, fj, yaw0, std::atan2(Real(2) * sig, len) + Real(0.02), Vec3::Zero(),
                   levelled_at_rest_ ? Real(0.2) : Real(1));
      return;
    }
  }
  // (b) Ground vehicles move forward: each chord of the LS track points along
  // the body x axis at mid-chord, whose gyro-relative yaw is known; the
  // length-weighted circular mean of (chord direction - relative yaw) over the
  // first metres is the start yaw. Works on curved tracks too.
  if (site_.platform != Platform::kGround || track_count_ < 2) return;
  const size_t newest = (track_head_ + kTrackCapacity - 1) % kTrackCapacity;
  const TrackFix& fn = track_[newest];
  const TrackFix* end = &fn;  // end of the chord being built (walking back in time)
  const TrackFix* fv = nullptr;  // >= 0.5 s older than the newest: velocity chord
  Real sum_c = Real(0), sum_s = Real(0), length = Real(0), sig_sum = Real(0);
  Real est_min = Real(10), est_max = Real(-10), first_est = Real(0);
  int chords = 0;
  for (size_t k = 1; k < track_count_ && length < cfg_.init_heading_dist; ++k) {
    const TrackFix& f = track_[(newest + kTrackCapacity - k) % kTrackCapacity];
    if (f.tag_index != fn.tag_index) continue;
    if (fn.t_us - f.t_us > kTrackMaxSpanUs) break;
    if (fv == nullptr && fn.t_us - f.t_us >= 500000) fv = &f;
    const Vec3 chord = end->tag_pos_nav_m - f.tag_pos_nav_m;
    const Real d = chord.head<2>().norm();
    const Real sig = std::sqrt(end->sigma_h_m * end->sigma_h_m + f.sigma_h_m * f.sigma_h_m);
    if (d < kMinChord_m || d < Real(5) * sig) continue;
    const Real turn = wrap_pi(end->yaw_rel_rad - f.yaw_rel_rad);
    const Real est = std::atan2(chord.y(), chord.x()) - (f.yaw_rel_rad + Real(0.5) * turn);
    // Unwrap relative to the first chord's estimate before judging the spread.
    const Real rel = chords == 0 ? Real(0) : wrap_pi(est - first_est);
    if (chords == 0) first_est = est;
    est_min = std::fmin(est_min, rel);
    est_max = std::fmax(est_max, rel);
    sum_c += d * std::cos(est);
    sum_s += d * std::sin(est);
    length += d;
    sig_sum += sig;
    ++chords;
    end = &f;
  }
  if (length < cfg_.init_heading_dist || fv == nullptr || chords == 0) return;
  // Chords disagreeing by more than this are not forward driving (reversing, sliding).
  if (est_max - est_min > kMaxChordSpreadRad) return;
  const Real yaw0 = wrap_pi(std::atan2(sum_s, sum_c));
  const Real dt_v = static_cast<Real>(fn.t_us - fv->t_us) * Real(1e-6);
  Vec3 vel = (fn.tag_pos_nav_m - fv->tag_pos_nav_m) / dt_v;
  vel.z() = Real(0);
  const Real vel_sigma =
      Real(0.3) + Real(2) * std::sqrt(fn.sigma_h_m * fn.sigma_h_m + fv->sigma_h_m * fv->sigma_h_m) / dt_v;
  // Yaw: chord direction noise, side slip allowance and the chords' spread.
  const Real yaw_sigma = std::atan2(Real(2) * sig_sum / static_cast<Real>(chords), length / static_cast<Real>(chords)) /
                             std::sqrt(static_cast<Real>(chords)) +
                         Real(0.03) + Real(0.5) * (est_max - est_min);
  start_filter(t_us, fn, yaw0, yaw_sigma, vel, vel_sigma);
}

void Navigator::setup_height(Real origin_z_m) {
  // Auto: firm on planar layouts (z unobservable), weak otherwise (z observable
  // near the anchors but not far from them; ramps stay within the weak sigma).
  height_on_ = cfg_.ground_constraints && cfg_.height_mode != 0;
  height_sigma_m_ = (cfg_.height_mode == 1 || planar_) ? cfg_.height_sigma : kWeakHeightFactor * cfg_.height_sigma;
  // Planar layouts fixed the height from the survey; otherwise hold the initial fix.
  height_ref_m_ = planar_ ? cfg_.origin_height : origin_z_m;
}

void Navigator::start_filter(uint64_t t_us, const TrackFix& fix, Real yaw_rad, Real yaw_sigma_rad,
                             const Vec3& vel_nav_mps, Real vel_sigma_mps) {
  NominalState x;
  x.q_nav_body = quat_normalised(quat_mul(quat_from_yaw(yaw_rad), q_init_));
  const Mat3 c = quat_to_dcm(x.q_nav_body);
  const Vec3 lev = lever(fix.tag_index);
  x.pos_nav_m = fix.tag_pos_nav_m - c * lev;
  x.vel_nav_mps = vel_nav_mps;
  x.bg_body_radps = bg_init_;
  ErrVec sigma;
  // Heading uncertainty moves the origin by up to |lever| * yaw sigma.
  const Real lever_h = lev.head<2>().norm() * std::fmin(yaw_sigma_rad, Real(1));
  const Real pos_h = std::sqrt(Real(0.5) * fix.sigma_h_m * fix.sigma_h_m + lever_h * lever_h) + Real(0.05);
  const bool ground = site_.platform == Platform::kGround;
  const Real pos_v = last_fix_sigma_z_m_ > Real(0) ? last_fix_sigma_z_m_ : (ground ? Real(0.2) : Real(1.0));
  const Real tilt = levelled_at_rest_ ? Real(0.01) : Real(0.05);
  sigma << pos_h, pos_h, pos_v, vel_sigma_mps, vel_sigma_mps, Real(0.2), tilt, tilt, yaw_sigma_rad,
      cfg_.accel_bias_init, cfg_.accel_bias_init, cfg_.accel_bias_init,
      levelled_at_rest_ ? std::fmin(cfg_.gyro_bias_init, Real(0.002)) : cfg_.gyro_bias_init,
      levelled_at_rest_ ? std::fmin(cfg_.gyro_bias_init, Real(0.002)) : cfg_.gyro_bias_init,
      levelled_at_rest_ ? std::fmin(cfg_.gyro_bias_init, Real(0.002)) : cfg_.gyro_bias_init;
  ekf_.init(x, sigma);
  phase_ = Phase::kRunning;
  cv_mode_ = false;
  t_state_us_ = have_prev_imu_ ? prev_imu_.t_us : t_us;
  running_since_us_ = t_us;
  last_constraint_us_ = t_state_us_;
  after_failure_ = false;
  setup_height(x.pos_nav_m.z());
}

void Navigator::start_cv_filter(uint64_t t_us, const TrackFix& fix) {
  NominalState x;
  x.q_nav_body = levelled_ ? q_init_ : Quat(1, 0, 0, 0);
  const Vec3 lev = lever(fix.tag_index);
  // Heading unknown: take the lever arm's vertical part only, its horizontal part as uncertainty.
  x.pos_nav_m = fix.tag_pos_nav_m - Vec3(0, 0, (quat_to_dcm(x.q_nav_body) * lev).z());
  ErrVec sigma;
  const Real pos_h = std::sqrt(Real(0.5) * fix.sigma_h_m * fix.sigma_h_m + lev.head<2>().squaredNorm()) + Real(0.05);
  const bool ground = site_.platform == Platform::kGround;
  const Real pos_v = last_fix_sigma_z_m_ > Real(0) ? last_fix_sigma_z_m_ : (ground ? Real(0.2) : Real(1.0));
  sigma << pos_h, pos_h, pos_v, Real(2), Real(2), Real(0.5), Real(0.1), Real(0.1), Real(0.1), cfg_.accel_bias_init,
      cfg_.accel_bias_init, cfg_.accel_bias_init, cfg_.gyro_bias_init, cfg_.gyro_bias_init, cfg_.gyro_bias_init;
  ekf_.init(x, sigma);
  phase_ = Phase::kRunning;
  cv_mode_ = true;
  t_state_us_ = t_us;
  running_since_us_ = t_us;
  after_failure_ = false;
  setup_height(x.pos_nav_m.z());
}

}  // namespace uwbnav
