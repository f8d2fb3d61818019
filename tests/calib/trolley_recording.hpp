// Test recording of the issue-19 vehicle: a 3-tag trolley (tags ~0.3 m apart)
// in a room with 8 anchors at 1.04 m, UWB-only at 100 Hz per tag, 5 cm noise,
// simulated by tools/sim; then known per anchor/tag pair offsets of 0.09-0.31 m
// (anchor delay + tag delay + a pair-specific part) and 1 cm quantisation are
// applied to every range, as the radio of that vehicle reports them.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "tools/dataset/recording.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::testing {

struct TrolleyRecording {
  dataset::Recording rec;
  std::vector<double> offset_m;  // true offset per pair index (anchor index * num_tags + tag index) [m]
};

// `moving`: a closed loop with turns (4.3 m x 3.5 m) after a 10 s stop at the
// start; otherwise parked for the whole run. `outlier_prob`: gross positive
// outliers per range (NLOS-like), 0 for a clean line-of-sight lab.
// `start`: "X Y Z HEADING_DEG" of the body origin at t = 0.
// `survey_sigma_m`: anchors.csv holds the true positions plus this error per axis.
inline std::string trolley_scenario(double duration_s, bool moving, double outlier_prob,
                                    const std::string& start = "1.5 1.2 0 0", double survey_sigma_m = 0.0) {
  std::string s = R"(
[scenario]
name = trolley_test
description = 3-tag trolley, 8 anchors at 1.04 m, UWB only, 100 Hz
platform = ground
[site]
anchor = 1 0 0 1.04
anchor = 2 4 0 1.04
anchor = 3 8 0 1.04
anchor = 4 8 3 1.04
anchor = 5 8 6 1.04
anchor = 6 4 6 1.04
anchor = 7 0 6 1.04
anchor = 8 0 3 1.04
tag = 0 0.20 0 0.45
tag = 1 -0.10 0.15 0.45
tag = 2 -0.10 -0.15 0.45
[imu]
enabled = 0
rate_hz = 100
[uwb]
rate_hz = 100
sigma_m = 0.05
packet_loss = 0
channel_diagnostics = 0
[nlos]
body_block = 0
[route]
)";
  s += "start = " + start + "\n";
  s += "[scenario]\nduration_s = " + std::to_string(duration_s) + "\n";
  s += "[site]\nsurvey_sigma_m = " + std::to_string(survey_sigma_m) + "\n";
  s += "[nlos]\noutlier_prob = " + std::to_string(outlier_prob) + "\noutlier_min_m = 0.5\noutlier_max_m = 5\n";
  if (moving) {
    s += R"([route]
loop_from = 2
maneuver = hold 10
maneuver = speed 0.8 2
maneuver = hold 1.5
maneuver = turn 90 3
maneuver = hold 0.5
maneuver = turn 90 3
maneuver = hold 1.5
maneuver = turn 90 3
maneuver = hold 0.5
maneuver = turn 90 3
)";
  }
  return s;
}

inline double trolley_true_offset(size_t anchor_index, size_t tag_index) {
  const double d_anchor = 0.08 + 0.02 * static_cast<double>(anchor_index);
  const double d_tag[3] = {0.02, 0.05, 0.08};
  const double pair = 0.004 * static_cast<double>(static_cast<int>((anchor_index * 3 + tag_index) % 5) - 2);
  return d_anchor + d_tag[tag_index % 3] + pair;
}

inline TrolleyRecording make_trolley(uint64_t seed, double duration_s = 60.0, bool moving = true,
                                     double outlier_prob = 0.0, const std::string& start = "1.5 1.2 0 0",
                                     double survey_sigma_m = 0.0) {
  TrolleyRecording out;
  sim::Scenario sc;
  std::string err;
  const std::string text = trolley_scenario(duration_s, moving, outlier_prob, start, survey_sigma_m);
  EXPECT_TRUE(ok(sim::parse_scenario(text, "trolley", sc, &err))) << err;
  EXPECT_TRUE(ok(sim::validate_scenario(sc, &err))) << err;
  sim::SimOptions opt;
  opt.seed = seed;
  sim::SimOutput sim_out;
  EXPECT_TRUE(ok(sim::simulate_scenario(sc, opt, sim_out, &err))) << err;
  out.rec = sim_out.rec;
  const SiteConfig& site = out.rec.site;
  out.offset_m.assign(site.num_anchors * site.num_tags, 0.0);
  for (size_t a = 0; a < site.num_anchors; ++a) {
    for (size_t t = 0; t < site.num_tags; ++t) out.offset_m[a * site.num_tags + t] = trolley_true_offset(a, t);
  }
  for (dataset::UwbRow& row : out.rec.uwb) {
    const int a = site.find_anchor(row.range.anchor_id);
    const int t = site.find_tag(row.range.tag_id);
    const double r = static_cast<double>(row.range.range_m) + trolley_true_offset(static_cast<size_t>(a), static_cast<size_t>(t));
    row.range.range_m = static_cast<float>(std::round(r * 100.0) / 100.0);  // 1 cm resolution
  }
  return out;
}

}  // namespace uwbnav::testing
