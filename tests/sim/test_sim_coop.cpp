// Neighbour vehicles in the simulator ([coop], the coop_canyon cell): the cell
// writes neighbours.csv and ranges to the neighbours' tags; the broadcast
// covariance is honest (NEES ~ 3 against the truth recomputed here through
// NeighbourTracks); inter-vehicle ranges are NLOS exactly when a third
// vehicle's box blocks the line; the ego hears fewer than 3 anchors for >= 20 s;
// GNSS is open only at the street's ends; adding neighbours changes no other
// stream; the [coop] keys parse and bad ones are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "tools/dataset/recording.hpp"
#include "tools/sim/coop.hpp"
#include "tools/sim/family.hpp"
#include "tools/sim/simulator.hpp"
#include "tools/sim/trajectory.hpp"

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

SimOutput canyon(uint64_t seed, bool fast = true) {
  FamilyOptions opt;
  opt.fast = fast;
  SimOutput out;
  std::string err;
  EXPECT_EQ(simulate_family("coop_canyon", seed, opt, out, &err), Status::kOk) << seed << " " << err;
  return out;
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

Eigen::Matrix3d covariance(const NeighbourState& n) {
  const float* c = n.cov_pos_m2;
  Eigen::Matrix3d p;
  p << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
  return p;
}

// Index of the vehicle with this id in the tracks.
size_t vehicle_index(const NeighbourTracks& tracks, uint16_t id) {
  for (size_t i = 0; i < tracks.size(); ++i) {
    if (tracks.vehicle(i).id == id) return i;
  }
  ADD_FAILURE() << "no vehicle " << id;
  return 0;
}

// Broadcast position minus the true tag, the truth recomputed from the scenario.
struct Residual {
  Eigen::Vector3d error_nav_m;
  Eigen::Matrix3d cov_m2;
  double yaw_rad = 0.0;  // the sender's heading at t_us
};

std::map<uint16_t, std::vector<Residual>> residuals_per_vehicle(const SimOutput& out) {
  NeighbourTracks tracks;
  tracks.build(out.scenario, out.scenario.duration_s);
  std::vector<NeighbourState> states = out.rec.neighbours;
  std::stable_sort(states.begin(), states.end(),
                   [](const NeighbourState& a, const NeighbourState& b) { return a.t_us < b.t_us; });
  std::map<uint16_t, std::vector<Residual>> res;
  for (const NeighbourState& n : states) {
    const size_t i = vehicle_index(tracks, n.vehicle_id);
    Residual r;
    r.error_nav_m = Eigen::Vector3d(n.pos_nav_m.x, n.pos_nav_m.y, n.pos_nav_m.z) - tracks.tag_nav_m(i, n.t_us);
    r.cov_m2 = covariance(n);
    r.yaw_rad = tracks.at(i, n.t_us).yaw_rad;
    res[n.vehicle_id].push_back(r);
  }
  return res;
}

double nees(const Residual& r) { return r.error_nav_m.dot(r.cov_m2.ldlt().solve(r.error_nav_m)); }

TEST(SimCoop, CanyonCellWritesNeighboursCsvWithTwoOrThreeVehiclesAt10HzAndRangesToTheirTags) {
  std::set<size_t> counts;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const SimOutput out = canyon(seed);
    const Scenario& sc = out.scenario;
    const double dur_s = sc.duration_s;
    ASSERT_GE(sc.coop.vehicles.size(), 2U) << seed;
    ASSERT_LE(sc.coop.vehicles.size(), 3U) << seed;
    counts.insert(sc.coop.vehicles.size());
    ASSERT_EQ(out.rec.neighbours.size(), out.neighbour_truth.size());
    ASSERT_EQ(out.rec.uwb.size(), out.range_truth.size());
    std::map<uint16_t, size_t> states;
    uint64_t prev_rx = 0;
    for (const NeighbourState& n : out.rec.neighbours) {
      ++states[n.vehicle_id];
      EXPECT_GE(n.rx_t_us, prev_rx) << "arrival order";
      prev_rx = n.rx_t_us;
      EXPECT_GE(n.rx_t_us - n.t_us, 20000U) << seed;
      EXPECT_LE(n.rx_t_us - n.t_us, 80000U) << seed;
      EXPECT_FALSE(n.cooperative);
      EXPECT_TRUE(std::isfinite(n.vel_nav_mps.x) && std::isfinite(n.vel_nav_mps.y) && std::isfinite(n.vel_nav_mps.z));
      const double sx = std::sqrt(static_cast<double>(n.cov_pos_m2[0]));
      const double sy = std::sqrt(static_cast<double>(n.cov_pos_m2[3]));
      const double sz = std::sqrt(static_cast<double>(n.cov_pos_m2[5]));
      EXPECT_GE(std::min(sx, sy), 0.05 - 1e-6);
      EXPECT_LE(std::max(sx, sy), 0.2 + 1e-6);
      EXPECT_GT(sz, std::max(sx, sy)) << "vertical larger than horizontal";
    }
    std::map<uint16_t, size_t> ranges;
    uint64_t prev_t = 0;
    for (const auto& row : out.rec.uwb) {
      EXPECT_GE(row.range.t_us, prev_t) << "uwb.csv in time order";
      prev_t = row.range.t_us;
      if (is_vehicle_id(row.range.anchor_id)) ++ranges[row.range.anchor_id];
    }
    uint16_t id = kFirstVehicleId + 1;
    for (const NeighbourDef& n : sc.coop.vehicles) {
      EXPECT_EQ(n.id, id++) << "vehicle ids 32769, 32770, ...";
      EXPECT_NEAR(static_cast<double>(states[n.id]), 10.0 * dur_s, 10.0 * 0.1 + 2.0) << seed << " " << n.id;
      EXPECT_GT(ranges[n.id], 0U) << seed << " " << n.id;
      if (n.motion == NeighbourMotion::kOffset) {
        // Always in range (8-30 m off): about 10 Hz less the packet loss.
        EXPECT_GE(static_cast<double>(ranges[n.id]), 10.0 * dur_s * (0.95 - sc.uwb.packet_loss)) << seed;
        EXPECT_LE(static_cast<double>(ranges[n.id]), 10.0 * dur_s + 1.0) << seed;
      }
    }
  }
  EXPECT_EQ(counts.size(), 2U) << "both 2 and 3 neighbours occur";

  // Written as a recording: neighbours.csv is there and reads back.
  const SimOutput out = canyon(2);
  const std::string dir = (std::filesystem::path(::testing::TempDir()) / "uwbnav_sim_coop_canyon_2").string();
  std::filesystem::remove_all(dir);
  ASSERT_EQ(dataset::write_recording(dir, out.rec), Status::kOk);
  ASSERT_TRUE(std::filesystem::exists(dir + "/neighbours.csv"));
  dataset::Recording back;
  dataset::ReadReport rep;
  ASSERT_EQ(dataset::read_recording(dir, back, rep), Status::kOk) << rep.error;
  EXPECT_TRUE(rep.warnings.empty());
  ASSERT_EQ(back.neighbours.size(), out.rec.neighbours.size());
  for (size_t i = 0; i < back.neighbours.size(); ++i) {
    ASSERT_EQ(back.neighbours[i].t_us, out.rec.neighbours[i].t_us) << i;
    ASSERT_EQ(back.neighbours[i].vehicle_id, out.rec.neighbours[i].vehicle_id) << i;
    ASSERT_TRUE(same_bits(back.neighbours[i].pos_nav_m.x, out.rec.neighbours[i].pos_nav_m.x)) << i;
  }
  std::filesystem::remove_all(dir);
  // A drive without neighbours has no neighbours.csv.
  SimOutput plain;
  std::string err;
  ASSERT_EQ(simulate_family("ground_gnss", 2, FamilyOptions{}, plain, &err), Status::kOk) << err;
  EXPECT_TRUE(plain.rec.neighbours.empty());
}

// An hour of three vehicles (two in formation with the turning ego, one
// circling): the broadcast error against the truth has NEES mean ~3 and the
// chi-square(3) 95 % share, its along/cross/up RMS is the claimed sigma, and it
// is time-correlated with the configured correlation time.
TEST(SimCoop, BroadcastCovarianceIsHonestOverAnHour) {
  const Scenario sc = load(
      "base = parking_los\n[scenario]\nduration_s = 3600\n[uwb]\nrate_hz = 1\n[coop]\n"
      "vehicle = 32769 offset 12 0\nvehicle = 32770 offset -20 0.3\nvehicle = 32771 route 10 40 0 0\n"
      "vehicle_maneuver = 32771 speed 5 3\nvehicle_maneuver = 32771 turn 360 60\n"
      "vehicle_error = 32769 0.05 0.15 0.3 5\nvehicle_error = 32770 0.2 0.08 0.4 10\n"
      "vehicle_error = 32771 0.1 0.12 0.2 20\n");
  const SimOutput out = run(sc, 23);
  const auto res = residuals_per_vehicle(out);
  ASSERT_EQ(res.size(), 3U);
  double sum = 0.0;
  size_t n = 0, in95 = 0;
  for (const auto& [id, rows] : res) {
    ASSERT_GT(rows.size(), 35900U) << id;
    const NeighbourDef* def = nullptr;
    for (const NeighbourDef& d : out.scenario.coop.vehicles) def = d.id == id ? &d : def;
    ASSERT_NE(def, nullptr);
    double sq[3] = {0, 0, 0};
    double lag = 0.0, var = 0.0;
    double prev_along = 0.0;
    for (size_t k = 0; k < rows.size(); ++k) {
      const Residual& r = rows[k];
      const double x = nees(r);
      sum += x;
      in95 += x <= 7.815 ? 1U : 0U;
      ++n;
      const double c = std::cos(r.yaw_rad), s = std::sin(r.yaw_rad);
      const double along = c * r.error_nav_m.x() + s * r.error_nav_m.y();
      const double cross = -s * r.error_nav_m.x() + c * r.error_nav_m.y();
      sq[0] += along * along;
      sq[1] += cross * cross;
      sq[2] += r.error_nav_m.z() * r.error_nav_m.z();
      if (k > 0) lag += along * prev_along;
      var += along * along;
      prev_along = along;
    }
    for (int a = 0; a < 3; ++a) {
      const double rms = std::sqrt(sq[a] / static_cast<double>(rows.size()));
      EXPECT_NEAR(rms / def->sigma_m[a], 1.0, 0.2) << id << " axis " << a;
    }
    EXPECT_NEAR(lag / var, std::exp(-0.1 / def->tau_s), 0.01) << id << ": first-order Gauss-Markov at 10 Hz";
  }
  std::printf("an hour, 3 vehicles: NEES mean %.3f, %.1f %% within the chi-square(3) 95 %% bound\n",
              sum / static_cast<double>(n), 100.0 * static_cast<double>(in95) / static_cast<double>(n));
  EXPECT_NEAR(sum / static_cast<double>(n), 3.0, 0.3);
  EXPECT_NEAR(static_cast<double>(in95) / static_cast<double>(n), 0.95, 0.03);
}

TEST(SimCoop, CanyonCellBroadcastCovarianceIsHonestPooledOverDrives) {
  double sum = 0.0;
  size_t n = 0;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    const SimOutput out = canyon(seed, false);
    for (const auto& [id, rows] : residuals_per_vehicle(out)) {
      for (const Residual& r : rows) {
        sum += nees(r);
        ++n;
      }
    }
    for (size_t i = 0; i < out.rec.neighbours.size(); ++i) {
      const NeighbourTruth& t = out.neighbour_truth[i];
      const NeighbourState& s = out.rec.neighbours[i];
      EXPECT_NEAR(s.pos_nav_m.x, t.tag_nav_m[0] + t.error_nav_m[0], 1e-3);
    }
  }
  ASSERT_GT(n, 30000U);
  EXPECT_NEAR(sum / static_cast<double>(n), 3.0, 0.6) << n << " states";
  std::printf("coop_canyon seeds 1-12: NEES mean %.3f over %zu broadcast states\n", sum / static_cast<double>(n), n);
}

// Segment p->q against the body box of `body` by clipping its parameter range
// against the six faces (Liang-Barsky); `grow_m` enlarges the box.
bool crosses_box(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const KinState& body, const double box_m[3],
                 double grow_m) {
  const Eigen::Vector3d a = body.R_nav_body.transpose() * (p - body.pos_nav_m);
  const Eigen::Vector3d d = body.R_nav_body.transpose() * (q - p);
  const double lo[3] = {-0.5 * box_m[0] - grow_m, -0.5 * box_m[1] - grow_m, -grow_m};
  const double hi[3] = {0.5 * box_m[0] + grow_m, 0.5 * box_m[1] + grow_m, box_m[2] + grow_m};
  double u0 = 0.0, u1 = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double pk[2] = {-d[k], d[k]};
    const double qk[2] = {a[k] - lo[k], hi[k] - a[k]};
    for (int j = 0; j < 2; ++j) {
      if (pk[j] == 0.0) {
        if (qk[j] < 0.0) return false;  // parallel to the face and outside it
        continue;
      }
      const double u = qk[j] / pk[j];
      if (pk[j] < 0.0) {
        u0 = std::max(u0, u);
      } else {
        u1 = std::min(u1, u);
      }
    }
  }
  return u0 <= u1;
}

TEST(SimCoop, VehicleRangesAreNlosExactlyWhenAThirdVehicleBlocksTheLine) {
  size_t blocked_n = 0, los_n = 0, checked = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const SimOutput out = canyon(seed);
    const Scenario& sc = out.scenario;
    Trajectory ego;
    ego.build(sc, sc.duration_s);
    NeighbourTracks tracks;
    tracks.build(sc, sc.duration_s);
    for (size_t r = 0; r < out.rec.uwb.size(); ++r) {
      const dataset::UwbRow& row = out.rec.uwb[r];
      if (!is_vehicle_id(row.range.anchor_id)) continue;
      const RangeTruth& truth = out.range_truth[r];
      const uint64_t t_us = row.range.t_us;
      const KinState e = ego.at(t_us);
      const double* l = sc.tags[0].lever_body_m;
      const Eigen::Vector3d ego_tag = e.pos_nav_m + e.R_nav_body * Eigen::Vector3d(l[0], l[1], l[2]);
      const size_t i = vehicle_index(tracks, row.range.anchor_id);
      const Eigen::Vector3d other_tag = tracks.tag_nav_m(i, t_us);
      ASSERT_NEAR(truth.true_range_m, (other_tag - ego_tag).norm(), 1e-9);
      ASSERT_LE(truth.true_range_m, sc.uwb.max_range_m);
      bool surely = false, maybe = false;  // blocked for a box 1 mm smaller / larger
      for (size_t m = 0; m < tracks.size(); ++m) {
        if (m == i) continue;
        const KinState b = tracks.at(m, t_us);
        surely = surely || crosses_box(ego_tag, other_tag, b, sc.coop.box_m, -1e-3);
        maybe = maybe || crosses_box(ego_tag, other_tag, b, sc.coop.box_m, 1e-3);
      }
      if (surely != maybe) continue;  // grazing a box edge: either answer is right
      ++checked;
      const bool outlier = truth.cause == RangeCause::kOutlier;
      EXPECT_EQ(row.nlos_label, surely || outlier ? 1 : 0) << seed << " t=" << t_us;
      if (outlier) continue;
      EXPECT_EQ(truth.cause, surely ? RangeCause::kVehicle : RangeCause::kLos) << seed << " t=" << t_us;
      const double err = static_cast<double>(row.range.range_m) - truth.true_range_m;
      if (surely) {
        ++blocked_n;
        EXPECT_GT(err, 0.2 - 5.0 * (sc.uwb.sigma_m + sc.coop.nlos_extra_sigma_m)) << seed;
        EXPECT_LT(err, 1.5 + 5.0 * (sc.uwb.sigma_m + sc.coop.nlos_extra_sigma_m)) << seed;
      } else {
        ++los_n;
        EXPECT_LT(std::fabs(err), 5.0 * sc.uwb.sigma_m + 1e-3) << seed;
      }
    }
  }
  std::printf("vehicle ranges: %zu blocked, %zu LOS, %zu checked (outliers and grazing lines excluded)\n", blocked_n,
              los_n, checked);
  EXPECT_GT(blocked_n, 1000U);
  EXPECT_GT(los_n, 10000U);
  EXPECT_GT(checked, blocked_n + los_n);
}

// Longest stretch [s] during which fewer than 3 distinct anchors (vehicle ids
// excluded) were heard in the 2 s before each 0.1 s step; `end_heard` gets the
// anchors heard in the last 2 s of the drive.
double longest_sparse_s(const SimOutput& out, size_t& end_heard) {
  std::map<uint16_t, double> heard;
  size_t next = 0;
  double longest = 0.0, start = -1.0;
  const double dur = out.scenario.duration_s;
  for (double t = 0.0; t <= dur; t += 0.1) {
    while (next < out.rec.uwb.size() && static_cast<double>(out.rec.uwb[next].range.t_us) * 1e-6 <= t) {
      const UwbRange& r = out.rec.uwb[next++].range;
      if (!is_vehicle_id(r.anchor_id)) heard[r.anchor_id] = static_cast<double>(r.t_us) * 1e-6;
    }
    size_t n = 0;
    for (const auto& kv : heard) n += kv.second + 2.0 >= t ? 1U : 0U;
    if (n < 3 && start < 0.0) start = t;
    if (n >= 3 && start >= 0.0) {
      longest = std::max(longest, t - start);
      start = -1.0;
    }
    end_heard = n;
  }
  if (start >= 0.0) longest = std::max(longest, dur - start);
  return longest;
}

TEST(SimCoop, EgoHearsFewerThanThreeAnchorsForAtLeast20sAndComesBack) {
  for (uint64_t seed : {1ULL, 2ULL, 3ULL, 4ULL, 5ULL, 6ULL, 7ULL, 8ULL, 1000ULL, 1001ULL}) {
    for (bool fast : {true, false}) {
      if (!fast && seed > 3) continue;  // full-length drives: three seeds keep the test short
      const SimOutput out = canyon(seed, fast);
      size_t end_heard = 0;
      EXPECT_GE(longest_sparse_s(out, end_heard), 20.0) << seed << (fast ? " fast" : "");
      if (!fast) {
        EXPECT_GE(end_heard, 3U) << seed << ": back among the anchors at the end";
      }
      ASSERT_GE(out.scenario.anchors.size(), 4U);
      ASSERT_LE(out.scenario.anchors.size(), 6U);
      for (const AnchorDef& a : out.scenario.anchors) EXPECT_LE(a.pos_nav_m[0], 55.0 + 1e-6) << seed;
      EXPECT_GE(out.scenario.uwb.max_range_m, 45.0);
      EXPECT_LE(out.scenario.uwb.max_range_m, 65.0);
    }
  }
}

TEST(SimCoop, GnssIsOpenAtTheStreetEndsAndBlockedOrMultipathInTheCanyon) {
  size_t blocked = 0, multipath = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const SimOutput out = canyon(seed, false);
    ASSERT_TRUE(out.scenario.gnss.enabled);
    ASSERT_FALSE(out.scenario.gnss.windows.empty());
    for (const GnssWindow& w : out.scenario.gnss.windows) {
      (w.kind == GnssWindowKind::kBlocked ? blocked : multipath) += 1;
    }
    double max_x = 0.0;
    for (const TruthState& t : out.truth) max_x = std::max(max_x, t.pos_nav_m[0]);
    size_t open_start = 0, in_canyon = 0;
    for (size_t i = 0; i < out.rec.gnss.size(); ++i) {
      const GnssFix& f = out.rec.gnss[i];
      const double x = out.truth[f.t_us / 10000U].pos_nav_m[0];
      const bool open = f.fix == GnssFixType::kDgnss;
      if (open) {
        EXPECT_TRUE(x < 90.0 + 3.0 || x > max_x - 30.0 - 3.0) << seed << " open sky fix at x=" << x;
      }
      open_start += open && f.t_us < 10000000U ? 1U : 0U;
      in_canyon += x > 95.0 && x < max_x - 35.0 ? 1U : 0U;
    }
    EXPECT_GE(open_start, 45U) << seed << ": fixes while parked at the anchors' end";
    // Inside the canyon: multipath fixes only, none where blocked (the ego spends > 10 s there).
    EXPECT_LT(static_cast<double>(in_canyon), 5.0 * 0.75 * (out.scenario.duration_s - 20.0)) << seed;
  }
  EXPECT_GT(blocked, 4U);
  EXPECT_GT(multipath, 4U);
}

bool same_range(const dataset::UwbRow& a, const dataset::UwbRow& b) {
  return a.range.t_us == b.range.t_us && a.range.anchor_id == b.range.anchor_id && a.range.tag_id == b.range.tag_id &&
         a.nlos_label == b.nlos_label && same_bits(a.range.range_m, b.range.range_m) &&
         same_bits(a.range.rx_power_dbm, b.range.rx_power_dbm) && same_bits(a.range.fp_power_dbm, b.range.fp_power_dbm);
}

TEST(SimCoop, AddingNeighboursLeavesImuAnchorRangesTruthAndGnssBitIdentical) {
  const std::string base =
      "base = parking_nlos\n[gnss]\nenabled = 1\nlever_m = 1 0 1.5\nblocked = 20 30\nmultipath = 40 50\n";
  const SimOutput a = run(load(base), 9);
  const SimOutput b = run(load(base + "[coop]\nvehicle = 32769 offset 10 0\nvehicle = 32770 offset 20 0\n"
                                      "vehicle = 32771 route 60 5 0 180\nvehicle_maneuver = 32771 speed 4 3\n"
                                      "vehicle_maneuver = 32771 hold 10\n"),
                          9);
  EXPECT_TRUE(a.rec.neighbours.empty());
  EXPECT_GT(b.rec.neighbours.size(), 1700U);
  for (const auto& kv : a.rec.meta) EXPECT_EQ(kv.first.find("coop"), std::string::npos) << kv.first;
  EXPECT_EQ(b.rec.meta.at("sim_coop_vehicles"), "32769,32770,32771");
  ASSERT_EQ(a.rec.imu.size(), b.rec.imu.size());
  for (size_t i = 0; i < a.rec.imu.size(); ++i) {
    ASSERT_TRUE(same_bits(a.rec.imu[i].accel_body_mps2.x, b.rec.imu[i].accel_body_mps2.x) &&
                same_bits(a.rec.imu[i].gyro_body_radps.z, b.rec.imu[i].gyro_body_radps.z))
        << "imu " << i;
  }
  ASSERT_EQ(a.rec.truth.size(), b.rec.truth.size());
  for (size_t i = 0; i < a.rec.truth.size(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(a.rec.truth[i].pos_nav_m[k], b.rec.truth[i].pos_nav_m[k]) << i;
  }
  std::vector<size_t> anchor_rows;
  size_t vehicle_rows = 0;
  for (size_t i = 0; i < b.rec.uwb.size(); ++i) {
    if (is_vehicle_id(b.rec.uwb[i].range.anchor_id)) {
      ++vehicle_rows;
    } else {
      anchor_rows.push_back(i);
    }
  }
  EXPECT_GT(vehicle_rows, 1000U);
  ASSERT_EQ(anchor_rows.size(), a.rec.uwb.size());
  for (size_t i = 0; i < a.rec.uwb.size(); ++i) {
    ASSERT_TRUE(same_range(a.rec.uwb[i], b.rec.uwb[anchor_rows[i]])) << "anchor range " << i;
    ASSERT_EQ(a.range_truth[i].bias_m, b.range_truth[anchor_rows[i]].bias_m) << i;
  }
  ASSERT_EQ(a.rec.gnss.size(), b.rec.gnss.size());
  for (size_t i = 0; i < a.rec.gnss.size(); ++i) {
    ASSERT_EQ(a.rec.gnss[i].rx_t_us, b.rec.gnss[i].rx_t_us);
    ASSERT_TRUE(same_bits(a.rec.gnss[i].pos_nav_m.x, b.rec.gnss[i].pos_nav_m.x)) << "gnss " << i;
  }
}

TEST(SimCoop, OffsetVehiclesDriveTheEgosRouteTranslatedAndRouteVehiclesTheirOwn) {
  const Scenario sc = load(
      "base = parking_los\n[route]\nstart = 5 7 0 30\n[coop]\nvehicle = 40000 offset 12 -3.5\n"
      "vehicle = 40001 route 100 0 0 90\nvehicle_maneuver = 40001 speed 5 2\nvehicle_maneuver = 40001 hold 1\n"
      "vehicle_tag = 40001 0.5 -0.1 1.3\ndependent = 1\n");
  const SimOutput out = run(sc, 4);
  Trajectory ego;
  ego.build(out.scenario, out.scenario.duration_s);
  NeighbourTracks tracks;
  tracks.build(out.scenario, out.scenario.duration_s);
  ASSERT_EQ(tracks.size(), 2U);
  const double h = 30.0 * 3.14159265358979323846 / 180.0;
  const Eigen::Vector3d offset(12.0 * std::cos(h) + 3.5 * std::sin(h), 12.0 * std::sin(h) - 3.5 * std::cos(h), 0.0);
  for (uint64_t t_us = 0; t_us < 60000000U; t_us += 1234567U) {
    const KinState e = ego.at(t_us);
    const KinState n = tracks.at(0, t_us);
    EXPECT_LT((n.pos_nav_m - e.pos_nav_m - offset).norm(), 1e-6) << t_us;
    EXPECT_NEAR(n.yaw_rad, e.yaw_rad, 1e-12);
    const KinState r = tracks.at(1, t_us);
    const double t_s = static_cast<double>(t_us) * 1e-6;
    if (t_s > 2.0) {
      EXPECT_NEAR(r.pos_nav_m.x(), 100.0, 1e-6) << "drives north (heading 90 deg)";
      EXPECT_NEAR(r.pos_nav_m.y(), 5.0 * (t_s - 2.0) + 5.0, 1e-3) << "5 m/s after 2 s reaching it (5 m)";
      EXPECT_NEAR(r.speed_mps, 5.0, 1e-9) << "repeats its last maneuver";
    }
  }
  const Eigen::Vector3d tag = tracks.tag_nav_m(1, 10000000U);
  const KinState r = tracks.at(1, 10000000U);
  EXPECT_LT((tag - r.pos_nav_m - r.R_nav_body * Eigen::Vector3d(0.5, -0.1, 1.3)).norm(), 1e-12);
  for (const NeighbourState& s : out.rec.neighbours) EXPECT_TRUE(s.cooperative) << "dependent = 1";
  EXPECT_NE(out.rec.meta.at("sim_coop_vehicle_40001").find("route 100 0 0 90"), std::string::npos);
}

TEST(SimCoop, CoopKeysAreCheckedWithTheirLine) {
  const auto error_of = [](const std::string& text) {
    Scenario sc;
    std::string err;
    EXPECT_NE(parse_scenario("base = parking_los\n[coop]\n" + text, "f.ini", sc, &err), Status::kOk) << text;
    return err;
  };
  EXPECT_NE(error_of("vehicle = 32767 offset 10 0\n").find("f.ini:3: vehicle: vehicle id must be an integer in [32768, 65534]"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 65535 offset 10 0\n").find("vehicle id must be"), std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nvehicle = 32769 offset 20 0\n").find("f.ini:4: vehicle: duplicate vehicle id"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 fly 10 0\n").find("unknown vehicle motion 'fly'"), std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10\n").find("ID offset DX DY"), std::string::npos);
  EXPECT_NE(error_of("vehicle_tag = 32769 0 0 1\n").find("not defined yet"), std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nvehicle_maneuver = 32769 speed 3 2\n").find("takes no maneuvers"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 route 0 0 0 0\nvehicle_maneuver = 32769 goto 1 2 3 4\n").find("hold, speed, turn and climb"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 route 0 0 0 0\n").find("has a route but no vehicle_maneuver"), std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nvehicle_error = 32769 0.1 0 0.2 5\n").find("must be > 0"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nlatency_ms = 10\nlatency_jitter_ms = 20\n").find("latency_jitter_ms exceeds"),
            std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nrate_hz = 3\n").find("coop.rate_hz must divide"), std::string::npos);
  EXPECT_NE(error_of("vehicle = 32769 offset 10 0\nnlos_bias_min_m = 2\nnlos_bias_max_m = 1\n").find("nlos_bias_max_m <"),
            std::string::npos);
  EXPECT_NE(error_of("box_m = 4.5 0 1.5\n").find("box_m needs"), std::string::npos);
  Scenario sc;
  std::string err;
  EXPECT_NE(parse_scenario("base = parking_los\n[site]\nanchor = 32769 0 0 2\n[coop]\nvehicle = 32769 offset 10 0\n", "f.ini",
                           sc, &err),
            Status::kOk);
  EXPECT_NE(err.find("vehicle id 32769 is an anchor id"), std::string::npos) << err;
  // Defaults of a scenario without [coop]: no vehicles.
  ASSERT_EQ(parse_scenario("base = parking_los\n", "f.ini", sc, &err), Status::kOk) << err;
  EXPECT_TRUE(sc.coop.vehicles.empty());
}

}  // namespace
}  // namespace uwbnav::sim
