// Scenario data model of the simulator and its INI-like text format
// (docs/simulator.md): site, route, IMU errors, UWB ranging, NLOS geometry, channel.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"

namespace uwbnav::sim {

// One step of the route. Speed/yaw/height changes follow the smooth profile
// q(u) = q0 + dq * (u - sin(2*pi*u) / (2*pi)), u = tau / T, so acceleration is
// continuous and jerk is zero at both ends (docs/simulator.md "Truth").
enum class ManeuverKind : uint8_t {
  kHold = 0,   // keep speed, heading and height for duration_s
  kSpeed = 1,  // change speed to value [m/s] over duration_s
  kTurn = 2,   // change heading by value [deg, CCW positive] over duration_s at the current speed
  kClimb = 3,  // change height by value [m] over duration_s (level body)
};

struct Maneuver {
  ManeuverKind kind = ManeuverKind::kHold;
  double value = 0.0;       // target speed [m/s], turn [deg] or climb [m]; unused for hold
  double duration_s = 1.0;  // [s], > 0
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
};

struct UwbConfig {
  double rate_hz = 50.0;            // ranging rate per tag, round-robin over anchors [Hz]
  double offset_ms = 3.0;           // time of the first range after t = 0 [ms]
  double sigma_m = 0.10;            // LOS ranging noise 1-sigma (seed 000 Table 1) [m]
  double packet_loss = 0.02;        // probability a range slot produces nothing [-]
  bool channel_diagnostics = true;  // write fp_power_dbm / rx_power_dbm
  std::vector<Outage> outages;
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
  double start_nav_m[3] = {0, 0, 0};  // body origin at t = 0 [m]
  double start_heading_deg = 0.0;     // yaw of body x from nav x, CCW [deg]
  size_t loop_from = 0;               // maneuver index the route repeats from when exhausted
  std::vector<Maneuver> maneuvers;    // empty: parked for the whole run
};

struct Scenario {
  std::string name = "custom";
  std::string description;
  double duration_s = 60.0;
  std::string platform = "ground";    // ground | air
  double gravity_mps2 = 9.80665;      // rounded to float on load (the value the recording carries)
  std::vector<AnchorDef> anchors;
  std::vector<TagDef> tags;
  ImuConfig imu;
  UwbConfig uwb;
  NlosConfig nlos;
  ChannelConfig channel;
  VehicleConfig vehicle;
  RouteConfig route;
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

}  // namespace uwbnav::sim
