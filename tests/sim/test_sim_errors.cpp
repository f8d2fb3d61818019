// Simulator error models beyond the seed 000 set: survey errors, range offsets
// and scale errors, random NLOS episodes, burst loss, anchor blockages,
// quantisation, range schedules (per anchor, frame), IMU grades and vibration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {
namespace {

SimOutput run_text(const std::string& text, uint64_t seed = 5, bool ideal_imu = false) {
  Scenario sc;
  std::string err;
  EXPECT_EQ(parse_scenario(text, "test", sc, &err), Status::kOk) << err;
  SimOutput out;
  SimOptions opt;
  opt.seed = seed;
  opt.ideal_imu = ideal_imu;
  EXPECT_EQ(simulate_scenario(sc, opt, out, &err), Status::kOk) << err;
  return out;
}

// LOS parking drive without noise, loss or NLOS: every deviation of a range from
// the true distance comes from the error model under test.
const char* const kClean = R"(base = parking_los
[uwb]
sigma_m = 0
packet_loss = 0
)";

double residual(const SimOutput& out, size_t i) {
  return static_cast<double>(out.rec.uwb[i].range.range_m) - out.range_truth[i].true_range_m;
}

TEST(SimErrors, SurveyErrorAppearsInAnchorsCsvButNotInRanges) {
  const SimOutput out = run_text(std::string(kClean) + "[site]\nsurvey_sigma_m = 0.15\n");
  ASSERT_EQ(out.rec.site.num_anchors, 4U);
  double sum_sq = 0.0;
  for (size_t a = 0; a < 4; ++a) {
    const AnchorDef& truth = out.scenario.anchors[a];
    const Anchor& site = out.rec.site.anchors[a];
    const double d[3] = {static_cast<double>(site.pos_nav_m.x) - truth.pos_nav_m[0],
                         static_cast<double>(site.pos_nav_m.y) - truth.pos_nav_m[1],
                         static_cast<double>(site.pos_nav_m.z) - truth.pos_nav_m[2]};
    for (double x : d) {
      EXPECT_LT(std::fabs(x), 0.75);  // 5 sigma
      sum_sq += x * x;
    }
    // The truth is a simulator fact in meta.ini, never in anchors.csv.
    const auto it = out.rec.meta.find("sim_anchor_true_" + std::to_string(truth.id));
    ASSERT_NE(it, out.rec.meta.end());
    double x = 0, y = 0, z = 0;
    ASSERT_EQ(std::sscanf(it->second.c_str(), "%lf %lf %lf", &x, &y, &z), 3);
    EXPECT_NEAR(x, truth.pos_nav_m[0], 1e-6);
    EXPECT_NEAR(y, truth.pos_nav_m[1], 1e-6);
    EXPECT_NEAR(z, truth.pos_nav_m[2], 1e-6);
  }
  EXPECT_GT(sum_sq, 1e-4) << "anchors.csv equals the truth";
  // Ranges are measured from the true positions.
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) EXPECT_NEAR(residual(out, i), 0.0, 2e-5);
}

TEST(SimErrors, ScaleErrorGrowsLinearlyWithRange) {
  const SimOutput out = run_text(std::string(kClean) + "[uwb]\nscale_common_pct = 0.3\n");
  // Least-squares line residual = b + s * true_range.
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    const double x = out.range_truth[i].true_range_m;
    const double y = residual(out, i);
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double intercept = (sy - slope * sx) / n;
  EXPECT_NEAR(slope, 0.003, 1e-5);
  EXPECT_NEAR(intercept, 0.0, 1e-3);
}

TEST(SimErrors, ExplicitOffsetsAddPerAnchorPerTagAndPerPair) {
  const SimOutput out = run_text(std::string(kClean) +
                                 "[uwb]\nanchor_offset = 1 0.10\ntag_offset = 0 0.05\npair_offset = 2 0 -0.20\n");
  const std::map<uint16_t, double> expected = {{1, 0.15}, {2, -0.15}, {3, 0.05}, {4, 0.05}};
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    EXPECT_NEAR(residual(out, i), expected.at(out.rec.uwb[i].range.anchor_id), 2e-5);
  }
  EXPECT_EQ(out.rec.meta.at("sim_range_offset_m_1_0"), "0.15");
}

TEST(SimErrors, DrawnOffsetsAreConstantPerPairAndDifferBetweenPairs) {
  const SimOutput out = run_text(std::string(kClean) + "[uwb]\nanchor_offset_sigma_m = 0.1\n");
  std::map<uint16_t, std::pair<double, double>> range_of;  // min, max residual per anchor
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    auto it = range_of.emplace(out.rec.uwb[i].range.anchor_id, std::make_pair(1e9, -1e9)).first;
    it->second.first = std::min(it->second.first, residual(out, i));
    it->second.second = std::max(it->second.second, residual(out, i));
  }
  std::set<long> distinct;
  for (const auto& kv : range_of) {
    EXPECT_LT(kv.second.second - kv.second.first, 5e-5) << "anchor " << kv.first;
    distinct.insert(std::lround(kv.second.first * 1e4));
  }
  EXPECT_EQ(distinct.size(), 4U);
}

TEST(SimErrors, RandomNlosEpisodesReachTheTargetShareWithPositiveBiases) {
  for (const char* law : {"exponential", "lognormal"}) {
    const SimOutput out = run_text(std::string(kClean) + "[scenario]\nduration_s = 1200\n[nlos]\nepisode_share = 0.3\n"
                                   "episode_mean_s = 2\nepisode_bias_mean_m = 0.6\nepisode_extra_sigma_m = 0\n"
                                   "episode_length_law = " + law + "\n");
    size_t nlos = 0;
    double bias_sum = 0.0;
    for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
      if (out.rec.uwb[i].nlos_label != 1) {
        EXPECT_NEAR(residual(out, i), 0.0, 2e-5);
        continue;
      }
      ++nlos;
      EXPECT_EQ(out.range_truth[i].cause, RangeCause::kEpisode);
      EXPECT_GT(residual(out, i), 0.0);
      bias_sum += residual(out, i);
    }
    const double share = static_cast<double>(nlos) / static_cast<double>(out.rec.uwb.size());
    EXPECT_NEAR(share, 0.3, 0.05) << law;
    EXPECT_NEAR(bias_sum / static_cast<double>(nlos), 0.6, 0.15) << law;
  }
}

TEST(SimErrors, BurstLossHasTheConfiguredShareAndMeanBurstLength) {
  // 50 Hz round-robin over 4 anchors: each pair owns every 4th slot.
  const SimOutput out =
      run_text(std::string(kClean) + "[scenario]\nduration_s = 1200\n[uwb]\nburst_loss = 0.2\nburst_mean_len = 5\n");
  const double period_us = 20000.0;
  const double offset_us = 3000.0;
  std::map<uint16_t, std::vector<bool>> present;  // per anchor, slots of that pair
  const size_t n_slots = static_cast<size_t>(1200.0 * 1e6 / period_us);
  for (uint16_t id = 1; id <= 4; ++id) present[id].assign(n_slots / 4, false);
  for (const auto& row : out.rec.uwb) {
    const size_t k = static_cast<size_t>(std::llround((static_cast<double>(row.range.t_us) - offset_us) / period_us));
    if (k / 4 < n_slots / 4) present[row.range.anchor_id][k / 4] = true;
  }
  size_t lost = 0, total = 0, bursts = 0;
  for (const auto& kv : present) {
    for (size_t i = 0; i < kv.second.size(); ++i) {
      ++total;
      if (kv.second[i]) continue;
      ++lost;
      if (i == 0 || kv.second[i - 1]) ++bursts;
    }
  }
  EXPECT_NEAR(static_cast<double>(lost) / static_cast<double>(total), 0.2, 0.03);
  EXPECT_NEAR(static_cast<double>(lost) / static_cast<double>(bursts), 5.0, 0.75);
}

TEST(SimErrors, BlockageScheduleNeverSilencesMoreThanKAnchors) {
  const SimOutput out = run_text(std::string(kClean) +
                                 "[scenario]\nduration_s = 900\n[uwb]\nblock_anchors = 2\nblock_min_s = 5\n"
                                 "block_max_s = 20\nblock_gap_min_s = 2\nblock_gap_max_s = 10\n");
  ASSERT_GE(out.blockages.size(), 20U);
  for (const Blockage& b : out.blockages) {
    EXPECT_EQ(b.anchor_ids.size(), 2U);
    EXPECT_NE(b.anchor_ids[0], b.anchor_ids[1]);
    EXPECT_GE(b.end_s - b.start_s, 5.0);
    EXPECT_LE(b.end_s - b.start_s, 20.0);
  }
  // Per whole second: anchors that produced no range (each anchor has 12-13 slots a second).
  std::vector<std::set<uint16_t>> heard(900);
  for (const auto& row : out.rec.uwb) heard[row.range.t_us / 1000000].insert(row.range.anchor_id);
  size_t seconds_with_two_silent = 0;
  for (const auto& s : heard) {
    EXPECT_GE(s.size(), 2U);
    if (s.size() == 2) ++seconds_with_two_silent;
  }
  EXPECT_GT(seconds_with_two_silent, 300U);
  // No range of a blocked anchor inside its blockage.
  for (const auto& row : out.rec.uwb) {
    const double t = static_cast<double>(row.range.t_us) * 1e-6;
    for (const Blockage& b : out.blockages) {
      if (t < b.start_s || t >= b.end_s) continue;
      for (uint16_t id : b.anchor_ids) EXPECT_NE(row.range.anchor_id, id);
    }
  }
}

TEST(SimErrors, RangesAreQuantisedToTheLsb) {
  const SimOutput out = run_text("base = parking_los\n[uwb]\nrange_lsb_m = 0.01\n");
  for (const auto& row : out.rec.uwb) {
    const double steps = static_cast<double>(row.range.range_m) / 0.01;
    EXPECT_NEAR(steps, std::round(steps), 1e-3);
  }
}

TEST(SimErrors, FrameModeStampsEveryTagAndAnchorAtTheSameInstant) {
  const SimOutput out = run_text(R"(base = parking_los
[scenario]
duration_s = 20
[site]
tag = 1 0.5 0.3 1.7
tag = 2 0.2 0 1.7
[uwb]
schedule = frame
rate_hz = 100
packet_loss = 0
)");
  std::map<uint64_t, std::set<std::pair<uint16_t, uint8_t>>> frames;
  for (const auto& row : out.rec.uwb) frames[row.range.t_us].insert({row.range.anchor_id, row.range.tag_id});
  ASSERT_EQ(frames.size(), 2000U);
  uint64_t prev = 0;
  bool first = true;
  for (const auto& kv : frames) {
    EXPECT_EQ(kv.second.size(), 12U);  // 4 anchors x 3 tags
    if (!first) {
      EXPECT_EQ(kv.first - prev, 10000U);
    }
    prev = kv.first;
    first = false;
  }
}

TEST(SimErrors, PerAnchorScheduleGivesEachAnchorTheConfiguredRate) {
  const SimOutput out = run_text("base = parking_los\n[scenario]\nduration_s = 60\n[uwb]\nschedule = per_anchor\n"
                                 "rate_hz = 25\npacket_loss = 0\n");
  std::map<uint16_t, size_t> count;
  for (const auto& row : out.rec.uwb) ++count[row.range.anchor_id];
  ASSERT_EQ(count.size(), 4U);
  for (const auto& kv : count) EXPECT_NEAR(static_cast<double>(kv.second), 25.0 * 60.0, 1.0);
  for (size_t i = 1; i < out.rec.uwb.size(); ++i) {
    const uint64_t dt = out.rec.uwb[i].range.t_us - out.rec.uwb[i - 1].range.t_us;
    EXPECT_GE(dt, 10000U);
    EXPECT_LE(dt, 10001U);
  }
}

TEST(SimErrors, ImuGradeSetsTheFiguresAndLaterKeysOverrideThem) {
  Scenario sc;
  std::string err;
  ASSERT_EQ(parse_scenario("base = parking_los\n[imu]\ngrade = consumer\naccel_bias_sigma_mg = 33\n", "t", sc, &err),
            Status::kOk)
      << err;
  EXPECT_EQ(sc.imu.accel_noise_ug_per_sqrt_hz, 350.0);
  EXPECT_EQ(sc.imu.gyro_bias_sigma_dps, 1.5);
  EXPECT_EQ(sc.imu.accel_bias_sigma_mg, 33.0);
  ASSERT_EQ(parse_scenario("base = parking_los\n[imu]\ngrade = automotive\n", "t", sc, &err), Status::kOk) << err;
  EXPECT_EQ(sc.imu.accel_noise_ug_per_sqrt_hz, 50.0);
  EXPECT_EQ(sc.imu.gyro_arw_dps_per_sqrt_h, 0.05);
  ASSERT_EQ(parse_scenario("base = parking_los\n[imu]\ngrade = mems\n", "t", sc, &err), Status::kOk) << err;
  EXPECT_EQ(sc.imu.accel_noise_ug_per_sqrt_hz, ImuConfig{}.accel_noise_ug_per_sqrt_hz);
  EXPECT_NE(parse_scenario("base = parking_los\n[imu]\ngrade = navigation\n", "t", sc, &err), Status::kOk);
  EXPECT_NE(err.find("unknown IMU grade"), std::string::npos) << err;
}

// Parked vehicle, noise-free IMU apart from vibration: the accelerometer x axis is pure vibration.
std::vector<double> parked_accel_x(const std::string& vib) {
  const SimOutput out = run_text("base = parking_los\n[scenario]\nduration_s = 60\n[route]\n[imu]\n"
                                 "gyro_bias_sigma_dps = 0\ngyro_arw_dps_per_sqrt_h = 0\ngyro_bias_rw_dps_per_sqrt_s = 0\n"
                                 "accel_bias_sigma_mg = 0\naccel_noise_ug_per_sqrt_hz = 0\n"
                                 "accel_bias_rw_mps2_per_sqrt_s = 0\n" + vib);
  std::vector<double> x;
  for (size_t k = 0; k < 1000; ++k) x.push_back(static_cast<double>(out.rec.imu[k].accel_body_mps2.x));
  return x;
}

double autocorr(const std::vector<double>& x, size_t lag) {
  double num = 0, den = 0;
  for (size_t i = 0; i < x.size(); ++i) den += x[i] * x[i];
  for (size_t i = 0; i + lag < x.size(); ++i) num += x[i] * x[i + lag];
  return num / den;
}

double rms(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s / static_cast<double>(x.size()));
}

TEST(SimErrors, VibrationAddsTheConfiguredRmsWhiteOrBandLimited) {
  // The parking_los route starts parked for 12 s: the first 1000 samples are at rest.
  const std::vector<double> white = parked_accel_x("vibration_accel_mps2 = 0.5\n");
  EXPECT_NEAR(rms(white), 0.5, 0.05);
  EXPECT_LT(std::fabs(autocorr(white, 1)), 0.1);
  // 25 Hz at 100 Hz sampling: a quarter period per sample, half a period per two.
  const std::vector<double> tone = parked_accel_x("vibration_accel_mps2 = 0.5\nvibration_hz = 25\nvibration_bandwidth_hz = 2\n");
  EXPECT_NEAR(rms(tone), 0.5, 0.12);
  EXPECT_LT(autocorr(tone, 2), -0.6);
}

TEST(SimErrors, NewKeysRejectBadValuesWithOneLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"[uwb]\nschedule = burst\n", "expected one of round_robin, per_anchor, frame"},
      {"[uwb]\nanchor_offset = 9 0.1\n", "unknown anchor 9"},
      {"[uwb]\npair_offset = 1 7 0.1\n", "unknown anchor 1 or tag 7"},
      {"[uwb]\nblock_anchors = 5\n", "block_anchors exceeds"},
      {"[uwb]\nburst_loss = 0.99\n", "burst_loss: value 0.99 outside"},
      {"[nlos]\nepisode_length_law = gamma\n", "expected one of exponential, lognormal"},
      {"[route]\nmaneuver = goto 1 2 3 4\n", "need route.kind = multicopter"},
      {"[route]\nkind = multicopter\nmaneuver = speed 3 3\n", "takes hold, goto and eight"},
      {"[route]\nkind = multicopter\nmaneuver = eight 1 1 0 1.5 10\n", "whole number of loops"},
      {"[imu]\nvibration_hz = 60\n", "below the Nyquist"},
  };
  for (const auto& c : cases) {
    Scenario sc;
    std::string err;
    const std::string text = "base = parking_los\n" + c.first;
    EXPECT_NE(parse_scenario(text, "bad.ini", sc, &err), Status::kOk) << c.first;
    EXPECT_NE(err.find(c.second), std::string::npos) << c.first << " -> " << err;
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace uwbnav::sim
