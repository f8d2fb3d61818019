// Scenario data model of the simulator and its INI-like text format
// (docs/simulator.md): site, route, IMU errors, UWB ranging, NLOS geometry,
// channel, GNSS receiver, neighbour vehicles (cooperative ranging).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav::sim {

// One step of the route. Speed/yaw/height changes follow the smooth profile
// q(u) = q0 + dq * (u - sin(2*pi*u) / (2*pi)), u = tau / T, so acceleration is
// continuous and jerk is zero at both ends (docs/simulator.md "Truth").
enum class ManeuverKind : uint8_t {
  kHold = 0,   // keep speed, heading and height for duration_s
  kSpeed = 1,  // change speed to value [m/s] over duration_s
  kTurn = 2,   // change heading by value [deg, CCW positive] over duration_s at the current speed
  kClimb = 3,  // change height by value [m] over duration_s (level body)
  // Multicopter route (route.kind = multicopter) only; rest-to-rest profiles with
  // the 7th-order smooth step (continuous jerk, so the body rates are continuous):
  kGoto = 4,   // fly to (arg[0], arg[1], arg[2]) [m] over duration_s
  kEight = 5,  // figure-eight about the current point: x' = arg[0] sin(phi), y' = arg[1] sin(2 phi) [m],
               // axes rotated by arg[2] [deg], arg[3] loops over duration_s
};

struct Maneuver {
  ManeuverKind kind = ManeuverKind::kHold;
  double value = 0.0;       // target speed [m/s], turn [deg] or climb [m]; unused for hold
  double duration_s = 1.0;  // [s], > 0
  double arg[4] = {0, 0, 0, 0};  // goto / eight arguments (see ManeuverKind)
};

// How the route is flown (docs/simulator.md "Truth").
enum class RouteKind : uint8_t {
  kVehicle = 0,      // ground vehicle: speed / turn / climb along the heading, suspension attitude
  kMulticopter = 1,  // 3-D position profile, tilt from the commanded acceleration, independent yaw
};

// Range schedule of the radios (docs/simulator.md "UWB model").
enum class UwbSchedule : uint8_t {
  kRoundRobin = 0,  // rate_hz ranges per second per tag, round-robin over the anchors
  kPerAnchor = 1,   // rate_hz ranges per second per anchor and tag, round-robin (total rate x anchors)
  kFrame = 2,       // every 1 / rate_hz each tag ranges every anchor at the same time stamp
};

// Distribution of NLOS episode lengths and biases.
enum class RandomLaw : uint8_t {
  kExponential = 0,
  kLogNormal = 1,
};

// Constant range offset (antenna delay) of one anchor, one tag or one anchor/tag pair.
struct RangeOffset {
  uint16_t anchor_id = 0;  // unused for a tag offset
  uint8_t tag_id = 0;      // unused for an anchor offset
  double offset_m = 0.0;   // added to every range of that anchor / tag / pair [m]
};

struct AnchorDef {
  uint16_t id = 0;
  double pos_nav_m[3] = {0, 0, 0};
};

struct TagDef {
  uint8_t id = 0;
  double lever_body_m[3] = {0, 0, 0};  // antenna position in the body frame (FLU) [m]
};

// Axis-aligned obstacle in the navigation frame.
struct Box {
  double min_nav_m[3] = {0, 0, 0};
  double max_nav_m[3] = {0, 0, 0};
};

// Full UWB outage [start_s, end_s): no range is produced inside.
struct Outage {
  double start_s = 0.0;
  double end_s = 0.0;
};

struct ImuConfig {
  bool enabled = true;                          // false: UWB-only recording (no imu.csv)
  double rate_hz = 100.0;                       // sample rate; 1e6 / rate must be an integer [us]
  double gyro_bias_sigma_dps = 0.5;             // turn-on bias 1-sigma per axis (seed 000 Table 1) [deg/s]
  double gyro_arw_dps_per_sqrt_h = 0.1;         // angle random walk (seed 000 Table 1) [deg/sqrt(h)]
  double gyro_bias_rw_dps_per_sqrt_s = 0.0005;  // bias random walk [deg/s/sqrt(s)]
  double accel_bias_sigma_mg = 15.0;            // turn-on bias 1-sigma per axis (seed 000 Table 1) [mg]
  double accel_noise_ug_per_sqrt_hz = 150.0;    // white noise density [ug/sqrt(Hz)]
  double accel_bias_rw_mps2_per_sqrt_s = 5e-5;  // bias random walk [m/s^2/sqrt(s)]
  double gyro_range_dps = 150.0;                // saturation (seed 000 Table 1) [deg/s]
  double accel_range_g = 5.0;                   // saturation (seed 000 Table 1) [g]
  double gyro_lsb_dps = 0.0;                    // quantisation step, 0 = off [deg/s]
  double accel_lsb_mg = 0.0;                    // quantisation step, 0 = off [mg]
  // Vibration (multicopter rotors): extra zero-mean noise per axis, white when
  // vibration_hz = 0, else band-limited around vibration_hz (resonator).
  double vibration_accel_mps2 = 0.0;            // RMS per axis [m/s^2]
  double vibration_gyro_dps = 0.0;              // RMS per axis [deg/s]
  double vibration_hz = 0.0;                    // centre frequency, 0 = white [Hz]
  double vibration_bandwidth_hz = 5.0;          // -3 dB bandwidth of the resonator [Hz]
};

struct UwbConfig {
  double rate_hz = 50.0;            // ranging rate per tag (schedule round_robin) or per anchor [Hz]
  UwbSchedule schedule = UwbSchedule::kRoundRobin;
  double offset_ms = 3.0;           // time of the first range after t = 0 [ms]
  double sigma_m = 0.10;            // LOS ranging noise 1-sigma (seed 000 Table 1) [m]
  double packet_loss = 0.02;        // probability a range slot produces nothing [-]
  bool channel_diagnostics = true;  // write fp_power_dbm / rx_power_dbm
  std::vector<Outage> outages;
  double range_lsb_m = 0.0;         // range quantisation step, 0 = off [m]
  // Constant offsets per run (antenna delays): drawn N(0, sigma) per anchor,
  // per tag and per pair, or given explicitly (an explicit value replaces the draw).
  double anchor_offset_sigma_m = 0.0;  // [m]
  double tag_offset_sigma_m = 0.0;     // [m]
  double pair_offset_sigma_m = 0.0;    // [m]
  std::vector<RangeOffset> anchor_offsets;
  std::vector<RangeOffset> tag_offsets;
  std::vector<RangeOffset> pair_offsets;
  // Scale error (clock drift): measured = (1 + s) true + ..., s = common + N(0, pair sigma) per pair.
  double scale_common_pct = 0.0;       // [%]
  double scale_pair_sigma_pct = 0.0;   // [%]
  // Gilbert-Elliott burst loss per anchor/tag pair: long-run share of ranges
  // lost in bursts and mean burst length, on top of the independent packet_loss.
  double burst_loss = 0.0;             // [-]
  double burst_mean_len = 5.0;         // mean burst length [ranges of that pair]
  // Anchor blockage schedule: after a gap U[gap_min, gap_max], block_anchors
  // random anchors fall silent for U[block_min, block_max]; repeat.
  size_t block_anchors = 0;            // anchors blocked at a time, 0 = off
  double block_min_s = 5.0;            // [s]
  double block_max_s = 20.0;           // [s]
  double block_gap_min_s = 10.0;       // [s]
  double block_gap_max_s = 30.0;       // [s]
  // Coverage: a range whose true distance exceeds this produces nothing.
  double max_range_m = 0.0;            // [m], 0 = unlimited
};

// What a GNSS window does to the fixes inside it (docs/simulator.md "GNSS model").
enum class GnssWindowKind : uint8_t {
  kBlocked = 0,    // no fix at all (tunnel, bridge)
  kMultipath = 1,  // extra slowly turning bias, claimed sigma grows only by multipath_claim_factor, fix single
};

// GNSS window [start_s, end_s).
struct GnssWindow {
  GnssWindowKind kind = GnssWindowKind::kBlocked;
  double start_s = 0.0;  // [s]
  double end_s = 0.0;    // [s]
};

// GNSS receiver: position-velocity fixes of its antenna (open sky: DGNSS-like).
struct GnssConfig {
  bool enabled = false;                 // false: no fixes (no gnss.csv)
  double rate_hz = 5.0;                 // fixes per second; 1e6 / rate must be an integer [us]
  double latency_ms = 80.0;             // mean delay from the time of validity to the arrival [ms]
  double latency_jitter_ms = 20.0;      // per-fix latency = mean + U[-jitter, +jitter] [ms]
  double lever_body_m[3] = {0, 0, 0};   // antenna position in the body frame (FLU) [m]
  // Open-sky position error per navigation axis: first-order Gauss-Markov
  // (stationary sigma, correlation time) plus white noise.
  double sigma_h_m = 0.8;               // Gauss-Markov 1-sigma, x and y [m]
  double sigma_v_m = 1.5;               // Gauss-Markov 1-sigma, z [m]
  double tau_s = 30.0;                  // Gauss-Markov correlation time [s]
  double sigma_white_m = 0.1;           // white noise 1-sigma per axis [m]
  // Claimed sigma = true stationary sigma sqrt(gm^2 + white^2) x claim_ratio (receivers misreport).
  double claim_ratio = 1.0;             // [-]
  double vel_sigma_mps = 0.05;          // white velocity noise per axis (claimed: x claim_ratio) [m/s]
  unsigned num_sv = 12;                 // satellites used in open sky (multipath: about half), 0 = unknown [-]
  double multipath_bias_m = 4.0;        // horizontal magnitude of the multipath bias [m]
  double multipath_turn_dps = 5.0;      // its direction turns at U[0.5, 1] x this rate, random sign [deg/s]
  double multipath_claim_factor = 2.0;  // claimed sigma and velocity noise factor in multipath [-]
  std::vector<GnssWindow> windows;
};

struct NlosConfig {
  std::vector<Box> boxes;
  double box_bias_mean_m = 0.8;       // mean positive bias of a box-blocked range [m]
  double box_extra_sigma_m = 0.15;    // extra Gaussian noise of a box-blocked range [m]
  bool body_block = true;             // vehicle body blocks rear anchors lower than the tag
  double body_cone_deg = 30.0;        // half-angle of the rearward blocked cone [deg]
  double body_bias_mean_m = 0.5;      // mean positive bias of a body-blocked range [m]
  double body_extra_sigma_m = 0.10;   // extra Gaussian noise of a body-blocked range [m]
  double bias_shape = 0.6;            // log-normal log-space sigma of an episode bias [-]
  double bias_jitter_shape = 0.3;     // log-normal range-to-range jitter of the bias [-]
  double outlier_prob = 0.005;        // probability of a gross outlier per range [-]
  double outlier_min_m = 2.0;         // gross outlier magnitude, log-uniform [m]
  double outlier_max_m = 30.0;        // [m]
  double outlier_positive_prob = 0.8; // probability an outlier is positive [-]
  bool protocol = false;              // seed 000 §2.1 labelling protocol instead of geometry
  double protocol_fraction = 0.5;     // fraction of each anchor's ranges labelled NLOS [-]
  double protocol_mean_min_m = 1.0;   // per-range mean of the added error ~ U[min, max] [m]
  double protocol_mean_max_m = 2.0;   // [m]
  double protocol_spread_m = 0.3;     // Gaussian spread around that mean [m]
  // Random NLOS episodes independent of geometry: per anchor/tag pair an
  // alternating renewal process of LOS stretches and NLOS episodes.
  double episode_share = 0.0;              // long-run share of time in NLOS, 0 = off [-]
  double episode_mean_s = 2.0;             // mean NLOS episode length [s]
  RandomLaw episode_length_law = RandomLaw::kExponential;
  double episode_length_shape = 1.0;       // log-space sigma of log-normal lengths [-]
  double episode_bias_mean_m = 0.5;        // mean episode bias [m]
  RandomLaw episode_bias_law = RandomLaw::kLogNormal;  // log-normal uses bias_shape
  double episode_extra_sigma_m = 0.10;     // extra Gaussian noise of episode ranges [m]
};

struct ChannelConfig {
  double rx_power_1m_dbm = -60.0;     // total received power at 1 m, LOS [dBm]
  double path_loss_exponent = 2.0;    // log-distance path-loss exponent [-]
  double shadowing_sigma_db = 1.5;    // log-normal shadowing [dB]
  double nlos_extra_loss_db = 5.0;    // extra attenuation of blocked paths [dB]
  double los_gap_mean_db = 2.5;       // rx - fp in LOS, folded normal mean [dB]
  double los_gap_sigma_db = 1.5;      // [dB]
  double nlos_gap_mean_db = 9.0;      // rx - fp in NLOS / outliers [dB]
  double nlos_gap_sigma_db = 2.5;     // [dB]
};

struct VehicleConfig {
  double roll_gain_deg_per_mps2 = 0.4;   // body roll per lateral acceleration (outward) [deg/(m/s^2)]
  double pitch_gain_deg_per_mps2 = 0.3;  // body pitch per longitudinal acceleration (nose dips braking)
};

struct RouteConfig {
  RouteKind kind = RouteKind::kVehicle;
  double start_nav_m[3] = {0, 0, 0};  // body origin at t = 0 [m]
  double start_heading_deg = 0.0;     // yaw of body x from nav x, CCW [deg]
  size_t loop_from = 0;               // maneuver index the route repeats from when exhausted
  std::vector<Maneuver> maneuvers;    // empty: parked for the whole run
  std::vector<Maneuver> yaw_turns;    // multicopter: heading changes on their own timeline (kTurn; 0 deg = hold)
};

// How a neighbour vehicle moves (docs/simulator.md "Cooperative ranging").
enum class NeighbourMotion : uint8_t {
  kOffset = 0,  // the ego's route translated by a fixed offset (convoy, adjacent lane)
  kRoute = 1,   // a route of its own (start pose and maneuvers; repeats its last maneuver when exhausted)
};

// One neighbour vehicle: its motion, its ranging tag and the error of the state it broadcasts.
struct NeighbourDef {
  uint16_t id = kFirstVehicleId;             // vehicle id (uwb.csv anchor_id of the ranges to its tag)
  NeighbourMotion motion = NeighbourMotion::kOffset;
  double offset_m[2] = {0, 0};               // kOffset: ahead of and left of the ego's start pose [m]
  RouteConfig route;                         // kRoute: start pose and maneuvers (vehicle kind)
  double tag_lever_body_m[3] = {0, 0, 1.2};  // its ranging tag in its body frame (FLU) [m]
  // Broadcast position error: per axis of its along-track / cross-track / up
  // frame a stationary first-order Gauss-Markov error with these 1-sigmas,
  // which the broadcast covariance claims (honestly).
  double sigma_m[3] = {0.1, 0.1, 0.2};       // along, cross, up [m]
  double tau_s = 10.0;                       // correlation time [s]
};

// Most neighbour vehicles a scenario may have.
constexpr size_t kMaxSimVehicles = 16;

// Neighbour vehicles: their broadcast states (neighbours.csv) and the ego's ranges to their tags.
struct CoopConfig {
  std::vector<NeighbourDef> vehicles;  // none: no neighbours.csv and no inter-vehicle ranges
  double rate_hz = 10.0;               // broadcast states per second per vehicle; 1e6 / rate an integer [us]
  double latency_ms = 50.0;            // mean delay from the time of validity to the arrival [ms]
  double latency_jitter_ms = 20.0;     // per-state latency = mean + U[-jitter, +jitter] [ms]
  double vel_sigma_mps = 0.05;         // white noise of the broadcast velocity per axis [m/s]
  bool dependent = false;              // broadcast coop = 1 (the senders used neighbour ranges)
  double range_rate_hz = 10.0;         // ranges per second per neighbour and ego tag; 1e6 / rate an integer [us]
  double range_offset_ms = 5.0;        // time of the first inter-vehicle range slot [ms]
  double box_m[3] = {4.5, 1.8, 1.5};   // vehicle body box: length, width (centred on the body origin), height [m]
  double nlos_bias_min_m = 0.2;        // bias of a range blocked by a third vehicle ~ U[min, max] per blockage [m]
  double nlos_bias_max_m = 1.5;        // [m]
  double nlos_extra_sigma_m = 0.15;    // extra Gaussian noise of a blocked range [m]
};

struct SiteErrors {
  double survey_sigma_m = 0.0;  // anchors.csv = true position + N(0, sigma) per axis [m]
};

struct Scenario {
  std::string name = "custom";
  std::string description;
  double duration_s = 60.0;
  std::string platform = "ground";    // ground | air
  double gravity_mps2 = 9.80665;      // rounded to float on load (the value the recording carries)
  std::vector<AnchorDef> anchors;     // true antenna positions (ranges are made from these)
  std::vector<TagDef> tags;
  SiteErrors site;
  ImuConfig imu;
  UwbConfig uwb;
  NlosConfig nlos;
  ChannelConfig channel;
  VehicleConfig vehicle;
  RouteConfig route;
  GnssConfig gnss;
  CoopConfig coop;
};

// Names of the built-in presets; the first is the default scenario.
std::vector<std::string> preset_names();

// Scenario text of a preset, or an empty string when `name` is not a preset.
std::string preset_text(const std::string& name);

// Every "section.key" the parser accepts (for the documentation test).
std::vector<std::string> scenario_keys();

// Parses scenario text. `origin` prefixes error messages (file name or preset).
// On failure returns non-kOk and a one-line "origin:line: reason" in `error`.
[[nodiscard]] Status parse_scenario(const std::string& text, const std::string& origin, Scenario& out,
                                    std::string* error);

// A preset name or the path of a scenario file.
[[nodiscard]] Status load_scenario(const std::string& name_or_path, Scenario& out, std::string* error);

// Consistency checks after parsing (ids, rates, probabilities, geometry).
[[nodiscard]] Status validate_scenario(const Scenario& s, std::string* error);

// Rounds gravity, anchor positions and lever arms (tags, GNSS antenna) to float, the precision the
// recording carries (parse_scenario does this; scenarios built in code call it).
void snap_to_recording_precision(Scenario& s);

// Named IMU grades (imu.grade): sets the noise, bias and range figures of `imu`.
// False when `grade` is unknown. Grades: consumer, mems (the default), automotive.
bool apply_imu_grade(const std::string& grade, ImuConfig& imu);
std::vector<std::string> imu_grade_names();

}  // namespace uwbnav::sim
