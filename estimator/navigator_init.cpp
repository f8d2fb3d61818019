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
constexpr int kYawBankMinUpdates = 10;             // yaw bank: fewest ranges before it may start the filter
constexpr Real kYawBankCorrTime_s = Real(1);       // yaw bank: correlation time turning bias/tilt into white noise [s]
constexpr Real kTiltSigmaRest_rad = Real(0.01);    // tilt 1-sigma after levelling at rest [rad]
constexpr Real kTiltSigmaMoving_rad = Real(0.05);  // tilt 1-sigma when levelled on the move [rad]
constexpr Real kMaxLinearYawSigma_rad = Real(0.5); // largest yaw 1-sigma the IMU filter is started with

// Chi-square acceptance of an LS fix with dof degrees of freedom (~99.9 % for small dof).
bool ls_consistent(const LsFix& ls) {
  if (ls.dof == 0) return static_cast<Real>(ls.gdop) <= Real(10);
  return static_cast<Real>(ls.weighted_ssr) <= Real(10) + Real(6) * static_cast<Real>(ls.dof);
}

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
  gsf_.reset();
  ekf_.init(NominalState{}, ErrVec::Ones());
}

void Navigator::init_on_imu(const ImuSample& imu) {
  const Vec3 w_mean = Real(0.5) * (to_vec3(imu.gyro_body_radps) + to_vec3(prev_imu_.gyro_body_radps));
  const Real dt = static_cast<Real>(imu.t_us - prev_imu_.t_us) * Real(1e-6);
  if (levelled_) {
    // Attitude with an arbitrary (relative) yaw until the heading is known.
    const Vec3 dtheta = (w_mean - bg_init_) * dt;
    if (gsf_.active()) {
      const Vec3 f_mean = Real(0.5) * (to_vec3(imu.accel_body_mps2) + to_vec3(prev_imu_.accel_body_mps2));
      gsf_.accumulate(quat_to_dcm(quat_mul(q_init_, quat_exp(Real(0.5) * dtheta))) * f_mean, dt);
    }
    q_init_ = quat_normalised(quat_mul(q_init_, quat_exp(dtheta)));
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
  // 3-D when the layout allows it; 2-D (known height) for planar layouts or
  // when the 3-D geometry is singular - never as a way around a 3-D fix that
  // failed its own consistency test (the height assumption would absorb it).
  Status st = Status::kSingular;
  if (!planar_ && n >= 4) st = robust_ls_fix(ranges, n, opt, ls);
  if (st != Status::kOk && st != Status::kRejected && n >= 3) {
    opt.two_d = true;
    st = robust_ls_fix(ranges, n, opt, ls);
  }
  if (st != Status::kOk) return false;
  fix.t_us = t_us;
  fix.tag_pos_nav_m = to_vec3(ls.pos_nav_m);
  fix.sigma_h_m = std::sqrt(static_cast<Real>(ls.cov_nav_m2[0][0] + ls.cov_nav_m2[1][1]));
  fix.yaw_rel_rad = quat_yaw(q_init_);
  fix.tag_index = tag_index;
  last_fix_sigma_z_m_ = opt.two_d ? Real(-1) : std::sqrt(static_cast<Real>(ls.cov_nav_m2[2][2]));
  return std::isfinite(fix.sigma_h_m);
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
  pair_[anchor_index][tag_index] = PairRange{t, range.range_m, true};
  if (first_range_t_us_ == 0) {
    first_range_t_us_ = t;
    window_grow_t_us_ = t;
  }
  // Sparse ranging: widen the collection window while no fix comes (up to 10 s).
  if (!have_fix_ && t - window_grow_t_us_ > 2 * window_us_ && window_us_ < kMaxWindowUs) {
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
  gsf_.reset();
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
  if (phase_ == Phase::kWaitHeading) yaw_bank_on_range(anchor_index, tag_index, range);
  if (phase_ == Phase::kWaitHeading && t - heading_wait_since_us_ > cfg_.init_heading_timeout_us) {
    // No heading yet. With a yaw the linearisation can carry, start the IMU
    // filter from the bank; otherwise an IMU filter would integrate the
    // specific force in an unknown direction and claim a covariance its
    // linearisation cannot honour: run on ranges alone (constant velocity,
    // degraded) while the bank keeps listening, and switch when it converges.
    const TrackFix& newest = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];
    if (gsf_.active() && gsf_.yaw_sigma() < kMaxLinearYawSigma_rad) {
      start_from_yaw_bank(t, kMaxLinearYawSigma_rad);
    } else {
      start_cv_filter(t, newest);
    }
  }
}

YawGsf::Noise Navigator::yaw_bank_noise() const {
  // The models estimate neither accelerometer bias nor tilt: both enter as
  // white acceleration with a 1 s correlation time, on top of the measured
  // accelerometer noise; the start yaw walks with gyro noise and bias.
  YawGsf::Noise nz;
  const Real tilt = levelled_at_rest_ ? kTiltSigmaRest_rad : kTiltSigmaMoving_rad;
  const Real g_tilt = static_cast<Real>(site_.gravity_mps2) * tilt;
  const Real ba = cfg_.accel_bias_init;
  nz.accel_psd = std::sqrt(imu_eff_.accel_noise * imu_eff_.accel_noise + (ba * ba + g_tilt * g_tilt) * kYawBankCorrTime_s);
  const Real bg = levelled_at_rest_ ? std::fmin(cfg_.gyro_bias_init, Real(0.002)) : cfg_.gyro_bias_init;
  nz.yaw_psd = std::sqrt(imu_eff_.gyro_noise * imu_eff_.gyro_noise + bg * bg * kYawBankCorrTime_s);
  return nz;
}

void Navigator::yaw_bank_on_range(int anchor_index, int tag_index, const UwbRange& range) {
  const Mat3 c_lvl = quat_to_dcm(q_init_);
  if (!gsf_.active()) {
    if (!have_fix_ || track_count_ == 0) return;
    // Seed at the newest fix (this range is part of it).
    const TrackFix& fix = track_[(track_head_ + kTrackCapacity - 1) % kTrackCapacity];
    const bool ground = site_.platform == Platform::kGround;
    const Real pos_v = last_fix_sigma_z_m_ > Real(0) ? last_fix_sigma_z_m_ : (ground ? Real(0.2) : Real(1.0));
    const Real vel_sigma = levelled_at_rest_ && !track_moving(range.t_us) ? Real(0.2) : cfg_.init_speed;
    gsf_.start(fix.tag_pos_nav_m, c_lvl * lever(fix.tag_index), Real(0),
               fix.sigma_h_m * std::sqrt(Real(0.5)) + Real(0.05), pos_v, std::fmax(vel_sigma, Real(0.2)));
    return;
  }
  gsf_.propagate(static_cast<Real>(site_.gravity_mps2), yaw_bank_noise());
  if (!gsf_.update_range(to_vec3(site_.anchors[anchor_index].pos_nav_m), c_lvl * lever(tag_index),
                         static_cast<Real>(range.range_m), cfg_.uwb_sigma_m)) {
    return;
  }
  // Ground vehicles get their heading from the track (try_heading), which is
  // honest about its uncertainty; the bank's yaw sigma is optimistic early on
  // (measured: 0.3-1.1 m errors at a claimed 5 cm after such a start), so on
  // the ground it is only the fallback after the heading timeout.
  const bool bank_may_start = site_.platform == Platform::kAir;
  if (bank_may_start && gsf_.updates() >= kYawBankMinUpdates && gsf_.yaw_sigma() < cfg_.init_yaw_sigma) {
    start_from_yaw_bank(range.t_us, cfg_.init_yaw_sigma);
  }
}

void Navigator::start_from_yaw_bank(uint64_t t_us, Real max_yaw_sigma_rad) {
  Vec3 pos, pos_sigma, vel, vel_sigma;
  gsf_.mixture(pos, pos_sigma, vel, vel_sigma);
  const Real yaw_sigma = std::fmin(std::fmax(gsf_.yaw_sigma(), Real(0.02)), max_yaw_sigma_rad);
  start_filter_at(t_us, pos, pos_sigma, gsf_.yaw_mean(), yaw_sigma, vel, vel_sigma);
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
  const Mat3 c = quat_to_dcm(quat_normalised(quat_mul(quat_from_yaw(yaw_rad), q_init_)));
  const Vec3 lev = lever(fix.tag_index);
  // Heading uncertainty moves the origin by up to |lever| * yaw sigma.
  const Real lever_h = lev.head<2>().norm() * std::fmin(yaw_sigma_rad, Real(1));
  const Real pos_h = std::sqrt(Real(0.5) * fix.sigma_h_m * fix.sigma_h_m + lever_h * lever_h) + Real(0.05);
  const bool ground = site_.platform == Platform::kGround;
  const Real pos_v = last_fix_sigma_z_m_ > Real(0) ? last_fix_sigma_z_m_ : (ground ? Real(0.2) : Real(1.0));
  start_filter_at(t_us, fix.tag_pos_nav_m - c * lev, Vec3(pos_h, pos_h, pos_v), yaw_rad, yaw_sigma_rad, vel_nav_mps,
                  Vec3(vel_sigma_mps, vel_sigma_mps, Real(0.2)));
}

void Navigator::start_filter_at(uint64_t t_us, const Vec3& pos_nav_m, const Vec3& pos_sigma_m, Real yaw_rad,
                                Real yaw_sigma_rad, const Vec3& vel_nav_mps, const Vec3& vel_sigma_mps) {
  NominalState x;
  x.q_nav_body = quat_normalised(quat_mul(quat_from_yaw(yaw_rad), q_init_));
  x.pos_nav_m = pos_nav_m;
  x.vel_nav_mps = vel_nav_mps;
  x.bg_body_radps = bg_init_;
  ErrVec sigma;
  const Real tilt = levelled_at_rest_ ? kTiltSigmaRest_rad : kTiltSigmaMoving_rad;
  sigma << pos_sigma_m.x(), pos_sigma_m.y(), pos_sigma_m.z(), vel_sigma_mps.x(), vel_sigma_mps.y(),
      vel_sigma_mps.z(), tilt, tilt, yaw_sigma_rad,
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
  gsf_.reset();
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
