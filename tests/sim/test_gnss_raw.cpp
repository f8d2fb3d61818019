// Tests of tools/sim/gnss_raw: raw code/carrier observations of two receivers
// and the inter-vehicle UWB range for estimator/rtk_baseline (seed 002).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tools/sim/gnss_raw.hpp"

namespace uwbnav::sim {
namespace {

TEST(SimGnssRaw, SameSeedSameDataOtherSeedOtherData) {
  GnssRawConfig c;
  c.seed = 42;
  c.slip_rate_hz = 0.01;
  const auto a = simulate_gnss_raw(c);
  const auto b = simulate_gnss_raw(c);
  c.seed = 43;
  const auto d = simulate_gnss_raw(c);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), 121u);
  bool differs = a.front().sats.size() != d.front().sats.size();
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].sats.size(), b[k].sats.size());
    EXPECT_EQ(a[k].uwb_range_m, b[k].uwb_range_m);
    EXPECT_EQ(a[k].baseline_nav_m, b[k].baseline_nav_m);
    for (size_t i = 0; i < a[k].sats.size(); ++i) {
      EXPECT_EQ(a[k].sats[i].code_a_m, b[k].sats[i].code_a_m);
      EXPECT_EQ(a[k].sats[i].carrier_b_cyc, b[k].sats[i].carrier_b_cyc);
      EXPECT_EQ(a[k].sats[i].slip_b, b[k].sats[i].slip_b);
    }
    if (!differs && k < d.size()) differs = a[k].uwb_range_m != d[k].uwb_range_m;
  }
  EXPECT_TRUE(differs);
}

TEST(SimGnssRaw, SkyAndBaselineWithinTheConfiguredRanges) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    GnssRawConfig c;
    c.seed = seed;
    const auto run = simulate_gnss_raw(c);
    const size_t n = run.front().sats.size();
    EXPECT_GE(n, 6u);
    EXPECT_LE(n, 10u);
    const double len0 = run.front().baseline_nav_m.head<2>().norm();
    EXPECT_GE(len0, 5.0 - 1e-9);
    EXPECT_LE(len0, 20.0 + 1e-9);
    for (const auto& s : run.front().sats) {
      EXPECT_GE(s.elevation_rad, 15.0 * M_PI / 180.0 - 1e-3);
      EXPECT_NEAR(s.los_nav.norm(), 1.0, 1e-12);
    }
  }
}

TEST(SimGnssRaw, DoubleDifferencesEqualGeometryPlusIntegerWavelengthsWithinNoise) {
  GnssRawConfig c;
  c.seed = 7;
  const auto run = simulate_gnss_raw(c);
  const double lam = c.lambda_m;
  double max_code = 0.0, max_phase = 0.0;
  for (const auto& ep : run) {
    const RtkEpoch e = to_rtk_epoch(ep, true);
    const int r = 0;
    for (int j = 1; j < e.n_sats; ++j) {
      // Geometry: -(e_j - e_r).b (planar, short baseline) plus the DD integer.
      const double geo = -(e.sats[j].los_nav - e.sats[r].los_nav).dot(ep.baseline_nav_m);
      int64_t n_dd = 0;
      ASSERT_TRUE(truth_dd_ambiguity(ep, e.sats[j].sat_id, e.sats[r].sat_id, n_dd));
      const double code_dd = e.sats[j].code_sd_m - e.sats[r].code_sd_m;
      const double phase_dd_m = lam * (e.sats[j].carrier_sd_cyc - e.sats[r].carrier_sd_cyc);
      max_code = std::max(max_code, std::fabs(code_dd - geo));
      max_phase = std::max(max_phase, std::fabs(phase_dd_m - geo - lam * static_cast<double>(n_dd)));
    }
    EXPECT_NEAR(e.uwb_range_m, ep.baseline_nav_m.norm(), 5.0 * c.sigma_uwb_m);
  }
  // 4 undifferenced noises of sigma / sin(15 deg): 5 sigma bounds.
  const double k = 5.0 * 2.0 / std::sin(15.0 * M_PI / 180.0);
  EXPECT_LT(max_code, k * c.sigma_code_m);
  EXPECT_LT(max_phase, k * c.sigma_phase_m);
  EXPECT_GT(max_phase, 0.0);
}

TEST(SimGnssRaw, NoiselessDoubleDifferencesAreExactAndClocksCancel) {
  GnssRawConfig c;
  c.seed = 3;
  c.sigma_code_m = 0.0;
  c.sigma_phase_m = 0.0;
  const auto run = simulate_gnss_raw(c);
  for (const auto& ep : run) {
    EXPECT_GT(std::fabs(ep.clock_a_m - ep.clock_b_m), 0.0);
    const RtkEpoch e = to_rtk_epoch(ep, false);
    for (int j = 1; j < e.n_sats; ++j) {
      const auto& sj = ep.sats[static_cast<size_t>(j)];
      const auto& sr = ep.sats[0];
      const double exact = (sj.range_b_m - sj.range_a_m) - (sr.range_b_m - sr.range_a_m);
      EXPECT_NEAR(e.sats[j].code_sd_m - e.sats[0].code_sd_m, exact, 1e-6);
      // Planar approximation error |b|^2 / (2 rho) ~ 1e-5 m.
      const double geo = -(e.sats[j].los_nav - e.sats[0].los_nav).dot(ep.baseline_nav_m);
      EXPECT_NEAR(exact, geo, 1e-4);
    }
  }
}

TEST(SimGnssRaw, SlipsChangeTheIntegerAndAreFlagged) {
  GnssRawConfig c;
  c.seed = 11;
  c.slip_rate_hz = 0.02;
  const auto run = simulate_gnss_raw(c);
  int slips = 0;
  for (size_t k = 1; k < run.size(); ++k) {
    for (size_t i = 0; i < run[k].sats.size(); ++i) {
      const auto& s = run[k].sats[i];
      const auto& p = run[k - 1].sats[i];
      EXPECT_EQ(s.slip_a, s.amb_a_cyc != p.amb_a_cyc);
      EXPECT_EQ(s.slip_b, s.amb_b_cyc != p.amb_b_cyc);
      slips += s.slip_a + s.slip_b;
    }
  }
  EXPECT_GT(slips, 5);
  c.slip_rate_hz = 0.0;
  for (const auto& ep : simulate_gnss_raw(c)) {
    for (const auto& s : ep.sats) EXPECT_FALSE(s.slip_a || s.slip_b);
  }
}

// |cos(az)| of a line of sight, az from the across-street axis y.
double across_street(const Eigen::Vector3d& los) { return std::fabs(los.y()) / los.head<2>().norm(); }

TEST(SimGnssRaw, CanyonWallsBlockSatellitesAcrossTheStreetOnly) {
  int blocked_total = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    GnssRawConfig c;
    c.seed = seed;
    c.canyon_start_s = 30.0;
    c.canyon_end_s = 60.0;
    c.canyon_height_to_halfwidth = 1.0;
    const auto run = simulate_gnss_raw(c);
    const size_t n_open = run.front().sats.size();
    for (const auto& ep : run) {
      EXPECT_EQ(ep.in_canyon, ep.t_s >= 30.0 && ep.t_s < 60.0);
      EXPECT_EQ(ep.sats_in_sky, static_cast<int>(n_open));
      if (!ep.in_canyon) {
        EXPECT_EQ(ep.sats.size(), n_open) << "open sky: every satellite tracked";
        continue;
      }
      for (const auto& s : ep.sats) {
        EXPECT_GE(std::tan(s.elevation_rad), across_street(s.los_nav) - 1e-9) << "a tracked satellite clears the wall";
      }
      // Every open-sky satellite missing in the canyon is below the roof line.
      for (const auto& s0 : run.front().sats) {
        bool tracked = false;
        for (const auto& s : ep.sats) tracked = tracked || s.sat_id == s0.sat_id;
        if (!tracked) {
          ++blocked_total;
          EXPECT_LT(std::tan(s0.elevation_rad), across_street(s0.los_nav) + 1e-9);
        }
      }
    }
  }
  EXPECT_GT(blocked_total, 0);
}

TEST(SimGnssRaw, SatellitesReacquiredAfterTheCanyonHaveNewIntegersAndAreFlagged) {
  int reacquired = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    GnssRawConfig c;
    c.seed = seed;
    c.canyon_start_s = 30.0;
    c.canyon_end_s = 60.0;
    c.canyon_height_to_halfwidth = 1.5;
    const auto run = simulate_gnss_raw(c);
    const auto& before = run[29];
    const auto& after = run[60];
    ASSERT_FALSE(after.in_canyon);
    for (const auto& s : after.sats) {
      bool in_canyon = false;
      for (const auto& t : run[59].sats) in_canyon = in_canyon || t.sat_id == s.sat_id;
      const GnssRawSat* p = nullptr;
      for (const auto& t : before.sats) {
        if (t.sat_id == s.sat_id) p = &t;
      }
      ASSERT_NE(p, nullptr);
      if (in_canyon) {
        EXPECT_FALSE(s.slip_a || s.slip_b);
        continue;
      }
      ++reacquired;
      EXPECT_TRUE(s.slip_a && s.slip_b) << "loss of lock is flagged by both receivers";
      EXPECT_TRUE(s.amb_a_cyc != p->amb_a_cyc || s.amb_b_cyc != p->amb_b_cyc);
    }
  }
  EXPECT_GT(reacquired, 5);
}

TEST(SimGnssRaw, MultipathOnlyInsideTheCanyonAndCarrierMultipathBelowAQuarterCycle) {
  GnssRawConfig c;
  c.seed = 9;
  c.sigma_code_m = 0.0;
  c.sigma_phase_m = 0.0;
  c.canyon_start_s = 30.0;
  c.canyon_end_s = 60.0;
  c.canyon_height_to_halfwidth = 0.0;  // multipath only, nothing blocked
  c.multipath_phase_m = 1.0;           // large: the quarter-cycle clip must act
  const auto run = simulate_gnss_raw(c);
  double max_code_open = 0.0, max_code_canyon = 0.0, max_phase_canyon = 0.0;
  for (const auto& ep : run) {
    for (const auto& s : ep.sats) {
      const double code_err = std::fabs(s.code_a_m - s.range_a_m - ep.clock_a_m);
      const double phase_err =
          std::fabs(c.lambda_m * (s.carrier_a_cyc - static_cast<double>(s.amb_a_cyc)) - s.range_a_m - ep.clock_a_m);
      if (ep.in_canyon) {
        max_code_canyon = std::max(max_code_canyon, code_err);
        max_phase_canyon = std::max(max_phase_canyon, phase_err);
      } else {
        max_code_open = std::max(max_code_open, code_err);
        EXPECT_LT(phase_err, 1e-3);
      }
    }
  }
  EXPECT_LT(max_code_open, 1e-3);
  EXPECT_GT(max_code_canyon, 0.5);
  EXPECT_LE(max_phase_canyon, 0.25 * c.lambda_m + 1e-3);
  EXPECT_GT(max_phase_canyon, 0.2 * c.lambda_m);
}

}  // namespace
}  // namespace uwbnav::sim
