// Simulator GNSS receiver and UWB coverage limit: switching GNSS on changes no
// other stream; open-sky errors have the configured statistics; blocked and
// multipath windows, latency, lever arm; ranges beyond max_range_m vanish alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {
namespace {

Scenario load(const std::string& text) {
  Scenario sc;
  std::string err;
  EXPECT_EQ(parse_scenario(text, "test", sc, &err), Status::kOk) << err;
  return sc;
}

SimOutput run(const Scenario& sc, uint64_t seed) {
  SimOptions opt;
  opt.seed = seed;
  SimOutput out;
  std::string err;
  EXPECT_EQ(simulate_scenario(sc, opt, out, &err), Status::kOk) << err;
  return out;
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Antenna position from the recorded truth (body origin, attitude) at t_us,
// an IMU instant: truth + R(q) lever.
Eigen::Vector3d antenna_from_truth(const SimOutput& out, uint64_t t_us, const double lever_body_m[3]) {
  const size_t k = static_cast<size_t>(t_us / 10000U);
  EXPECT_LT(k, out.truth.size());
  const TruthState& ts = out.truth[k];
  EXPECT_EQ(ts.t_us, t_us);
  const Eigen::Quaterniond q(ts.q_nav_body[0], ts.q_nav_body[1], ts.q_nav_body[2], ts.q_nav_body[3]);
  return Eigen::Vector3d(ts.pos_nav_m[0], ts.pos_nav_m[1], ts.pos_nav_m[2]) +
         q.toRotationMatrix() * Eigen::Vector3d(lever_body_m[0], lever_body_m[1], lever_body_m[2]);
}

constexpr const char* kGnssOn =
    "[gnss]\nenabled = 1\nlever_m = 1.2 -0.3 1.6\nsigma_h_m = 0.8\nsigma_v_m = 1.5\ntau_s = 30\n"
    "sigma_white_m = 0.1\nclaim_ratio = 1.3\nvel_sigma_mps = 0.05\n";

TEST(SimGnss, EnablingGnssLeavesImuUwbAndTruthBitIdentical) {
  const Scenario off = load("base = parking_nlos\n");
  const Scenario on = load(std::string("base = parking_nlos\n") + kGnssOn + "blocked = 20 30\nmultipath = 40 60\n");
  const SimOutput a = run(off, 5);
  const SimOutput b = run(on, 5);
  EXPECT_TRUE(a.rec.gnss.empty());
  EXPECT_GT(b.rec.gnss.size(), 800U);
  ASSERT_EQ(a.rec.imu.size(), b.rec.imu.size());
  ASSERT_EQ(a.rec.uwb.size(), b.rec.uwb.size());
  ASSERT_EQ(a.rec.truth.size(), b.rec.truth.size());
  for (size_t i = 0; i < a.rec.imu.size(); ++i) {
    ASSERT_EQ(a.rec.imu[i].t_us, b.rec.imu[i].t_us);
    ASSERT_TRUE(same_bits(a.rec.imu[i].accel_body_mps2.x, b.rec.imu[i].accel_body_mps2.x) &&
                same_bits(a.rec.imu[i].accel_body_mps2.z, b.rec.imu[i].accel_body_mps2.z) &&
                same_bits(a.rec.imu[i].gyro_body_radps.z, b.rec.imu[i].gyro_body_radps.z))
        << "imu " << i;
  }
  for (size_t i = 0; i < a.rec.uwb.size(); ++i) {
    ASSERT_EQ(a.rec.uwb[i].range.t_us, b.rec.uwb[i].range.t_us);
    ASSERT_EQ(a.rec.uwb[i].range.anchor_id, b.rec.uwb[i].range.anchor_id);
    ASSERT_EQ(a.rec.uwb[i].nlos_label, b.rec.uwb[i].nlos_label);
    ASSERT_TRUE(same_bits(a.rec.uwb[i].range.range_m, b.rec.uwb[i].range.range_m) &&
                same_bits(a.rec.uwb[i].range.rx_power_dbm, b.rec.uwb[i].range.rx_power_dbm))
        << "uwb " << i;
  }
  for (size_t i = 0; i < a.rec.truth.size(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(a.rec.truth[i].pos_nav_m[k], b.rec.truth[i].pos_nav_m[k]) << i;
    for (int k = 0; k < 4; ++k) ASSERT_EQ(a.rec.truth[i].q_nav_body[k], b.rec.truth[i].q_nav_body[k]) << i;
  }
  // Off: nothing of GNSS in the recording; on: the lever as site configuration.
  for (const auto& kv : a.rec.meta) EXPECT_EQ(kv.first.find("gnss"), std::string::npos) << kv.first;
  EXPECT_EQ(a.rec.site.gnss_lever_body_m.x, 0.0F);
  EXPECT_EQ(b.rec.site.gnss_lever_body_m.x, 1.2F);
  EXPECT_EQ(b.rec.site.gnss_lever_body_m.y, -0.3F);
  EXPECT_EQ(b.rec.site.gnss_lever_body_m.z, 1.6F);
  EXPECT_EQ(b.rec.meta.at("gnss_lever_m"), "1.2,-0.3,1.6");
  EXPECT_EQ(b.rec.meta.at("sim_gnss_windows_s"), "[20,30):blocked [40,60):multipath");
}

// An hour of open sky while the car drives its loops with a 2 m lever arm: the
// fix minus the antenna truth (recomputed here from truth.csv) has the
// configured stationary RMS per axis, the claimed sigma is that times
// claim_ratio, and the velocity error is the white noise only (so the
// lever-arm term w x l is in the simulated antenna velocity).
TEST(SimGnss, OpenSkyErrorsHaveTheConfiguredRmsAndClaimsAndTheLeverArmIsApplied) {
  const Scenario sc = load(std::string("base = parking_los\n[scenario]\nduration_s = 3600\n[uwb]\nrate_hz = 1\n") +
                           kGnssOn);
  const SimOutput out = run(sc, 17);
  const GnssConfig& g = out.scenario.gnss;
  ASSERT_EQ(out.rec.gnss.size(), out.gnss_truth.size());
  ASSERT_GT(out.rec.gnss.size(), 17900U);
  double sq[3] = {0, 0, 0};
  double vel_sq[3] = {0, 0, 0};
  double turn_lever_mps = 0.0;  // largest |w x l| met, to show the term mattered
  for (size_t i = 0; i < out.rec.gnss.size(); ++i) {
    const GnssFix& f = out.rec.gnss[i];
    ASSERT_EQ(f.fix, GnssFixType::kDgnss);
    const Eigen::Vector3d antenna = antenna_from_truth(out, f.t_us, g.lever_body_m);
    const Eigen::Vector3d pos(f.pos_nav_m.x, f.pos_nav_m.y, f.pos_nav_m.z);
    for (int k = 0; k < 3; ++k) sq[k] += (pos[k] - antenna[k]) * (pos[k] - antenna[k]);
    const TruthState& ts = out.truth[f.t_us / 10000U];
    const Eigen::Quaterniond q(ts.q_nav_body[0], ts.q_nav_body[1], ts.q_nav_body[2], ts.q_nav_body[3]);
    const Eigen::Vector3d lever(g.lever_body_m[0], g.lever_body_m[1], g.lever_body_m[2]);
    const Eigen::Vector3d w(ts.gyro_body_radps[0], ts.gyro_body_radps[1], ts.gyro_body_radps[2]);
    const Eigen::Vector3d lever_vel = q.toRotationMatrix() * w.cross(lever);
    turn_lever_mps = std::max(turn_lever_mps, lever_vel.norm());
    const Eigen::Vector3d vel_true =
        Eigen::Vector3d(ts.vel_nav_mps[0], ts.vel_nav_mps[1], ts.vel_nav_mps[2]) + lever_vel;
    const Eigen::Vector3d vel(f.vel_nav_mps.x, f.vel_nav_mps.y, f.vel_nav_mps.z);
    for (int k = 0; k < 3; ++k) vel_sq[k] += (vel[k] - vel_true[k]) * (vel[k] - vel_true[k]);
  }
  const double n = static_cast<double>(out.rec.gnss.size());
  const double want[3] = {std::hypot(g.sigma_h_m, g.sigma_white_m), std::hypot(g.sigma_h_m, g.sigma_white_m),
                          std::hypot(g.sigma_v_m, g.sigma_white_m)};
  for (int k = 0; k < 3; ++k) {
    const double rms = std::sqrt(sq[k] / n);
    EXPECT_NEAR(rms / want[k], 1.0, 0.3) << "axis " << k << ": rms " << rms << " m, configured " << want[k] << " m";
    EXPECT_NEAR(std::sqrt(vel_sq[k] / n) / g.vel_sigma_mps, 1.0, 0.1) << "velocity axis " << k;
  }
  EXPECT_GT(turn_lever_mps, 0.3) << "the loops' turns must exercise the lever-arm velocity";
  const GnssFix& f = out.rec.gnss.front();
  EXPECT_FLOAT_EQ(f.pos_sigma_m.x, static_cast<float>(want[0] * g.claim_ratio));
  EXPECT_FLOAT_EQ(f.pos_sigma_m.y, static_cast<float>(want[1] * g.claim_ratio));
  EXPECT_FLOAT_EQ(f.pos_sigma_m.z, static_cast<float>(want[2] * g.claim_ratio));
  EXPECT_FLOAT_EQ(f.vel_sigma_mps, static_cast<float>(g.vel_sigma_mps * g.claim_ratio));
  EXPECT_GE(f.num_sv, 11);
  EXPECT_LE(f.num_sv, 13);
}

TEST(SimGnss, NoFixInsideBlockedWindowsAndMultipathFixesAreSingleWithLargeErrorButSmallClaims) {
  const Scenario sc = load(std::string("base = parking_los\n") + kGnssOn +
                           "blocked = 20 35\nmultipath = 60 90\nmultipath_bias_m = 6\nmultipath_claim_factor = 2\n");
  const SimOutput out = run(sc, 3);
  size_t before = 0;
  size_t after = 0;
  size_t multipath = 0;
  double mp_err_h = 0.0;
  float open_sigma = 0.0F;
  for (size_t i = 0; i < out.rec.gnss.size(); ++i) {
    const GnssFix& f = out.rec.gnss[i];
    const double t_s = static_cast<double>(f.t_us) * 1e-6;
    ASSERT_FALSE(t_s >= 20.0 && t_s < 35.0) << "fix at " << t_s << " s inside the blocked window";
    before += t_s >= 19.0 && t_s < 20.0 ? 1U : 0U;
    after += t_s >= 35.0 && t_s < 36.0 ? 1U : 0U;
    const bool in_mp = t_s >= 60.0 && t_s < 90.0;
    EXPECT_EQ(out.gnss_truth[i].multipath, in_mp) << t_s;
    if (!in_mp) {
      EXPECT_EQ(f.fix, GnssFixType::kDgnss) << t_s;
      open_sigma = f.pos_sigma_m.x;
      continue;
    }
    EXPECT_EQ(f.fix, GnssFixType::kSingle) << t_s;
    ++multipath;
    const Eigen::Vector3d antenna = antenna_from_truth(out, f.t_us, out.scenario.gnss.lever_body_m);
    mp_err_h += std::hypot(static_cast<double>(f.pos_nav_m.x) - antenna.x(),
                           static_cast<double>(f.pos_nav_m.y) - antenna.y());
  }
  EXPECT_EQ(before, 5U);
  EXPECT_EQ(after, 5U);
  ASSERT_EQ(multipath, 150U);
  mp_err_h /= static_cast<double>(multipath);
  EXPECT_GT(mp_err_h, 4.0) << "mean horizontal error in multipath";
  EXPECT_LT(mp_err_h, 8.5);
  for (size_t i = 0; i < out.rec.gnss.size(); ++i) {
    if (out.gnss_truth[i].multipath) {
      EXPECT_FLOAT_EQ(out.rec.gnss[i].pos_sigma_m.x, 2.0F * open_sigma);
      EXPECT_LT(out.rec.gnss[i].pos_sigma_m.x, 3.5F) << "the claim grows by 2 only, far below the 6 m bias";
      EXPECT_LE(out.rec.gnss[i].num_sv, 7);
    }
  }
}

TEST(SimGnss, LatencyStaysWithinItsBoundsAndFixesComeInArrivalOrderOnTheRateGrid) {
  const Scenario sc = load(std::string("base = parking_los\n") + kGnssOn +
                           "rate_hz = 10\nlatency_ms = 100\nlatency_jitter_ms = 30\n");
  const SimOutput out = run(sc, 9);
  ASSERT_GT(out.rec.gnss.size(), 1700U);
  uint64_t lo = UINT64_MAX;
  uint64_t hi = 0;
  const uint64_t dur_us = static_cast<uint64_t>(out.scenario.duration_s * 1e6);
  for (size_t i = 0; i < out.rec.gnss.size(); ++i) {
    const GnssFix& f = out.rec.gnss[i];
    EXPECT_EQ(f.t_us % 100000U, 0U);
    ASSERT_GE(f.rx_t_us, f.t_us);
    lo = std::min(lo, f.rx_t_us - f.t_us);
    hi = std::max(hi, f.rx_t_us - f.t_us);
    EXPECT_LT(f.rx_t_us, dur_us) << "a fix arriving after the end is not in the recording";
    if (i > 0) {
      ASSERT_GE(f.rx_t_us, out.rec.gnss[i - 1].rx_t_us) << i;
    }
  }
  EXPECT_GE(lo, 70000U);
  EXPECT_LE(hi, 130000U);
  EXPECT_LT(lo, 72000U) << "the jitter spans its range";
  EXPECT_GT(hi, 128000U);
}

TEST(SimGnss, GnssScenarioKeysParseAndInconsistentOnesAreRejected) {
  const Scenario sc = load(std::string("base = parking_los\n") + kGnssOn +
                           "num_sv = 9\nmultipath_turn_dps = 3\nblocked = 1 2\nmultipath = 3 4.5\n");
  const GnssConfig& g = sc.gnss;
  EXPECT_TRUE(g.enabled);
  EXPECT_NEAR(g.lever_body_m[0], 1.2, 1e-6);
  EXPECT_NEAR(g.lever_body_m[1], -0.3, 1e-6);
  EXPECT_NEAR(g.lever_body_m[2], 1.6, 1e-6);
  EXPECT_EQ(g.num_sv, 9U);
  EXPECT_EQ(g.multipath_turn_dps, 3.0);
  ASSERT_EQ(g.windows.size(), 2U);
  EXPECT_EQ(g.windows[0].kind, GnssWindowKind::kBlocked);
  EXPECT_EQ(g.windows[1].kind, GnssWindowKind::kMultipath);
  EXPECT_EQ(g.windows[1].end_s, 4.5);
  EXPECT_FALSE(Scenario{}.gnss.enabled) << "GNSS is off unless a scenario asks for it";
  for (const char* bad : {"[gnss]\nenabled = 1\nrate_hz = 3\n",            // 1e6 / 3 us is not whole
                          "[gnss]\nlatency_ms = 10\nlatency_jitter_ms = 20\nenabled = 1\n",
                          "[gnss]\nblocked = 5 5\n", "[gnss]\nmultipath = -1 3\n", "[gnss]\nlever_m = 1 2\n",
                          "[gnss]\nenabled = 1\nsigma_h_m = 0\nsigma_white_m = 0\n",  // a zero claimed sigma
                          "[gnss]\nclaim_ratio = 0\n", "[uwb]\nmax_range_m = -1\n"}) {
    Scenario s;
    std::string err;
    EXPECT_NE(parse_scenario(std::string("base = parking_los\n") + bad, "bad.ini", s, &err), Status::kOk) << bad;
    EXPECT_FALSE(err.empty()) << bad;
  }
}

TEST(SimGnss, UwbMaxRangeDropsOnlyTheRangesBeyondIt) {
  const SimOutput all = run(load("base = parking_nlos\n"), 4);
  const SimOutput near = run(load("base = parking_nlos\n[uwb]\nmax_range_m = 40\n"), 4);
  std::vector<size_t> kept;
  for (size_t i = 0; i < all.rec.uwb.size(); ++i) {
    if (all.range_truth[i].true_range_m <= 40.0) kept.push_back(i);
  }
  ASSERT_GT(kept.size(), near.rec.uwb.size() / 2);
  ASSERT_LT(kept.size(), all.rec.uwb.size()) << "the lot must have ranges beyond 40 m";
  ASSERT_EQ(near.rec.uwb.size(), kept.size());
  for (size_t j = 0; j < kept.size(); ++j) {
    const UwbRange& a = all.rec.uwb[kept[j]].range;
    const UwbRange& b = near.rec.uwb[j].range;
    ASSERT_EQ(a.t_us, b.t_us) << j;
    ASSERT_EQ(a.anchor_id, b.anchor_id) << j;
    ASSERT_TRUE(same_bits(a.range_m, b.range_m)) << "the ranges kept keep their values: " << j;
  }
  EXPECT_EQ(near.rec.meta.at("sim_uwb_max_range_m"), "40");
  EXPECT_EQ(all.rec.meta.count("sim_uwb_max_range_m"), 0U);
}

}  // namespace
}  // namespace uwbnav::sim
