// The estimator's one entry point for the firmware: initialisation (LS-Taylor,
// levelling), the error-state EKF, vehicle constraints, the NLOS gating layer
// and degraded modes, behind a small API. Pure library: no I/O, no heap.
#pragma once

#include <cstdint>

#include "estimator/bias_window.hpp"
#include "estimator/ekf_core.hpp"
#include "estimator/gating.hpp"
#include "estimator/ls_taylor.hpp"
#include "estimator/mm_range.hpp"
#include "estimator/nlos/gating_layer.hpp"
#include "estimator/params.hpp"
#include "estimator/rbf_bridge.hpp"
#include "estimator/rest_detector.hpp"
#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "estimator/yaw_gsf.hpp"

// Outage bridging with the RBF network (estimator/rbf_bridge.hpp). Boards short
// of RAM build without it (0: ekf.rbf_bridge is accepted and has no effect).
#ifndef UWBNAV_RBF_BRIDGE
#define UWBNAV_RBF_BRIDGE 1
#endif

namespace uwbnav {

// Counters the console and CAN diagnostics read. Monotonic since start.
// Recoveries escalate (docs/ekf.md "Recovery"): inflate -> re-anchor -> re-align;
// only a non-finite or exploded state is reset, and output continues throughout.
struct NavDiagnostics {
  uint32_t imu_samples = 0;
  uint32_t ranges_received = 0;
  uint32_t ranges_used = 0;
  uint32_t ranges_rejected = 0;
  uint32_t resets = 0;           // hard resets: non-finite or exploded state (filter restarted)
  uint32_t reinits = 0;          // re-alignments: the IMU filter re-acquires its heading (ranges-only output meanwhile)
  uint32_t inflations = 0;       // divergence met by covariance inflation
  uint32_t reanchors = 0;        // divergence met by re-anchoring position/velocity to the ranges
  uint32_t integrity_fails = 0;  // integrity checks the filter failed (LS fix disagrees beyond chi-square)
  uint32_t short_range_fails = 0;  // short-range tests failed (ranges from two anchors clearly shorter than predicted)
  uint32_t operator_resets = 0;  // reset() calls (console `reset filter`)
  uint32_t iterated_updates = 0;  // range re-linearisations of the iterated update (metre steps across the line of sight)
  uint32_t start_height_switches = 0;  // first 3-D fixes replaced by their mirror or the 2-D fix at the start height (start height prior)
  uint64_t last_imu_t_us = 0;
  uint64_t last_range_used_t_us = 0;
  float uwb_sigma_m = 0.0F;      // learned LOS ranging 1-sigma [m]
  float gyro_bias_rw_gain = 1.0F;   // learned gain on imu.gyro_bias_rw (1-sigma ratio, >= 1) [-]
  float accel_bias_rw_gain = 1.0F;  // learned gain on imu.accel_bias_rw (1-sigma ratio, >= 1) [-]
  RbfBridgeDiag rbf;             // outage bridging (ekf.rbf_bridge): training, predictions, fusions
#if UWBNAV_GNSS
  uint32_t gnss_received = 0;    // fixes handed to on_gnss
  uint32_t gnss_used = 0;        // fixes fused
  uint32_t gnss_rejected[static_cast<size_t>(GnssVerdict::kCount)] = {};  // per GnssVerdict (kFused unused)
  uint64_t last_gnss_used_t_us = 0;  // time of validity of the last fused fix [us]
#endif
#if UWBNAV_COOP
  uint32_t neighbour_states = 0;     // neighbour states stored (on_neighbour_state kOk)
  uint32_t neighbour_evictions = 0;  // states that displaced the stalest vehicle of a full table
  uint32_t neighbour_ranges = 0;     // ranges to neighbour vehicles received
  uint32_t neighbour_used = 0;       // of which fused
  uint32_t neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kCount)] = {};  // per verdict (kFused unused)
  uint64_t last_neighbour_used_t_us = 0;  // time of the last fused neighbour range [us]
#endif
};

// Capacity of the neighbour table (latest broadcast state per vehicle). A state
// from a vehicle not in a full table replaces the vehicle heard from least recently.
#ifndef UWBNAV_MAX_NEIGHBOURS
#define UWBNAV_MAX_NEIGHBOURS 8
#endif
constexpr size_t kMaxNeighbours = UWBNAV_MAX_NEIGHBOURS;

// The range-error state of one anchor, for the console and diagnostics.
struct AnchorOffset {
  float offset_m = kNaNf;        // estimated range offset (NaN: no slot lent) [m]
  float sigma_m = kNaNf;         // its 1-sigma [m]
};

// Per-anchor view for the console `anchors` command and CAN diagnostics.
struct AnchorStatus {
  uint16_t anchor_id = 0;
  uint64_t last_t_us = 0;        // time of the last range received [us]
  float last_range_m = kNaNf;
  float last_innovation_m = kNaNf;
  float last_p_nlos = kNaNf;     // last fused NLOS probability
  uint32_t los_count = 0;        // ranges classified LOS
  uint32_t nlos_count = 0;       // ranges classified NLOS
  uint32_t used_count = 0;       // ranges fused
  bool nlos_state = false;       // current (hysteretic) NLOS state of this anchor
};

// Public API used by firmware/. Calls must come in non-decreasing sensor time;
// the firmware guarantees that (validation rejects out-of-order frames).
class Navigator {
 public:
  Navigator();

  // Loads the site (anchors, tags, platform, calibration) and the parameters; clears state.
  [[nodiscard]] Status configure(const SiteConfig& site, const Params& params);
  // Applies changed parameter values live (console `param set`).
  void update_params(const Params& params);

  // One validated IMU sample: propagates the filter to imu.t_us.
  [[nodiscard]] Status on_imu(const ImuSample& imu);
  // One validated range: gating + sequential scalar update at range.t_us.
  [[nodiscard]] RangeReport on_range(const UwbRange& range);
  // One validated GNSS fix (docs/ekf.md "GNSS"): loose position (and velocity)
  // update of the running filter at the fix's time of validity, lever arm applied.
  [[nodiscard]] GnssReport on_gnss(const GnssFix& fix);
#if UWBNAV_COOP
  // One validated broadcast state of a neighbour vehicle: kept (latest per
  // vehicle) for the ranges to its tag. kInvalidArgument: not a vehicle id,
  // or older than the state already held for that vehicle.
  [[nodiscard]] Status on_neighbour_state(const NeighbourState& state);
  // True while this vehicle's estimate depends on neighbour ranges (the last one
  // fused less than coop.dependent_hold ago): its own broadcast says so.
  bool cooperative_at(uint64_t t_us) const;
#endif
  // The solution at t_us (end of a 10 ms cycle). Resets per-cycle counters.
  [[nodiscard]] NavOutput output(uint64_t t_us);

  // Drops the solution and starts initialisation again (console `reset filter`).
  void reset();

  const NavDiagnostics& diagnostics() const;
  size_t num_anchors() const;
  const AnchorStatus& anchor_status(size_t index) const;
  // Range offset of anchor `index` (into SiteConfig::anchors) and the scale error.
  AnchorOffset anchor_offset(size_t index) const;
  float range_scale() const;

  // Inertial core of the error state for the console `ekf` command.
  static constexpr size_t kErrorStateSize = 15;
  void state_vector(float out[16]) const;   // p(3) v(3) q(4) ba(3) bg(3)
  void covariance_diagonal(float out[kErrorStateSize]) const;
  float covariance(size_t row, size_t col) const;

 private:
  // Initialisation phases (docs/ekf.md): no fix yet -> running (in a mode).
  enum class Phase : uint8_t { kWaitFix, kRunning };

  // Parameter values in the estimator's types (refreshed by update_params).
  struct Config {
    ImuNoise imu;
    Real bias_rw_max_gain = Real(4);       // [-] ceiling of the learned bias random-walk gain (1: off)
    Real gyro_bias_init = Real(8.7e-3);
    Real accel_bias_init = Real(0.15);
    Real uwb_sigma_m = Real(0.1);
    Real uwb_sigma_min_m = Real(0.05);
    Real uwb_sigma_max_m = Real(1.0);
    Real noise_window = Real(200);
    bool learn_noise = true;
    Real anchor_bias_sigma = Real(0.1);
    Real tag_bias_sigma = Real(0.1);
    Real scale_sigma = Real(0.003);
    Real survey_sigma = Real(0.1);
    Real bias_rw = Real(1e-3);
    uint64_t imu_timeout_us = 100000;
    uint64_t uwb_timeout_us = 1000000;
    bool ground_constraints = true;  // effective: param and Platform::kGround
    Real nhc_sigma_lat = Real(0.1);
    Real nhc_sigma_vert = Real(0.1);
    Real pitch_gradient_rad_per_mps2 = Real(0);  // suspension pitch per longitudinal acceleration [rad/(m/s^2)]
    Real zupt_sigma = Real(0.02);
    Real zaru_sigma = Real(2e-3);
    int height_mode = 2;
    Real height_sigma = Real(0.1);
    Real origin_height = Real(0);
    uint64_t constraint_period_us = 100000;
    Real cv_accel_psd = Real(1);
    Real cv_yaw_psd = Real(0.3);
    Real cv_vel_tau = Real(5);      // [s] ranges-only velocity time constant (no IMU)
    uint64_t cv_vel_tau_us = 5000000;  // the same [us] (air: period of the speed prior)
    Real cv_speed_sigma = Real(3);  // [m/s] its stationary 1-sigma per axis
    Real cv_turn_psd = Real(1);     // [rad/s^2/sqrt(Hz)] turn-rate walk without IMU
    Real level_sigma = Real(0.03);  // [rad] ground vehicle without IMU: tilt about level
    uint64_t init_window_us = 300000;
    uint64_t init_redundancy_wait_us = 1000000;  // first fix: wait this long for up to three redundant ranges
    Real init_heading_dist = Real(3);
    uint64_t init_heading_timeout_us = 30000000;
    Real planar_spread = Real(1);
    Real diverge_nis = Real(25);
    Real diverge_fraction = Real(0.8);
    uint64_t diverge_window_us = 4000000;
    uint64_t recover_memory_us = 20000000;
    Real degraded_sigma = Real(1);
    Real init_speed = Real(1);
    Real init_yaw_sigma = Real(0.12);
    RbfMode rbf_mode = RbfMode::kOff;
#if UWBNAV_GNSS
    bool gnss_enable = true;
    int gnss_min_rank = 1;           // lowest fix rank fused (gnss_rank())
    int gnss_min_sv = 5;
    Real gnss_max_sigma = Real(10);  // [m] horizontal
    Real gnss_sigma_scale = Real(1.5);
    Real gnss_corr_time = Real(20);  // [s]
    Real gnss_gate_sigma = Real(5);
    uint64_t gnss_max_latency_us = 500000;
    bool gnss_use_vel = true;
#endif
#if UWBNAV_COOP
    bool coop_enable = true;
    uint64_t coop_max_age_us = 500000;
    Real coop_max_sigma = Real(1);    // [m] horizontal
    Real coop_gate_sigma = Real(4);
    bool coop_accept_dependent = false;
    uint64_t coop_hold_us = 10000000;
    Real coop_extrap_accel = Real(2);  // [m/s^2]
    Real coop_corr_time = Real(10);    // [s]
    Real coop_occluder_m = Real(1.5);  // [m] line of sight to another car's position closer than this: blocked
#endif
  };

  // Latest range per anchor/tag pair (LS fixes).
  struct PairRange {
    uint64_t t_us = 0;
    float range_m = 0.0F;
    bool valid = false;
    // The range's change from the pair's previous range exceeds what noise
    // and the start's motion bound allow (Navigator::range_jumped; before
    // the navigator's first fix only): the pair waits out of the first fix
    // while the redundancy wait lasts.
    bool jumped = false;
  };
  // One LS fix of the initialisation track.
  struct TrackFix {
    uint64_t t_us = 0;
    Vec3 tag_pos_nav_m = Vec3::Zero();
    Real sigma_h_m = Real(0);   // horizontal 1-sigma of the fix [m]
    Real sigma_v_m = Real(-1);  // vertical 1-sigma [m], negative for a 2-D fix
    Real yaw_rel_rad = Real(0); // gyro-integrated yaw of the levelled attitude at t_us
    int tag_index = -1;
    Real age_s = Real(0);       // age of the oldest range in the fix at t_us [s]
  };
  // Least-squares range rate of one anchor over a block of up to
  // kTrackSpeedWindowUs (rest check): sums relative to the block's first
  // range, ranges of one tag only (the block's), and the speed lower bound
  // of the previous block, which ended where this one started.
  struct RangeRateBlock {
    uint64_t t0_us = 0;          // first range of the block [us]
    float r0_m = 0.0F;           // its range [m]
    float t_last_s = 0.0F;       // newest range, from t0 [s]
    float st = 0.0F, sr = 0.0F, stt = 0.0F, str = 0.0F, srr = 0.0F;  // sums of t [s], r - r0 [m]
    float prev_bound_mps = 0.0F; // speed lower bound of the previous block [m/s]
    uint16_t n = 0;
    int8_t tag_index = -1;       // -1: no block
  };
  // An anchor-offset state slot lent to an anchor (ErrIdx::kAnchorBias + slot).
  struct BiasSlot {
    int anchor_index = -1;          // -1: free
    uint64_t last_t_us = 0;         // last range of the anchor [us]
  };
  static constexpr size_t kTrackCapacity = 32;   // 6.4 s of 5 Hz track: the heading's first metres
  static constexpr size_t kMonitorCapacity = 64;

  // navigator_init.cpp
  void restart(bool counted_reset);
  void init_on_imu(const ImuSample& imu);
  bool init_track(int anchor_index, int tag_index, const UwbRange& range);
  void begin_imu_recovery();
  bool try_ls_fix(uint64_t t_us, int tag_index, TrackFix& fix, size_t min_dof = 1, bool accept_rejected = false);
  void try_heading(uint64_t t_us);
  Real speed_lower_bound(uint64_t t_us) const;
  Real track_speed_bound(uint64_t t_us) const;
  // Seed 000 eq. 3-6 before the first fix: |Δρ| of a pair's consecutive
  // ranges beyond kRangeJumpSigma noise sigmas and ekf.init_speed · Δt.
  [[nodiscard]] bool range_jumped(const PairRange& prev, uint64_t t_us, float range_m) const;
  void range_rate_on_range(int anchor_index, int tag_index, uint64_t t_us, float range_m);
  Real range_rate_bound(const RangeRateBlock& b) const;
  Real range_rate_speed_bound(uint64_t t_us) const;
  bool imu_still(uint64_t t_us);
  void start_filter(uint64_t t_us, Real yaw_rad, Real yaw_sigma_rad);
  void yaw_bank_on_range(int anchor_index, int tag_index, const UwbRange& range);
  YawGsf::Noise yaw_bank_noise() const;
  Real levelled_tilt_sigma() const;
  // True when the rest window's mean specific force lies along the vertical of
  // the levelled, gyro-propagated attitude (imu_still: a new rest, not a steady acceleration).
  bool force_along_levelled_vertical(uint64_t t_us) const;
  bool moved_since_rest(uint64_t t_us) const;
  Vec3 levelled_gyro_bias_sigma() const;
  [[nodiscard]] Status robust_ls_fix(LsRange* ranges, size_t n, const LsOptions& opt, LsFix& ls) const;
  void setup_height(Real origin_z_m);
  // vel_h_prior_mps: horizontal velocity prior mean, nav frame [m/s] (zero at a start).
  void start_cv_filter(uint64_t t_us, const TrackFix& fix, NavMode reason, const Vec2& vel_h_prior_mps);
  void align_in_background(int anchor_index, int tag_index, const UwbRange& range);
  void cv_set_yaw(Real yaw_rad, Real yaw_sigma_rad);
  void cv_forget_yaw();
  void cv_start_turn_rate();
  bool average_two_tag_heading(uint64_t t_us, Real yaw_rad, Real sigma_rad, Real baseline_m);

  // navigator.cpp
  bool imu_alive(uint64_t t_us) const;
  // The ranges-only filter without an IMU: its range errors are consider
  // states (learnt by no update), and it runs so for the whole drive.
  bool ranges_only_without_imu(uint64_t t_us) const { return cv_mode_ && !imu_alive(t_us); }
  Real cv_accel_psd(uint64_t t_us) const;
  // The ranges-only model's process at t_us: white acceleration density
  // [m/s^2/sqrt(Hz)] and velocity time constant [s] (0: constant velocity).
  struct CvModel {
    Real accel_psd = Real(1);
    Real vel_tau_s = Real(0);
    Real turn_psd = Real(0);  // [rad/s^2/sqrt(Hz)], 0: no turn-rate state
    Real level_sigma_rad = Real(0);  // ground, no IMU: tilt prior about level [rad], 0: none
  };
  CvModel cv_model(uint64_t t_us) const;
  // Covariance matching of the IMU-bias corrections over a window; scales the
  // bias random walks the IMU filter uses (called after each IMU prediction of dt_s).
  void learn_bias_instability(Real dt_s);
  // Applies the learned gains to imu_eff_ (after the parameters change).
  void apply_bias_rw_gains();
  void track_imu_noise(const Vec3& accel_body_mps2, const Vec3& gyro_body_radps, Real dt_s);
  void enter_cv_mode(NavMode reason);
  void bridge_outage(uint64_t t_us, const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps, Real dt_s);
  void apply_constraints(uint64_t t_us);
  // Keeps the accelerometer bias on the sphere |f_rest - b_a| = g that a rest
  // measured (docs/ekf.md "Vertical balance after a tilt correction"): takes
  // the reference while at rest, then adds the second-order term of the
  // bias's move across the sphere's tangent plane; a move beyond the bias
  // prior's 4 sigma takes back what it added and drops the reference.
  void hold_rest_force_magnitude(bool at_rest);
  // Takes the reference of hold_rest_force_magnitude: the current bias and
  // the body's vertical up_body (unit) where the filter balanced the vertical.
  void set_rest_force_reference(const Vec3& up_body);
  bool fuse(const ScalarObs& obs);
  // Ranges-only filter: predicts to t_us (later than the state), constraints,
  // heading from the velocity. False when the filter restarted on the way.
  bool advance_cv(uint64_t t_us);
  void check_health(bool after_predict = true);
  // Not inlined: its locals stay off on_range's frame, which is on the
  // deepest stack chain (docs/footprint.md).
  [[gnu::noinline]] Real iterated_range_innovation(const RangePrediction& first, Real range_m, Real innovation_m,
                                                   Real hph_m2, Real r_var_m2, int tag_index, int anchor_index, Real dt_s,
                                                   const RangeErrorSlots& slots);
  void monitor_divergence(uint64_t t_us, Real nis);
  void recover(uint64_t t_us, uint8_t min_level = 1);
  void integrity_check(uint64_t t_us, int tag_index);
  void short_range_test(uint64_t t_us, int anchor_index, Real innovation_m, Real innovation_var_m2);
  void clear_short_range_test();  // forgets every run and count (recovery, restart)
  void cover_gap(uint64_t t_us, Real gap_m2);
  Vec3 lever(int tag_index) const;
  Vec3 model_lever(int tag_index) const;
  Vec3 mean_lever() const;
  int lend_bias_slot(int anchor_index, uint64_t t_us);
  void range_error_process_noise(int slot, int anchor_index, int tag_index, uint64_t t_us, const Vec3& tag_pos_nav_m);
  void learn_noise(int anchor_index, int tag_index, uint64_t t_us, Real innovation, Real hph, bool fused);
  // Per-axis survey error the range errors carry [m]: the commissioning's
  // measured systematic sigma on a calibrated site that has one, else uwb.survey_sigma.
  Real survey_sigma_m() const;
  Real anchor_bias_prior_var() const;
  Real tag_bias_prior_var() const;
  Real known_offset_m(int anchor_index, int tag_index) const;

  SiteConfig site_;
  Params params_;
  Config cfg_;
  bool configured_ = false;
  GatingLayer gating_;
  EkfCore ekf_;
  RestDetector rest_;
  NavDiagnostics diag_;
  AnchorStatus anchor_status_[kMaxAnchors];

  Phase phase_ = Phase::kWaitFix;
  bool after_failure_ = false;   // status invalid (not initialising) until running again
  bool cv_mode_ = false;         // running on the constant-velocity model (ranges only)
  NavMode cv_reason_ = NavMode::kUwbOnly;  // why (kUwbOnly, kAligning, kRecovering)
  bool cv_yaw_known_ = false;    // constant-velocity mode: heading estimated (lever arms modelled)
  bool cv_rest_latched_ = false; // constant-velocity mode: rest confirmed and the IMU still since
  bool planar_ = false;          // anchors near-planar: 2-D fix, height constraint (auto)
  bool height_on_ = false;
  Real height_ref_m_ = Real(0);  // body-origin height held by the constraint [m]
  Real height_sigma_m_ = Real(0.1);  // its 1-sigma [m]
  uint64_t t_state_us_ = 0;      // time of the filter state [us]
  uint64_t running_since_us_ = 0;  // time the filter (re)started [us]
  uint64_t last_constraint_us_ = 0;
  uint64_t last_speed_prior_us_ = 0;  // air: last speed-prior pseudo-measurement [us]
  uint64_t last_level_check_us_ = 0;  // levelling / rest judged at the constraint rate while not inertial

  // Range errors: anchor-offset slots, tag-offset time, learned ranging noise.
  BiasSlot slots_[kBiasSlots];
  int8_t anchor_slot_[kMaxAnchors];  // slot lent to each anchor, -1: none
  uint64_t tag_bias_t_us_[kMaxTags] = {};
  Real r_los_m2_ = Real(0.01);   // learned LOS ranging variance [m^2]
  Real r_diff_m2_ = Real(0.01);  // differenced estimate [m^2]
  Real r_sh_m2_ = Real(0.01);    // Sage-Husa estimate [m^2]
  Real r_count_ = Real(0);       // samples of the differenced estimate (saturates at the window)
  Real r_sh_count_ = Real(0);    // samples of the Sage-Husa estimate
  // Per anchor/tag pair: the previous innovation, for the differenced noise estimate.
  struct PrevInnovation {
    uint64_t t_us = 0;
    float innovation_m = 0.0F;
  };
  PrevInnovation prev_innov_[kMaxAnchors][kMaxTags];

  // Recovery ladder and the integrity check.
  uint64_t last_integrity_us_ = 0;
  uint64_t last_recovery_us_ = 0;
  uint8_t recovery_level_ = 0;   // 0 none, 1 inflated, 2 re-anchored (escalates within recover_memory)

  bool have_prev_imu_ = false;
  ImuSample prev_imu_;
  // IMU noise floor measured on line (second differences of the samples):
  // vibration on air platforms is far above the data-sheet densities.
  Vec3 prev2_accel_body_mps2_ = Vec3::Zero();
  Vec3 prev2_gyro_body_radps_ = Vec3::Zero();
  int imu_history_ = 0;              // consecutive samples without a gap (saturates at 2)
  Real accel_d2_ms_ = Real(0);       // EMA of the squared second difference, mean over axes [(m/s^2)^2]
  Real gyro_d2_ms_ = Real(0);        // same for the gyro [(rad/s)^2]
  ImuNoise imu_eff_;                 // densities used: max(parameter, measured floor)
  // Bias instability learned on line (docs/ekf.md "Learned bias instability"):
  // per BiasWindow::Bias (gyro, accelerometer).
  Real rw_var_gain_[2] = {Real(1), Real(1)};  // variance gains on the bias random walks, in [1, bias_rw_max_gain^2] [-]
  Real corr_ratio_[2] = {Real(1), Real(1)};   // windows' mean (squared correction sum / model variance), forgetting [-]
  BiasWindow bias_win_;               // the learning window (closed by start_filter, opened by the next IMU prediction)
  Vec3 last_gyro_body_radps_ = Vec3::Zero();

  // Initialisation / alignment state.
  PairRange pair_[kMaxAnchors][kMaxTags];
  RangeRateBlock range_rate_[kMaxAnchors];  // kept over restarts: the ranges, not the filter
  uint64_t fix_wait_from_us_ = 0;  // first range since the latest (re)start: the first fix's redundancy wait [us]
  uint64_t first_imu_t_us_ = 0;
  uint64_t levelled_t_us_ = 0;      // latest levelling from a window's mean specific force [us]
  bool levelled_ = false;
  bool levelled_at_rest_ = false;
  Quat q_init_ = Quat(1, 0, 0, 0);  // levelled attitude, yaw relative to the unknown start yaw
  Vec3 bg_init_ = Vec3::Zero();
  Vec3 bg_ref_ = Vec3::Zero();      // gyro bias whose 1-sigma is known (rest mean, failed filter's, zero) [rad/s]
  Vec3 ba_init_ = Vec3::Zero();     // accelerometer bias carried over a re-alignment [m/s^2]
  Real accel_h_ms_ = Real(0);         // EMA of the squared horizontal specific force, levelled frame [(m/s^2)^2]
  Real cv_turn_rad_ = Real(0);        // gyro's turn about the vertical since the last ranges-only step (ground) [rad]
  Vec3 rest_ref_body_mps2_ = Vec3::Zero();  // specific force when rest was confirmed (body) [m/s^2]
  Vec3 rest_ref_gyro_body_radps_ = Vec3::Zero();  // mean gyro when rest was confirmed (body) [rad/s]
  bool imu_still_now_ = false;        // result of the latest rest check (init_on_imu, constraint rate)
  bool rest_ref_valid_ = false;       // a confirmed rest is held (rest_ref_* are its references)
  // Reference of hold_rest_force_magnitude: the vertical in the body frame and
  // the accelerometer bias where the filter learnt the vertical balance (the
  // latest rest of the IMU filter, or its start from a levelling at rest). It
  // holds until the next rest, the next start_filter or an implausible move.
  Vec3 rest_force_up_body_ = Vec3::UnitZ();             // unit vector [-]
  Vec3 rest_force_ref_bias_body_mps2_ = Vec3::Zero();   // [m/s^2]
  Real rest_force_curvature_mps2_ = Real(0);            // bias moved along rest_force_up_body_ since [m/s^2]
  bool rest_force_ref_valid_ = false;
  bool dv_rest_valid_ = false;        // dv_rest_lvl_mps_ has integrated every IMU sample since the latest rest (ground)
  Vec2 dv_rest_lvl_mps_ = Vec2::Zero();  // IMU velocity change since the latest rest, levelled frame (relative yaw) [m/s]
  Real turn_rest_rad_ = Real(0);      // rotation of the body since the latest rest (sum of |gyro - bias| dt) [rad]
  TrackFix track_[kTrackCapacity];
  size_t track_head_ = 0;
  size_t track_count_ = 0;
  TrackFix last_fix_per_tag_[kMaxTags];
  // Two-tag heading without IMU, averaged over independent fixes while the
  // vehicle holds its heading (docs/ekf.md "Heading from the tags").
  struct HeadingAverage {
    Real sum_c = Real(0);  // weighted unit vectors, sum of w cos(yaw) [1/rad^2]
    Real sum_s = Real(0);  // sum of w sin(yaw) [1/rad^2]
    Real sum_w = Real(0);  // sum of the weights w = 1/sigma^2 [1/rad^2]
    int n = 0;             // samples
    uint64_t last_t_us = 0;
  };
  HeadingAverage heading_avg_;
  uint64_t last_fix_try_us_[kMaxTags] = {};  // last LS fix attempt per tag (track at ~10 Hz)
  uint64_t heading_wait_since_us_ = 0;
  bool have_fix_ = false;
  bool started_ = false;  // a first fix was made since configure(): the start height prior is spent
  YawGsf gsf_;                    // yaw hypotheses while no heading source has answered
  uint64_t gsf_last_update_us_ = 0;  // last range that updated the yaw bank

  // Per anchor/tag pair: filter tag position at the previous range (gating context).
  Vec3 prev_tag_pos_[kMaxAnchors][kMaxTags];
  bool prev_tag_valid_[kMaxAnchors][kMaxTags] = {};

  // Divergence monitor: per-range NIS flags in a time window.
  uint64_t monitor_t_us_[kMonitorCapacity] = {};
  bool monitor_bad_[kMonitorCapacity] = {};
  size_t monitor_head_ = 0;
  size_t monitor_count_ = 0;
  // Short-range test: ranges clearly shorter than predicted since the last consistent one.
  uint32_t short_count_ = 0;
  uint32_t short_anchor_mask_ = 0;  // bit per anchor index (indices >= 32 share bit 31)
  Real short_gap_m2_ = Real(0);     // largest squared shortfall seen [m^2]
  uint8_t short_run_[kMaxAnchors] = {};  // consecutive short ranges per anchor (its own consistent range clears) [-]

#if UWBNAV_RBF_BRIDGE
  // Outage bridging: the network, and per outage its pseudo-measurements so far.
  RbfBridge bridge_;
  uint64_t bridge_last_us_ = 0;   // last pseudo-measurement [us]
  uint32_t bridge_count_ = 0;     // pseudo-measurements in the current outage
#endif

#if UWBNAV_COOP
  // Latest broadcast state per neighbour vehicle, and when a range to it was last fused.
  struct NeighbourSlot {
    NeighbourState state;
    uint64_t prev_fused_us = 0;   // time of the previous fused range to this vehicle [us] (correlation)
    bool used = false;
  };
  NeighbourSlot neighbours_[kMaxNeighbours];
  RangeReport on_neighbour_range(const UwbRange& range, RangeReport rep);
  bool occluded(uint64_t t_us, const NeighbourSlot* target, const Vec3& tag_nav_m, const Vec3& target_nav_m) const;
#endif

#if UWBNAV_GNSS
  uint64_t gnss_prev_fused_us_ = 0;  // time of validity of the previous fused fix [us] (correlation)
#endif

  uint16_t cycle_used_ = 0;
  uint16_t cycle_rejected_ = 0;
};

}  // namespace uwbnav
