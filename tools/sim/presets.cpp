// Built-in simulator scenarios, written in the scenario text format
// (docs/simulator.md) so that every preset exercises the parser.
#include <string>
#include <vector>

#include "tools/sim/scenario.hpp"

namespace uwbnav::sim {
namespace {

// Seed 000 §2.1 set-up: outdoor parking lot 60 m x 40 m, 4 anchors at the
// corners at 1.5 m, slightly lower than the roof tag (1.7 m). The loop is
// counter-clockwise through (8..52 m) x (7..33 m); opposite sides are identical
// maneuver lists, so every loop closes exactly and long drives stay in the lot.
const char* const kParkingSite = R"(
[scenario]
duration_s = 180
platform = ground
gravity_mps2 = 9.80665

[site]
anchor = 1  0  0 1.5
anchor = 2 60  0 1.5
anchor = 3 60 40 1.5
anchor = 4  0 40 1.5
# roof antenna 0.5 m ahead of the body origin (ground level below the rear axle), 1.7 m up
tag = 0 0.5 0 1.7

[route]
start = 9.636 7 0 0
loop_from = 2
# parked for levelling, then pull away
maneuver = hold 12
maneuver = speed 3 3
# long side: accelerate, brake to a stop, wait, pull away, left turn (opposite side identical)
maneuver = speed 5 3
maneuver = hold 1.0454822550
maneuver = speed 0 4
maneuver = hold 4
maneuver = speed 3 3
maneuver = turn 90 3.5
# short side: S-bend (left then right), left turn
maneuver = hold 0.3624822055
maneuver = turn 25 2
maneuver = turn -25 2
maneuver = hold 0.3624822055
maneuver = turn 90 3.5
maneuver = speed 5 3
maneuver = hold 1.0454822550
maneuver = speed 0 4
maneuver = hold 4
maneuver = speed 3 3
maneuver = turn 90 3.5
maneuver = hold 0.3624822055
maneuver = turn 25 2
maneuver = turn -25 2
maneuver = hold 0.3624822055
maneuver = turn 90 3.5
)";

// Geometry NLOS of the parking lot: parked vans and the vehicle's own body.
const char* const kParkingObstacles = R"(
[nlos]
# parked vans (5 m x 2 m x 2.5 m)
box = 27 2.5 0  32 4.5 2.5
box = 54.5 17 0  56.5 22 2.5
box = 3 26 0  5 31 2.5
body_block = 1
body_cone_deg = 30
outlier_prob = 0.005
)";

const char* const kLosOnly = R"(
[nlos]
body_block = 0
outlier_prob = 0
)";

std::string parking_nlos() {
  return std::string(kParkingSite) + kParkingObstacles + R"(
[scenario]
name = parking_nlos
description = seed 000 set-up: parking lot 60x40 m, 4 corner anchors at 1.5 m below the 1.7 m roof tag, 180 s of loops with stops and turns; NLOS from 3 parked vans and the vehicle body, 0.5 % gross outliers, 2 % packet loss
[uwb]
packet_loss = 0.02
)";
}

std::string parking_los() {
  return std::string(kParkingSite) + kLosOnly + R"(
[scenario]
name = parking_los
description = seed 000 parking lot drive in line of sight: no obstacles, no body blocking, no outliers, 2 % packet loss
[uwb]
packet_loss = 0.02
)";
}

std::string parking_outages() {
  return std::string(kParkingSite) + kLosOnly + R"(
[scenario]
name = parking_outages
description = parking_los with full UWB outages of 5 s [40,45), 10 s [80,90) and 15 s [120,135)
[uwb]
packet_loss = 0.02
outage = 40 45
outage = 80 90
outage = 120 135
)";
}

std::string seed000_protocol() {
  // 36004 slots: 9001 per anchor at 50 Hz round-robin (seed 000 §2.1).
  return std::string(kParkingSite) + kLosOnly + R"(
[scenario]
name = seed000_protocol
description = seed 000 §2.1 identification protocol: LOS driving, half of each anchor's ranges get an added error of mean U[1,2] m (spread 0.3 m) and are labelled NLOS; 9001 ranges per anchor
duration_s = 720.08
[uwb]
packet_loss = 0
channel_diagnostics = 0
[nlos]
protocol = 1
protocol_fraction = 0.5
protocol_mean_min_m = 1
protocol_mean_max_m = 2
protocol_spread_m = 0.3
)";
}

std::string indoor3d() {
  // Seed 003 §3: indoor 3-D positioning, 4 anchors at different heights, a
  // small robot at walking speed with ramps (+/-0.4 m) on the short sides.
  return R"(
[scenario]
name = indoor3d
description = seed 003 indoor 3-D variant: 10x8 m room, 4 anchors at 0.4-2.9 m, robot at 0.5-1.5 m/s with ramps, one pillar, 0.5 % outliers
duration_s = 120
platform = ground
gravity_mps2 = 9.80665

[site]
anchor = 1 0.2 0.2 0.4
anchor = 2 9.8 0.3 2.6
anchor = 3 9.7 7.8 1.2
anchor = 4 0.3 7.7 2.9
tag = 0 0.1 0 0.5

[vehicle]
roll_gain_deg_per_mps2 = 0.2
pitch_gain_deg_per_mps2 = 0.2

[uwb]
packet_loss = 0.02

[nlos]
box = 4.6 3.6 0  5.4 4.4 3
body_block = 0
outlier_prob = 0.005

[route]
start = 2.169 2 0 0
loop_from = 2
maneuver = hold 10
maneuver = speed 1 2
maneuver = speed 1.5 1
maneuver = hold 0.358
maneuver = speed 0 1.5
maneuver = hold 3
maneuver = speed 1 1.5
maneuver = turn 90 2
maneuver = climb 0.4 1.662
maneuver = turn 90 2
maneuver = speed 1.5 1
maneuver = hold 0.358
maneuver = speed 0 1.5
maneuver = hold 3
maneuver = speed 1 1.5
maneuver = turn 90 2
maneuver = climb -0.4 1.662
maneuver = turn 90 2
)";
}

std::string drone_indoor() {
  // Indoor multicopter like the MILUV set-up: 10x8 m hall, 6 anchors at
  // 0.4-2.9 m, 25 Hz per anchor, take-off with an arbitrary heading, climb,
  // figure-eight, waypoints with hover phases and yaw turns, landing.
  return R"(
[scenario]
name = drone_indoor
description = indoor multicopter: 10x8 m hall, 6 anchors at 0.4-2.9 m, 25 Hz per anchor, take-off, figure-eight, waypoints, hover, yaw turns, landing; consumer IMU with rotor vibration; no body blocking
duration_s = 120
platform = air
gravity_mps2 = 9.80665

[site]
anchor = 1 0.3 0.3 0.4
anchor = 2 9.7 0.2 2.9
anchor = 3 9.8 7.7 0.5
anchor = 4 0.2 7.8 2.7
anchor = 5 5.0 0.1 1.6
anchor = 6 5.1 7.9 2.2
tag = 0 0.1 0 0.05

[imu]
rate_hz = 200
grade = consumer
vibration_accel_mps2 = 0.3
vibration_gyro_dps = 0.5
vibration_hz = 30
vibration_bandwidth_hz = 6

[uwb]
schedule = per_anchor
rate_hz = 25
packet_loss = 0.02

[nlos]
body_block = 0
outlier_prob = 0.005

[route]
kind = multicopter
start = 3 3 0.1 37
maneuver = hold 10
maneuver = goto 3 3 1.5 5
maneuver = hold 3
maneuver = eight 2 1.5 20 2 30
maneuver = goto 6.5 5 2 6
maneuver = hold 4
maneuver = goto 7 2.5 1.2 5
maneuver = hold 2
maneuver = goto 4 4 1.8 6
maneuver = eight 1.5 1 -30 1 15
maneuver = goto 3 3 1.5 5
maneuver = goto 3 3 0.1 5
maneuver = hold 100
yaw = 0 20
yaw = 90 6
yaw = 0 25
yaw = -180 10
)";
}

std::string drive_1h() {
  return std::string(kParkingSite) + kParkingObstacles + R"(
[scenario]
name = drive_1h
description = one-hour parking-lot drive (parking_nlos loops) for throughput tests; set duration_s for other lengths
duration_s = 3600
[uwb]
packet_loss = 0.02
)";
}

}  // namespace

std::vector<std::string> preset_names() {
  return {"parking_nlos", "parking_los", "seed000_protocol", "parking_outages", "indoor3d", "drive_1h", "drone_indoor"};
}

std::string preset_text(const std::string& name) {
  if (name == "parking_nlos") return parking_nlos();
  if (name == "parking_los") return parking_los();
  if (name == "seed000_protocol") return seed000_protocol();
  if (name == "parking_outages") return parking_outages();
  if (name == "indoor3d") return indoor3d();
  if (name == "drive_1h") return drive_1h();
  if (name == "drone_indoor") return drone_indoor();
  return std::string();
}

}  // namespace uwbnav::sim
