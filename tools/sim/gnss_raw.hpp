// Simulator of raw single-frequency GNSS observations (code, carrier, cycle
// slips) of two receivers on two vehicles driving together, plus the UWB range
// between their tags: the input of estimator/rtk_baseline (issue 16 item 3,
// seed 002). Seeded: the same config and seed give the same run.
// docs/lambda.md "Relative positioning with double differences (rtk_baseline)".
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "estimator/rtk_baseline.hpp"

namespace uwbnav::sim {

struct GnssRawConfig {
  uint64_t seed = 1;
  double duration_s = 120.0;
  double dt_s = 1.0;                     // epoch interval (seed 002: 1 s)
  int min_sats = 6, max_sats = 10;       // satellites in view (drawn per run)
  double min_elevation_deg = 15.0;
  double lambda_m = kBdsB1Wavelength_m;  // BDS B1
  double sigma_code_m = 0.5;             // undifferenced code noise at zenith, / sin(el) [m]
  double sigma_phase_m = 0.003;          // undifferenced carrier noise at zenith, / sin(el) [m]
  double slip_rate_hz = 0.0;             // cycle slips per satellite and receiver per second
  double baseline_min_m = 5.0, baseline_max_m = 20.0;  // initial |b|
  // Convoy geometry: B drives ahead of or behind A in the same street (along
  // x), offset sideways by at most this [m] (within a lane or two).
  double baseline_lateral_max_m = 3.0;
  double relative_walk_m_sqrt_s = 0.03;  // baseline random walk per horizontal axis [m/sqrt(s)] (vertical: 1/5)
  double speed_m_s = 5.0;                // vehicle A drives along x (seed 002: about 5 m/s)
  double sigma_uwb_m = 0.07;             // UWB range noise [m]
  // Street canyon (issue 16 item 4): between canyon_start_s and canyon_end_s
  // both vehicles drive in a street along x between walls. A satellite is
  // blocked for both receivers when its ray hits a wall below the roof line,
  // tan(el) < canyon_height_to_halfwidth * |cos(az)| (az from y, the across-
  // street axis; vehicles on the street centre line). A blocked satellite
  // loses lock: when it reappears its integers are new and the receivers flag
  // a slip. Visible satellites in the canyon carry multipath: per receiver a
  // first-order Gauss-Markov error, sigma / sin(el), on code and on carrier
  // (carrier clipped to +-lambda/4). No canyon when canyon_end_s <= canyon_start_s.
  double canyon_start_s = 0.0, canyon_end_s = 0.0;
  double canyon_height_to_halfwidth = 1.0;  // wall height / street half-width [-]
  double multipath_code_m = 1.0;            // code multipath sigma at zenith [m]
  double multipath_phase_m = 0.01;          // carrier multipath sigma at zenith [m]
  double multipath_corr_s = 10.0;           // multipath correlation time [s]
};

struct GnssRawSat {
  uint16_t sat_id = 0;
  Eigen::Vector3d los_nav = Eigen::Vector3d::Zero();  // unit vector from A toward the satellite
  double elevation_rad = 0.0;
  double code_a_m = 0.0, code_b_m = 0.0;              // pseudoranges incl. receiver clock [m]
  double carrier_a_cyc = 0.0, carrier_b_cyc = 0.0;    // carrier phases [cycles]
  bool slip_a = false, slip_b = false;                // slip flagged by the receiver this epoch
  int64_t amb_a_cyc = 0, amb_b_cyc = 0;               // truth integer ambiguities
  double range_a_m = 0.0, range_b_m = 0.0;            // truth geometric ranges [m]
};

struct GnssRawEpoch {
  double t_s = 0.0;
  bool in_canyon = false;                                    // inside the street canyon
  int sats_in_sky = 0;                                       // satellites above the elevation mask, blocked or not
  Eigen::Vector3d pos_a_nav_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d baseline_nav_m = Eigen::Vector3d::Zero();  // truth b = x_B - x_A
  double clock_a_m = 0.0, clock_b_m = 0.0;                   // receiver clock errors c dt [m]
  double uwb_range_m = 0.0;                                  // measured |b| + noise
  std::vector<GnssRawSat> sats;
};

// One run: duration_s / dt_s + 1 epochs. Static sky (the satellites move by
// well under a degree in 120 s), A at speed_m_s along x, b a random walk.
// An epoch lists only the satellites the receivers track (not blocked).
std::vector<GnssRawEpoch> simulate_gnss_raw(const GnssRawConfig& config);

// Single differences B minus A in the RtkBaseline input form (slip = A or B slipped).
RtkEpoch to_rtk_epoch(const GnssRawEpoch& epoch, bool with_uwb);

// Truth DD ambiguity (N_B - N_A)_sat - (N_B - N_A)_ref [cycles]; 0 and false when an id is missing.
bool truth_dd_ambiguity(const GnssRawEpoch& epoch, uint16_t sat_id, uint16_t ref_id, int64_t& dd_cyc);

}  // namespace uwbnav::sim
