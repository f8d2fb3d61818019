// Plain data types shared by the estimator, the HAL and the firmware: sensor
// samples stamped in microseconds at the sensor, site configuration (anchors,
// tags, platform) and estimator outputs. No Eigen here: these cross the HAL.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "estimator/status.hpp"

namespace uwbnav {

// Estimator floating-point type: float on ECUs, double by compile-time switch.
#ifdef UWBNAV_ESTIMATOR_DOUBLE
using Real = double;
#else
using Real = float;
#endif

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

struct Vec3f {
  float x = 0.0F;
  float y = 0.0F;
  float z = 0.0F;
};

// One IMU sample. Body frame FLU (x fwd, y left, z up), as format v1.
struct ImuSample {
  uint64_t t_us = 0;            // sensor timestamp [us]
  Vec3f accel_body_mps2;        // specific force, body frame [m/s^2]; level at rest: +9.81 on z
  Vec3f gyro_body_radps;        // angular rate, body frame [rad/s]
};

// One two-way range from a tag on the vehicle to a fixed anchor.
struct UwbRange {
  uint64_t t_us = 0;            // sensor timestamp of the ranging exchange [us]
  uint16_t anchor_id = 0;       // anchor id as surveyed (anchors.csv)
  uint8_t tag_id = 0;           // tag id on the vehicle (tags.csv), 0 by default
  float range_m = 0.0F;         // antenna-to-antenna distance [m]
  float fp_power_dbm = kNaNf;   // first-path power [dBm], NaN when unknown
  float rx_power_dbm = kNaNf;   // total received power [dBm], NaN when unknown
};

// Fix quality of a GNSS receiver, as the NMEA GGA quality indicator.
enum class GnssFixType : uint8_t {
  kNone = 0,      // no fix: the row carries no position
  kSingle = 1,    // autonomous (SPS) fix, metres
  kDgnss = 2,     // code-differential (DGNSS / SBAS), decimetres to a metre
  kRtkFixed = 4,  // carrier phase, integer ambiguities fixed, centimetres
  kRtkFloat = 5,  // carrier phase, float ambiguities, decimetres
};

// One GNSS position-velocity fix of the receiver's antenna (docs/dataset-format.md
// "gnss.csv"). Position and velocity are in the navigation frame: the receiver
// driver converts the geodetic solution with the site's survey datum.
struct GnssFix {
  uint64_t t_us = 0;            // time of validity of the solution, sensor clock [us]
  uint64_t rx_t_us = 0;         // arrival at the ECU [us], >= t_us (latency = rx_t_us - t_us)
  Vec3f pos_nav_m;              // antenna position, navigation frame [m]
  Vec3f pos_sigma_m;            // receiver's claimed 1-sigma per axis [m]
  Vec3f vel_nav_mps{kNaNf, kNaNf, kNaNf};  // antenna velocity, navigation frame [m/s]; NaN when not reported
  float vel_sigma_mps = kNaNf;  // receiver's claimed 1-sigma per velocity axis [m/s]; NaN when not reported
  GnssFixType fix = GnssFixType::kSingle;
  uint8_t num_sv = 0;           // satellites used, 0 = unknown
};

// Ranges to another vehicle's tag (issue 16 item 1, docs/dataset-format.md
// "neighbours.csv"): a UwbRange whose anchor_id is at least kFirstVehicleId
// names a vehicle, not a surveyed anchor. Vehicle ids are kFirstVehicleId..0xFFFE.
constexpr uint16_t kFirstVehicleId = 0x8000;
constexpr uint16_t kNoVehicleId = 0xFFFF;
constexpr bool is_vehicle_id(uint16_t id) { return id >= kFirstVehicleId && id != kNoVehicleId; }

// One broadcast state of another vehicle's ranging tag: what that vehicle's
// uwbnav publishes (CAN UWBNAV_Coop*, or a recording's neighbours.csv).
// Position and covariance are of the tag antenna the vehicle ranges with.
struct NeighbourState {
  uint64_t t_us = 0;            // time of validity, sensor clock [us]
  uint64_t rx_t_us = 0;         // arrival at the ECU [us], >= t_us
  uint16_t vehicle_id = kNoVehicleId;  // sender, kFirstVehicleId..0xFFFE
  Vec3f pos_nav_m;              // tag antenna, navigation frame [m]
  // Position covariance, navigation frame [m^2]: xx, xy, xz, yy, yz, zz.
  float cov_pos_m2[6] = {kNaNf, kNaNf, kNaNf, kNaNf, kNaNf, kNaNf};
  Vec3f vel_nav_mps{kNaNf, kNaNf, kNaNf};  // tag velocity, navigation frame [m/s]; NaN when not reported
  // True when the sender's own state used neighbour ranges recently: its
  // estimate then shares information with other vehicles (maybe with us).
  bool cooperative = false;
};

// Boards with little RAM may build with fewer tags (UWBNAV_MAX_TAGS, e.g.
// hal/mps2); per anchor/tag pair state scales with kMaxAnchors * kMaxTags.
#ifndef UWBNAV_MAX_TAGS
#define UWBNAV_MAX_TAGS 4
#endif
#ifndef UWBNAV_MAX_ANCHORS
#define UWBNAV_MAX_ANCHORS 16
#endif
constexpr size_t kMaxAnchors = UWBNAV_MAX_ANCHORS;  // capacity of the anchor table
static_assert(kMaxAnchors >= 4 && kMaxAnchors <= 16, "anchor table: 4..16 (CAN NLOS mask has 16 bits)");
constexpr size_t kMaxTags = UWBNAV_MAX_TAGS;  // capacity of the tag table
static_assert(kMaxTags >= 1 && kMaxTags <= 255, "tag ids and indices are uint8_t");

struct Anchor {
  uint16_t id = 0;
  Vec3f pos_nav_m;              // surveyed antenna position, navigation frame (ENU-like, z up) [m]
};

struct Tag {
  uint8_t id = 0;
  Vec3f lever_body_m;           // antenna position in the body frame (FLU) [m]
};

enum class Platform : uint8_t { kGround = 0, kAir = 1 };

// Everything the firmware must know about the site and the vehicle. Filled by
// the board (recording, simulator, parameter store) once at start-up.
struct SiteConfig {
  Anchor anchors[kMaxAnchors];
  size_t num_anchors = 0;
  Tag tags[kMaxTags];
  size_t num_tags = 0;
  Platform platform = Platform::kGround;
  float gravity_mps2 = 9.80665F;  // local gravity magnitude [m/s^2]
  bool has_imu = true;            // false for UWB-only recordings
  // Commissioned ranging calibration (`uwbnav calibrate`, docs/commissioning.md):
  // per anchor/tag pair (indices into anchors[] and tags[]) the offset of the
  // radio's ranges, measured minus true [m], which the estimator subtracts, and
  // the 1-sigma uncertainty of those offsets [m]. range_offset_sigma_m NaN: the
  // site is uncalibrated (offsets all zero, the filter's own bias prior applies).
  float range_offset_m[kMaxAnchors][kMaxTags] = {};
  float range_offset_sigma_m = kNaNf;
  // The range error the commissioned offsets leave as the line of sight
  // changes (measured by `uwbnav calibrate` from its slowly varying residuals)
  // [m]; the filter carries it in place of uwb.survey_sigma. NaN: not
  // measured, uwb.survey_sigma applies.
  float range_systematic_sigma_m = kNaNf;
  // GNSS antenna position in the body frame (FLU) [m]; meta.ini `gnss_lever_m`.
  Vec3f gnss_lever_body_m;

  // Returns index into anchors[] or -1 when unknown.
  int find_anchor(uint16_t id) const {
    for (size_t i = 0; i < num_anchors; ++i) {
      if (anchors[i].id == id) return static_cast<int>(i);
    }
    return -1;
  }
  int find_tag(uint8_t id) const {
    for (size_t i = 0; i < num_tags; ++i) {
      if (tags[i].id == id) return static_cast<int>(i);
    }
    return -1;
  }
  [[nodiscard]] Status add_anchor(uint16_t id, Vec3f pos_nav_m) {
    if (find_anchor(id) >= 0) return Status::kInvalidArgument;
    if (num_anchors >= kMaxAnchors) return Status::kFull;
    anchors[num_anchors++] = Anchor{id, pos_nav_m};
    return Status::kOk;
  }
  [[nodiscard]] Status add_tag(uint8_t id, Vec3f lever_body_m) {
    if (find_tag(id) >= 0) return Status::kInvalidArgument;
    if (num_tags >= kMaxTags) return Status::kFull;
    tags[num_tags++] = Tag{id, lever_body_m};
    return Status::kOk;
  }
};

// Navigation solution status, as published in estimates.csv and on CAN.
enum class NavStatus : uint8_t {
  kInitialising = 0,  // no fix yet (waiting for ranges / levelling)
  kValid = 1,         // nominal: IMU + UWB fused, covariance within bounds
  kDegraded = 2,      // coasting (UWB outage) or UWB-only (no IMU); usable with care
  kInvalid = 3,       // no trustworthy solution (diverged, reset pending)
};

constexpr const char* nav_status_name(NavStatus s) {
  switch (s) {
    case NavStatus::kInitialising: return "initialising";
    case NavStatus::kValid: return "valid";
    case NavStatus::kDegraded: return "degraded";
    case NavStatus::kInvalid: return "invalid";
  }
  return "unknown";
}

// Which solution the output carries (docs/ekf.md "Modes"). The status says how
// far to trust it; the mode says where it comes from.
enum class NavMode : uint8_t {
  kNone = 0,        // no estimate yet: position unknown (NaN), status initialising
  kInertial = 1,    // the IMU/UWB error-state EKF (nominal)
  kUwbOnly = 2,     // ranges alone (constant-velocity model): no IMU on this vehicle or IMU lost
  kAligning = 3,    // IMU present, heading not yet acquired: ranges-only solution meanwhile
  kRecovering = 4,  // the IMU filter is being re-anchored after divergence: ranges-only solution meanwhile
  kLsFix = 5,       // snapshot multilateration of the latest ranges (no filter yet)
};

constexpr const char* nav_mode_name(NavMode m) {
  switch (m) {
    case NavMode::kNone: return "none";
    case NavMode::kInertial: return "inertial";
    case NavMode::kUwbOnly: return "uwb-only";
    case NavMode::kAligning: return "aligning";
    case NavMode::kRecovering: return "recovering";
    case NavMode::kLsFix: return "ls-fix";
  }
  return "unknown";
}

// Output of the estimator every 10 ms cycle (body origin, navigation frame).
struct NavOutput {
  uint64_t t_us = 0;
  NavStatus status = NavStatus::kInitialising;
  NavMode mode = NavMode::kNone;  // source of the solution
  Vec3f pos_nav_m;               // body origin position [m]
  Vec3f vel_nav_mps;             // body origin velocity [m/s]
  float q_nav_body[4] = {1.0F, 0.0F, 0.0F, 0.0F};  // Hamilton, scalar first, body->nav
  Vec3f pos_sigma_m;             // claimed 1-sigma per axis [m]
  float pos_xy_corr = 0.0F;      // correlation coefficient of x/y position errors [-]
  Vec3f vel_sigma_mps;           // claimed 1-sigma velocity per axis [m/s]
  float heading_rad = 0.0F;      // yaw of body x axis from nav x axis, CCW positive [rad]
  float heading_sigma_rad = kNaNf;  // claimed 1-sigma of heading_rad [rad]; NaN: the heading is not an estimate
  uint16_t ranges_used = 0;      // ranges fused since the previous output
  uint16_t ranges_rejected = 0;  // ranges rejected since the previous output
  uint32_t resets = 0;           // filter resets since start
};

// What the estimator decided about one range, for ranges.csv, CAN and console.
struct RangeReport {
  uint64_t t_us = 0;
  uint16_t anchor_id = 0;
  uint8_t tag_id = 0;
  float range_m = 0.0F;
  float innovation_m = kNaNf;    // measured minus predicted range [m], NaN if not computed
  float innovation_var_m2 = kNaNf;  // innovation variance S [m^2]
  float p_svm = kNaNf;           // SVM NLOS probability p1 (seed 000 §1.2(1)), NaN if not run
  float p_mc = kNaNf;            // consistency-model NLOS probability p2 (eq. 6)
  float p_fused = kNaNf;         // fused NLOS probability R (eq. 8) or the policy's evidence
  bool nlos = false;             // the gating layer's NLOS decision
  bool used = false;             // fused into the filter
};

// What the estimator did with one GNSS fix (docs/ekf.md "GNSS"). Stable order (console).
enum class GnssVerdict : uint8_t {
  kFused = 0,      // position (and velocity, when reported) fused
  kDisabled,       // gnss.enable = 0, or the board build has no GNSS fusion
  kNoFilter,       // no filter running yet: GNSS does not start one (the ranges do)
  kQuality,        // degraded fix: quality, satellites or claimed sigma (gnss.min_quality, min_sv, max_sigma)
  kLate,           // latency above gnss.max_latency
  kGate,           // innovation outside gnss.gate_sigma on some axis
  kCount
};

constexpr const char* gnss_verdict_name(GnssVerdict v) {
  switch (v) {
    case GnssVerdict::kFused: return "fused";
    case GnssVerdict::kDisabled: return "disabled";
    case GnssVerdict::kNoFilter: return "no_filter";
    case GnssVerdict::kQuality: return "quality";
    case GnssVerdict::kLate: return "late";
    case GnssVerdict::kGate: return "gate";
    case GnssVerdict::kCount: break;
  }
  return "unknown";
}

struct GnssReport {
  uint64_t t_us = 0;             // the fix's time of validity [us]
  GnssVerdict verdict = GnssVerdict::kDisabled;
  Vec3f innovation_m{kNaNf, kNaNf, kNaNf};  // antenna position, measured minus predicted, nav frame [m]
  float nis_max = kNaNf;         // largest innov^2 / S over the position axes [-]
  bool vel_used = false;         // the velocity was fused too
};

// What the Navigator did with one range to a neighbour vehicle.
enum class NeighbourVerdict : uint8_t {
  kFused = 0,      // fused with the neighbour's uncertainty considered
  kDisabled,       // coop.enable = 0, or the build has no cooperative ranging
  kNoFilter,       // no filter running yet: neighbour ranges do not start one
  kUnknown,        // no broadcast state of that vehicle in the table
  kStale,          // the neighbour's state is older than coop.max_age
  kDependent,      // the neighbour's state is itself cooperative (double counting)
  kUncertain,      // the neighbour's claimed position sigma exceeds coop.max_sigma
  kOccluded,       // another neighbour's car lies on the line of sight (coop.occluder_m)
  kGate,           // innovation outside coop.gate_sigma
  kCount
};

constexpr const char* neighbour_verdict_name(NeighbourVerdict v) {
  switch (v) {
    case NeighbourVerdict::kFused: return "fused";
    case NeighbourVerdict::kDisabled: return "disabled";
    case NeighbourVerdict::kNoFilter: return "no_filter";
    case NeighbourVerdict::kUnknown: return "unknown";
    case NeighbourVerdict::kStale: return "stale";
    case NeighbourVerdict::kDependent: return "dependent";
    case NeighbourVerdict::kUncertain: return "uncertain";
    case NeighbourVerdict::kOccluded: return "occluded";
    case NeighbourVerdict::kGate: return "gate";
    case NeighbourVerdict::kCount: break;
  }
  return "unknown";
}

}  // namespace uwbnav
