// Deterministic UWB/IMU/GNSS scenario simulator: produces a format v1 Recording
// (truth, IMU, ranges with NLOS labels, GNSS fixes, neighbour vehicles' states and
// the ranges to their tags) from a scenario preset or file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/sim/scenario.hpp"

namespace uwbnav::sim {

// Names of the built-in scenarios; the first is the default of the main job.
std::vector<std::string> preset_names();

// Runs a built-in preset (by name) or a scenario file (by path). Same seed ->
// bit-identical recording. `error` receives a one-line reason on failure.
[[nodiscard]] Status simulate(const std::string& scenario, uint64_t seed, dataset::Recording& out,
                              std::string* error);

// ---- Extended interface (tests, evaluation) ----

struct SimOptions {
  uint64_t seed = 0;
  bool ideal_imu = false;  // no bias, noise, quantisation: IMU = exact truth derivatives
  bool ideal_uwb = false;  // no noise, NLOS bias, outliers, packet or burst loss, offsets, scale error,
                           // quantisation or survey error (outages and blockage schedules still apply)
};

// Why a range deviates from the true distance (evaluation only).
enum class RangeCause : uint8_t {
  kLos = 0,       // noise only
  kBox = 1,       // blocked by an obstacle box (may also be body-blocked)
  kBody = 2,      // blocked by the vehicle body only
  kOutlier = 3,   // gross outlier (possibly on top of a blocked path)
  kProtocol = 4,  // seed 000 §2.1 protocol: added error, labelled NLOS
  kEpisode = 5,   // random NLOS episode (renewal process, not geometry)
  kVehicle = 6,   // range to a neighbour vehicle's tag blocked by a third vehicle's body box
};

// Per-range ground truth, parallel to Recording::uwb.
struct RangeTruth {
  double true_range_m = 0.0;  // tag antenna (truth pos + R lever) to anchor or neighbour vehicle's tag [m]
  double bias_m = 0.0;        // NLOS / outlier / protocol error added on top of the LOS noise [m]
  double offset_m = 0.0;      // systematic part: anchor + tag + pair offset + scale error * true range [m]
  RangeCause cause = RangeCause::kLos;
};

// One entry of the anchor blockage schedule: the anchors are silent in [start_s, end_s).
struct Blockage {
  double start_s = 0.0;
  double end_s = 0.0;
  std::vector<uint16_t> anchor_ids;
};

// Constant ranging errors of one anchor/tag pair for the whole run.
struct PairError {
  uint16_t anchor_id = 0;
  uint8_t tag_id = 0;
  double offset_m = 0.0;  // anchor + tag + pair offset [m]
  double scale = 0.0;     // measured = (1 + scale) true + ... [-]
};

// Full truth at every IMU instant, parallel to Recording::truth.
struct TruthState {
  uint64_t t_us = 0;
  double pos_nav_m[3] = {0, 0, 0};
  double vel_nav_mps[3] = {0, 0, 0};
  double acc_nav_mps2[3] = {0, 0, 0};
  double q_nav_body[4] = {1, 0, 0, 0};      // Hamilton, scalar first, body -> nav
  double gyro_body_radps[3] = {0, 0, 0};    // true body rate
  double accel_body_mps2[3] = {0, 0, 0};    // true specific force (FLU, +g on z at rest)
};

// Per-fix ground truth, parallel to Recording::gnss (evaluation only).
struct GnssTruth {
  double antenna_nav_m[3] = {0, 0, 0};         // true antenna position at t_us (body origin + R lever) [m]
  double antenna_vel_nav_mps[3] = {0, 0, 0};   // true antenna velocity (v + R (w x lever)) [m/s]
  double error_nav_m[3] = {0, 0, 0};           // fix minus truth before rounding to float [m]
  bool multipath = false;                      // inside a multipath window
};

// Per-state ground truth, parallel to Recording::neighbours (evaluation only).
struct NeighbourTruth {
  double tag_nav_m[3] = {0, 0, 0};        // the vehicle's true tag antenna at t_us [m]
  double tag_vel_nav_mps[3] = {0, 0, 0};  // its true velocity (v + R (w x lever)) [m/s]
  double error_nav_m[3] = {0, 0, 0};      // broadcast position minus truth before rounding to float [m]
};

struct SimOutput {
  dataset::Recording rec;
  std::vector<TruthState> truth;         // same instants as rec.truth / rec.imu
  std::vector<RangeTruth> range_truth;   // same order as rec.uwb
  Scenario scenario;                     // what was simulated (anchors: true positions)
  std::vector<AnchorDef> anchors_surveyed;  // what anchors.csv carries (true + survey error)
  std::vector<PairError> pair_errors;    // per (tag, anchor), tag-major
  std::vector<Blockage> blockages;       // anchor blockage schedule
  std::vector<GnssTruth> gnss_truth;     // same order as rec.gnss
  std::vector<NeighbourTruth> neighbour_truth;  // same order as rec.neighbours
};

// Simulates a parsed scenario.
[[nodiscard]] Status simulate_scenario(const Scenario& scenario, const SimOptions& options, SimOutput& out,
                                       std::string* error);

// Loads a preset or file, then simulates it.
[[nodiscard]] Status simulate(const std::string& scenario, const SimOptions& options, SimOutput& out,
                              std::string* error);

}  // namespace uwbnav::sim
