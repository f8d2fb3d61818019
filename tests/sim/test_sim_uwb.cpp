// Simulator UWB model: determinism, round-robin timing, lever arm, outages,
// packet loss, geometric NLOS labels, outliers, channel diagnostics, seed 000 protocol.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {
namespace {

SimOutput run(const std::string& scenario, uint64_t seed = 11, bool ideal_uwb = false) {
  SimOptions opt;
  opt.seed = seed;
  opt.ideal_uwb = ideal_uwb;
  SimOutput out;
  std::string err;
  EXPECT_EQ(simulate(scenario, opt, out, &err), Status::kOk) << err;
  return out;
}

SimOutput run_text(const std::string& text, uint64_t seed = 5) {
  Scenario sc;
  std::string err;
  EXPECT_EQ(parse_scenario(text, "test", sc, &err), Status::kOk) << err;
  SimOutput out;
  SimOptions opt;
  opt.seed = seed;
  EXPECT_EQ(simulate_scenario(sc, opt, out, &err), Status::kOk) << err;
  return out;
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool identical(const dataset::Recording& a, const dataset::Recording& b) {
  if (a.imu.size() != b.imu.size() || a.uwb.size() != b.uwb.size() || a.truth.size() != b.truth.size()) return false;
  for (size_t i = 0; i < a.imu.size(); ++i) {
    const ImuSample& x = a.imu[i];
    const ImuSample& y = b.imu[i];
    if (x.t_us != y.t_us || !same_bits(x.accel_body_mps2.x, y.accel_body_mps2.x) ||
        !same_bits(x.accel_body_mps2.y, y.accel_body_mps2.y) || !same_bits(x.accel_body_mps2.z, y.accel_body_mps2.z) ||
        !same_bits(x.gyro_body_radps.x, y.gyro_body_radps.x) || !same_bits(x.gyro_body_radps.y, y.gyro_body_radps.y) ||
        !same_bits(x.gyro_body_radps.z, y.gyro_body_radps.z)) {
      return false;
    }
  }
  for (size_t i = 0; i < a.uwb.size(); ++i) {
    const UwbRange& x = a.uwb[i].range;
    const UwbRange& y = b.uwb[i].range;
    if (x.t_us != y.t_us || x.anchor_id != y.anchor_id || x.tag_id != y.tag_id || !same_bits(x.range_m, y.range_m) ||
        !same_bits(x.fp_power_dbm, y.fp_power_dbm) || !same_bits(x.rx_power_dbm, y.rx_power_dbm) ||
        a.uwb[i].nlos_label != b.uwb[i].nlos_label) {
      return false;
    }
  }
  for (size_t i = 0; i < a.truth.size(); ++i) {
    if (std::memcmp(a.truth[i].pos_nav_m, b.truth[i].pos_nav_m, sizeof a.truth[i].pos_nav_m) != 0 ||
        std::memcmp(a.truth[i].q_nav_body, b.truth[i].q_nav_body, sizeof a.truth[i].q_nav_body) != 0) {
      return false;
    }
  }
  return a.meta == b.meta;
}

TEST(SimUwb, SameSeedGivesBitIdenticalRecording) {
  dataset::Recording a;
  dataset::Recording b;
  std::string err;
  ASSERT_EQ(simulate("parking_nlos", 42, a, &err), Status::kOk) << err;
  ASSERT_EQ(simulate("parking_nlos", 42, b, &err), Status::kOk) << err;
  EXPECT_TRUE(identical(a, b));
}

TEST(SimUwb, DifferentSeedGivesDifferentNoise) {
  dataset::Recording a;
  dataset::Recording b;
  std::string err;
  ASSERT_EQ(simulate("parking_nlos", 1, a, &err), Status::kOk) << err;
  ASSERT_EQ(simulate("parking_nlos", 2, b, &err), Status::kOk) << err;
  EXPECT_FALSE(identical(a, b));
  // The truth is the scenario's, not the seed's.
  ASSERT_EQ(a.truth.size(), b.truth.size());
  EXPECT_EQ(std::memcmp(a.truth.back().pos_nav_m, b.truth.back().pos_nav_m, sizeof a.truth.back().pos_nav_m), 0);
}

TEST(SimUwb, RangesAreRoundRobinAt50HzStampedBetweenImuSamples) {
  // GIVEN an ideal radio (no loss) THEN slot k is at 3 ms + k * 20 ms and ranges anchor k mod 4
  const SimOutput out = run("parking_los", 3, true);
  ASSERT_EQ(out.rec.uwb.size(), 9000U);  // 180 s * 50 Hz
  for (size_t k = 0; k < out.rec.uwb.size(); ++k) {
    const UwbRange& r = out.rec.uwb[k].range;
    EXPECT_EQ(r.t_us, 3000U + 20000U * k);
    EXPECT_EQ(r.anchor_id, out.rec.site.anchors[k % 4].id);
    EXPECT_NE(r.t_us % 10000U, 0U);
  }
}

TEST(SimUwb, PacketLossDropsAboutTheConfiguredFractionAndKeepsTheSlotGrid) {
  const SimOutput out = run("parking_los", 9);
  const double kept = static_cast<double>(out.rec.uwb.size()) / 9000.0;
  EXPECT_NEAR(kept, 0.98, 0.006);
  for (const dataset::UwbRow& row : out.rec.uwb) {
    ASSERT_EQ((row.range.t_us - 3000U) % 20000U, 0U);
    const size_t k = (row.range.t_us - 3000U) / 20000U;
    EXPECT_EQ(row.range.anchor_id, out.rec.site.anchors[k % 4].id);
  }
}

TEST(SimUwb, IdealRangeIsTheDistanceFromTheLeverArmedTagToTheAnchor) {
  // During the parked start the truth is constant, so the tag antenna is truth pos + R * lever.
  const SimOutput out = run("parking_los", 3, true);
  const TruthState& t = out.truth.front();
  const Eigen::Quaterniond q(t.q_nav_body[0], t.q_nav_body[1], t.q_nav_body[2], t.q_nav_body[3]);
  const Tag& tag = out.rec.site.tags[0];
  const Eigen::Vector3d lever(static_cast<double>(tag.lever_body_m.x), static_cast<double>(tag.lever_body_m.y),
                              static_cast<double>(tag.lever_body_m.z));
  const Eigen::Vector3d antenna = Eigen::Vector3d(t.pos_nav_m[0], t.pos_nav_m[1], t.pos_nav_m[2]) + q * lever;
  EXPECT_NEAR(antenna.z(), 1.7, 1e-6);
  for (size_t k = 0; k < 100; ++k) {
    const UwbRange& r = out.rec.uwb[k].range;
    const Anchor& a = out.rec.site.anchors[out.rec.site.find_anchor(r.anchor_id)];
    const Eigen::Vector3d anchor(static_cast<double>(a.pos_nav_m.x), static_cast<double>(a.pos_nav_m.y),
                                 static_cast<double>(a.pos_nav_m.z));
    EXPECT_NEAR(static_cast<double>(r.range_m), (anchor - antenna).norm(), 1e-5);
    EXPECT_EQ(out.rec.uwb[k].nlos_label, 0);
  }
}

TEST(SimUwb, OutageWindowsContainNoRangesButTheirEdgesDo) {
  const SimOutput out = run("parking_outages");
  const double windows[3][2] = {{40, 45}, {80, 90}, {120, 135}};
  for (const auto& w : windows) {
    size_t before = 0;
    size_t after = 0;
    for (const dataset::UwbRow& row : out.rec.uwb) {
      const double t = static_cast<double>(row.range.t_us) * 1e-6;
      EXPECT_FALSE(t >= w[0] && t < w[1]) << "range at " << t << " inside outage [" << w[0] << "," << w[1] << ")";
      if (t >= w[0] - 0.5 && t < w[0]) ++before;
      if (t >= w[1] && t < w[1] + 0.5) ++after;
    }
    EXPECT_GT(before, 15U);
    EXPECT_GT(after, 15U);
  }
  EXPECT_NE(out.rec.meta.at("description").find("[80,90)"), std::string::npos);
}

// A parked vehicle at the origin heading +x, anchors ahead (1), behind (2), left (3), behind-high (4).
const char* const kParked = R"(
[scenario]
name = parked_geometry
duration_s = 20
[site]
anchor = 1 10 0 1.5
anchor = 2 -10 0 1.5
anchor = 3 0 10 1.5
anchor = 4 -10 -1 3.0
tag = 0 0.5 0 1.7
[uwb]
packet_loss = 0
[nlos]
outlier_prob = 0
)";

std::map<uint16_t, std::pair<size_t, double>> label_rate_and_mean_error(const SimOutput& out) {
  std::map<uint16_t, std::pair<size_t, double>> acc;  // anchor -> (labelled count, sum error)
  std::map<uint16_t, size_t> n;
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    const UwbRange& r = out.rec.uwb[i].range;
    acc[r.anchor_id].first += out.rec.uwb[i].nlos_label == 1 ? 1 : 0;
    acc[r.anchor_id].second += static_cast<double>(r.range_m) - out.range_truth[i].true_range_m;
    ++n[r.anchor_id];
  }
  for (auto& kv : acc) kv.second.second /= static_cast<double>(n[kv.first]);
  return acc;
}

TEST(SimUwb, RangeBlockedByABoxIsLabelledNlosAndBiasedPositive) {
  // GIVEN a van-sized box between the tag and anchor 1, body blocking off
  const SimOutput out = run_text(std::string(kParked) + "[nlos]\nbody_block = 0\nbox = 4 -1 0 5 1 2.5\n");
  const auto stats = label_rate_and_mean_error(out);
  const size_t per_anchor = out.rec.uwb.size() / 4;
  // THEN every range to anchor 1 is labelled, caused by the box, and positively biased
  EXPECT_EQ(stats.at(1).first, per_anchor);
  EXPECT_GT(stats.at(1).second, 0.3);
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    if (out.rec.uwb[i].range.anchor_id == 1) {
      EXPECT_EQ(out.range_truth[i].cause, RangeCause::kBox);
    }
  }
  // AND the unobstructed anchors are LOS with zero-mean error
  for (uint16_t id : {2, 3, 4}) {
    EXPECT_EQ(stats.at(id).first, 0U) << "anchor " << id;
    EXPECT_NEAR(stats.at(id).second, 0.0, 0.03) << "anchor " << id;
  }
}

TEST(SimUwb, VehicleBodyBlocksOnlyRearAnchorsLowerThanTheRoofTag) {
  const SimOutput out = run_text(std::string(kParked) + "[nlos]\nbody_block = 1\nbody_cone_deg = 30\n");
  const auto stats = label_rate_and_mean_error(out);
  const size_t per_anchor = out.rec.uwb.size() / 4;
  EXPECT_EQ(stats.at(2).first, per_anchor);  // behind and lower: blocked
  EXPECT_GT(stats.at(2).second, 0.2);
  EXPECT_EQ(stats.at(1).first, 0U);  // ahead
  EXPECT_EQ(stats.at(3).first, 0U);  // beside (90 deg off the rear axis)
  EXPECT_EQ(stats.at(4).first, 0U);  // behind but above the roof tag
}

TEST(SimUwb, DefaultScenarioHasGeometricNlosWithPositiveBiasesAndConsistentLabels) {
  const SimOutput out = run("parking_nlos");
  size_t nlos = 0;
  std::map<RangeCause, std::pair<size_t, double>> by_cause;
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    const RangeTruth& t = out.range_truth[i];
    EXPECT_EQ(out.rec.uwb[i].nlos_label, t.cause == RangeCause::kLos ? 0 : 1);
    nlos += out.rec.uwb[i].nlos_label == 1 ? 1 : 0;
    by_cause[t.cause].first += 1;
    by_cause[t.cause].second += static_cast<double>(out.rec.uwb[i].range.range_m) - t.true_range_m;
  }
  const double fraction = static_cast<double>(nlos) / static_cast<double>(out.rec.uwb.size());
  EXPECT_GT(fraction, 0.15);
  EXPECT_LT(fraction, 0.45);
  for (RangeCause c : {RangeCause::kBox, RangeCause::kBody, RangeCause::kOutlier}) {
    ASSERT_GT(by_cause[c].first, 10U) << static_cast<int>(c);
    EXPECT_GT(by_cause[c].second / static_cast<double>(by_cause[c].first), 0.3) << static_cast<int>(c);
  }
  EXPECT_NEAR(by_cause[RangeCause::kLos].second / static_cast<double>(by_cause[RangeCause::kLos].first), 0.0, 0.01);
}

TEST(SimUwb, GrossOutliersAreRareLargeAndMostlyPositive) {
  const SimOutput out = run("drive_1h", 4);
  size_t n_out = 0;
  size_t positive = 0;
  for (const RangeTruth& t : out.range_truth) {
    if (t.cause != RangeCause::kOutlier) continue;
    ++n_out;
    positive += t.bias_m > 0.0 ? 1 : 0;
  }
  const double rate = static_cast<double>(n_out) / static_cast<double>(out.range_truth.size());
  EXPECT_NEAR(rate, 0.005, 0.001);
  EXPECT_NEAR(static_cast<double>(positive) / static_cast<double>(n_out), 0.8, 0.06);
}

TEST(SimUwb, ChannelDiagnosticsSeparateLosFromNlosWithOverlap) {
  const SimOutput out = run("parking_nlos");
  double los_gap = 0.0;
  double nlos_gap = 0.0;
  size_t n_los = 0;
  size_t n_nlos = 0;
  size_t los_beyond_6db = 0;
  for (const dataset::UwbRow& row : out.rec.uwb) {
    ASSERT_TRUE(std::isfinite(row.range.fp_power_dbm));
    ASSERT_TRUE(std::isfinite(row.range.rx_power_dbm));
    const double diff = static_cast<double>(row.range.fp_power_dbm - row.range.rx_power_dbm);
    EXPECT_LE(diff, 0.0);
    EXPECT_LT(row.range.rx_power_dbm, -60.0F);
    EXPECT_GT(row.range.rx_power_dbm, -115.0F);
    if (row.nlos_label == 1) {
      nlos_gap += diff;
      ++n_nlos;
    } else {
      los_gap += diff;
      ++n_los;
      los_beyond_6db += diff < -6.0 ? 1 : 0;
    }
  }
  los_gap /= static_cast<double>(n_los);
  nlos_gap /= static_cast<double>(n_nlos);
  EXPECT_GT(los_gap, -4.0);
  EXPECT_LT(nlos_gap, -7.0);
  EXPECT_LT(static_cast<double>(los_beyond_6db) / static_cast<double>(n_los), 0.05);
}

TEST(SimUwb, ChannelDiagnosticsCanBeOmitted) {
  const SimOutput out = run("seed000_protocol");
  for (size_t i = 0; i < 100; ++i) {
    EXPECT_TRUE(std::isnan(out.rec.uwb[i].range.fp_power_dbm));
    EXPECT_TRUE(std::isnan(out.rec.uwb[i].range.rx_power_dbm));
  }
}

TEST(SimUwb, Seed000ProtocolLabelsHalfOfEachAnchorsRangesWithMeanErrorOneToTwoMetres) {
  const SimOutput out = run("seed000_protocol");
  ASSERT_EQ(out.rec.uwb.size(), 36004U);  // seed 000 §2.1: 4 anchors x 9001
  std::map<uint16_t, size_t> total;
  std::map<uint16_t, size_t> labelled;
  double err_nlos = 0.0;
  double err_los = 0.0;
  for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
    const dataset::UwbRow& row = out.rec.uwb[i];
    const double err = static_cast<double>(row.range.range_m) - out.range_truth[i].true_range_m;
    ++total[row.range.anchor_id];
    if (row.nlos_label == 1) {
      ++labelled[row.range.anchor_id];
      err_nlos += err;
    } else {
      err_los += err;
    }
  }
  size_t n_nlos = 0;
  for (const auto& kv : total) {
    EXPECT_EQ(kv.second, 9001U);
    EXPECT_GE(labelled[kv.first], 4500U);
    EXPECT_LE(labelled[kv.first], 4501U);
    n_nlos += labelled[kv.first];
  }
  err_nlos /= static_cast<double>(n_nlos);
  err_los /= static_cast<double>(out.rec.uwb.size() - n_nlos);
  EXPECT_GE(err_nlos, 1.0);
  EXPECT_LE(err_nlos, 2.0);
  EXPECT_NEAR(err_nlos, 1.5, 0.05);
  EXPECT_NEAR(err_los, 0.0, 0.01);
}

}  // namespace
}  // namespace uwbnav::sim
