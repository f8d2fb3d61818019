// Simulator of raw code/carrier observations of two receivers plus the UWB
// range between the vehicles (see gnss_raw.hpp; seed 002 set-up: BDS B1, 1 s).
#include "tools/sim/gnss_raw.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace uwbnav::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kSatDistance_m = 21.5e6;  // slant range scale of BDS MEO/IGSO
}  // namespace

std::vector<GnssRawEpoch> simulate_gnss_raw(const GnssRawConfig& c) {
  std::mt19937_64 rng(c.seed * 0x9E3779B97F4A7C15ULL + 0x5eedULL);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_int_distribution<int> nsat_dist(std::min(c.min_sats, c.max_sats), std::max(c.min_sats, c.max_sats));
  std::uniform_int_distribution<int64_t> amb_dist(-1000000, 1000000);
  std::uniform_int_distribution<int> slip_dist(1, 60);

  const int nsat = nsat_dist(rng);
  const double min_el = c.min_elevation_deg * kPi / 180.0;
  std::vector<Eigen::Vector3d> sat_pos(static_cast<size_t>(nsat));
  std::vector<uint16_t> ids(static_cast<size_t>(nsat));
  std::vector<int64_t> amb_a(static_cast<size_t>(nsat)), amb_b(static_cast<size_t>(nsat));
  std::vector<double> az_rad(static_cast<size_t>(nsat));
  for (int i = 0; i < nsat; ++i) {
    const double az = 2.0 * kPi * u01(rng);
    // sin(el) uniform between sin(min_el) and sin(85 deg).
    const double s = std::sin(min_el) + (std::sin(85.0 * kPi / 180.0) - std::sin(min_el)) * u01(rng);
    const double el = std::asin(s);
    const Eigen::Vector3d e(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
    sat_pos[static_cast<size_t>(i)] = kSatDistance_m * e;
    az_rad[static_cast<size_t>(i)] = az;
    ids[static_cast<size_t>(i)] = static_cast<uint16_t>(i + 1 + static_cast<int>(u01(rng) * 3.0) * 20);
    amb_a[static_cast<size_t>(i)] = amb_dist(rng);
    amb_b[static_cast<size_t>(i)] = amb_dist(rng);
  }
  const double len0 = c.baseline_min_m + (c.baseline_max_m - c.baseline_min_m) * u01(rng);
  const double lateral0 = std::min(c.baseline_lateral_max_m, len0) * (2.0 * u01(rng) - 1.0);
  const double along0 = (u01(rng) < 0.5 ? -1.0 : 1.0) * std::sqrt(std::max(0.0, len0 * len0 - lateral0 * lateral0));
  Eigen::Vector3d b(along0, lateral0, 0.3 * (2.0 * u01(rng) - 1.0));
  double clk_a = 3e5 * (2.0 * u01(rng) - 1.0);
  double clk_b = 3e5 * (2.0 * u01(rng) - 1.0);

  const int n_epochs = static_cast<int>(std::floor(c.duration_s / c.dt_s + 1e-9)) + 1;
  std::vector<GnssRawEpoch> out;
  out.reserve(static_cast<size_t>(n_epochs));
  const double p_slip = std::clamp(c.slip_rate_hz * c.dt_s, 0.0, 1.0);
  // Canyon state per satellite: blocked at the previous epoch, multipath
  // errors of A and B (code [m], carrier [m]) while in the canyon.
  const bool has_canyon = c.canyon_end_s > c.canyon_start_s;
  std::vector<char> was_blocked(static_cast<size_t>(nsat), 0);
  std::vector<Eigen::Vector4d> mp(static_cast<size_t>(nsat), Eigen::Vector4d::Zero());
  std::vector<char> mp_on(static_cast<size_t>(nsat), 0);
  const double mp_phi = c.multipath_corr_s > 0.0 ? std::exp(-c.dt_s / c.multipath_corr_s) : 0.0;
  const double mp_drive = std::sqrt(std::max(0.0, 1.0 - mp_phi * mp_phi));
  for (int k = 0; k < n_epochs; ++k) {
    GnssRawEpoch ep;
    ep.t_s = k * c.dt_s;
    ep.in_canyon = has_canyon && ep.t_s >= c.canyon_start_s && ep.t_s < c.canyon_end_s;
    ep.sats_in_sky = nsat;
    if (k > 0) {
      const double w = c.relative_walk_m_sqrt_s * std::sqrt(c.dt_s);
      b += Eigen::Vector3d(w * n01(rng), w * n01(rng), 0.2 * w * n01(rng));
      clk_a += 30.0 * n01(rng);  // free-running receiver clocks (cancel in DD)
      clk_b += 30.0 * n01(rng);
    }
    ep.pos_a_nav_m = Eigen::Vector3d(c.speed_m_s * ep.t_s, 0.0, 0.0);
    ep.baseline_nav_m = b;
    ep.clock_a_m = clk_a;
    ep.clock_b_m = clk_b;
    ep.uwb_range_m = b.norm() + c.sigma_uwb_m * n01(rng);
    const Eigen::Vector3d pos_b = ep.pos_a_nav_m + b;
    for (int i = 0; i < nsat; ++i) {
      const size_t si = static_cast<size_t>(i);
      GnssRawSat s;
      s.sat_id = ids[si];
      const Eigen::Vector3d da = sat_pos[si] - ep.pos_a_nav_m;
      const Eigen::Vector3d db = sat_pos[si] - pos_b;
      s.range_a_m = da.norm();
      s.range_b_m = db.norm();
      s.los_nav = da / s.range_a_m;
      s.elevation_rad = std::asin(std::clamp(s.los_nav.z(), -1.0, 1.0));
      if (k > 0 && u01(rng) < p_slip) {
        amb_a[si] += (u01(rng) < 0.5 ? -1 : 1) * slip_dist(rng);
        s.slip_a = true;
      }
      if (k > 0 && u01(rng) < p_slip) {
        amb_b[si] += (u01(rng) < 0.5 ? -1 : 1) * slip_dist(rng);
        s.slip_b = true;
      }
      const double scale = 1.0 / std::max(std::sin(s.elevation_rad), 0.1);
      // Street canyon: walls block low satellites across the street.
      const bool blocked = ep.in_canyon && std::tan(s.elevation_rad) <
                                               c.canyon_height_to_halfwidth * std::fabs(std::cos(az_rad[si]));
      if (blocked) {
        was_blocked[si] = 1;
        mp_on[si] = 0;
        continue;
      }
      if (was_blocked[si] != 0) {
        // Re-acquired after a loss of lock: new integers, flagged by both receivers.
        amb_a[si] = amb_dist(rng);
        amb_b[si] = amb_dist(rng);
        s.slip_a = true;
        s.slip_b = true;
        was_blocked[si] = 0;
      }
      s.amb_a_cyc = amb_a[si];
      s.amb_b_cyc = amb_b[si];
      Eigen::Vector4d mp_m = Eigen::Vector4d::Zero();  // code A, code B, carrier A, carrier B [m]
      if (ep.in_canyon) {
        Eigen::Vector4d& m = mp[si];
        const Eigen::Vector4d w(n01(rng), n01(rng), n01(rng), n01(rng));
        m = mp_on[si] != 0 ? Eigen::Vector4d(mp_phi * m + mp_drive * w) : w;  // stationary start
        mp_on[si] = 1;
        const double quarter = 0.25 * c.lambda_m;
        mp_m << c.multipath_code_m * scale * m(0), c.multipath_code_m * scale * m(1),
            std::clamp(c.multipath_phase_m * scale * m(2), -quarter, quarter),
            std::clamp(c.multipath_phase_m * scale * m(3), -quarter, quarter);
      } else {
        mp_on[si] = 0;
      }
      s.code_a_m = s.range_a_m + clk_a + c.sigma_code_m * scale * n01(rng) + mp_m(0);
      s.code_b_m = s.range_b_m + clk_b + c.sigma_code_m * scale * n01(rng) + mp_m(1);
      s.carrier_a_cyc = (s.range_a_m + clk_a + c.sigma_phase_m * scale * n01(rng) + mp_m(2)) / c.lambda_m +
                        static_cast<double>(s.amb_a_cyc);
      s.carrier_b_cyc = (s.range_b_m + clk_b + c.sigma_phase_m * scale * n01(rng) + mp_m(3)) / c.lambda_m +
                        static_cast<double>(s.amb_b_cyc);
      ep.sats.push_back(s);
    }
    out.push_back(std::move(ep));
  }
  return out;
}

RtkEpoch to_rtk_epoch(const GnssRawEpoch& epoch, bool with_uwb) {
  RtkEpoch r;
  r.n_sats = static_cast<int>(std::min<size_t>(epoch.sats.size(), kRtkMaxSats));
  for (int i = 0; i < r.n_sats; ++i) {
    const GnssRawSat& s = epoch.sats[static_cast<size_t>(i)];
    RtkSatObs& o = r.sats[i];
    o.sat_id = s.sat_id;
    o.los_nav = s.los_nav;
    o.code_sd_m = s.code_b_m - s.code_a_m;
    o.carrier_sd_cyc = s.carrier_b_cyc - s.carrier_a_cyc;
    o.slip = s.slip_a || s.slip_b;
  }
  r.has_uwb = with_uwb;
  r.uwb_range_m = epoch.uwb_range_m;
  return r;
}

bool truth_dd_ambiguity(const GnssRawEpoch& epoch, uint16_t sat_id, uint16_t ref_id, int64_t& dd_cyc) {
  const GnssRawSat* sj = nullptr;
  const GnssRawSat* sr = nullptr;
  for (const GnssRawSat& s : epoch.sats) {
    if (s.sat_id == sat_id) sj = &s;
    if (s.sat_id == ref_id) sr = &s;
  }
  dd_cyc = 0;
  if (sj == nullptr || sr == nullptr) return false;
  dd_cyc = (sj->amb_b_cyc - sj->amb_a_cyc) - (sr->amb_b_cyc - sr->amb_a_cyc);
  return true;
}

}  // namespace uwbnav::sim
