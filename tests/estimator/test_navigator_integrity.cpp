// The integrity check (seed 001 RAIM turned on the filter, docs/ekf.md
// "Integrity check") and the short-range test on simulated drives: ranges
// lengthened by NLOS never make them re-anchor an accurate filter, and a
// filter that has left its ranges is brought back without a reset, with dense
// ranging (integrity check) and with sparse ranging (short-range test), also
// when only one anchor in view can see its error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/estimator/nav_harness.hpp"
#include "tools/sim/family.hpp"

namespace uwbnav {
namespace {

// Horizontal error of the published position at the output nearest t_us.
double error_at(const test::RunScore& s, uint64_t t_us) {
  for (const test::ScoredOutput& o : s.outputs) {
    if (o.out.t_us >= t_us && o.has_truth) return std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
  }
  return NAN;
}

// Largest horizontal error of the published position over [t0_us, t1_us].
double max_error(const test::RunScore& s, uint64_t t0_us, uint64_t t1_us) {
  double m = 0.0;
  for (const test::ScoredOutput& o : s.outputs) {
    if (o.out.t_us >= t0_us && o.out.t_us <= t1_us && o.has_truth) {
      m = std::max(m, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
    }
  }
  return m;
}

// Keeps only ranges at least min_gap_us after the previous kept one (sparse ranging).
void thin_ranges(dataset::Recording& rec, uint64_t min_gap_us) {
  std::vector<dataset::UwbRow> thinned;
  uint64_t last_us = 0;
  for (const dataset::UwbRow& r : rec.uwb) {
    if (last_us != 0 && r.range.t_us - last_us < min_gap_us) continue;
    thinned.push_back(r);
    last_us = r.range.t_us;
  }
  rec.uwb = thinned;
}

// The push of the recovery tests: the accelerometer reads 3 m/s^2 too much
// along body x for 2 s from t = 40 s.
constexpr uint64_t kPushFrom_us = 40000000;
constexpr uint64_t kPushTo_us = 42000000;
void push_accelerometer(dataset::Recording& rec) {
  for (ImuSample& s : rec.imu) {
    if (s.t_us >= kPushFrom_us && s.t_us < kPushTo_us) s.accel_body_mps2.x += 3.0F;
  }
}

TEST(NavigatorIntegrity, NlosLengthenedRangesDoNotReanchorAnAccurateFilter) {
  // GIVEN a tuning drive of the NLOS lot (family ground_nlos, seed 6) where two
  // of the four anchors range long at once while the filter tracks the other
  // two: an LS fix from the latest range of each anchor then lies metres off
  // and still passes its own chi-square (two faults, two degrees of freedom).
  // Measured with the check failing on the chi-square alone: 5 integrity
  // failures, 1 re-anchor, 2 re-alignments, RMSE 0.23 m instead of 0.08 m on
  // this drive. (Seed 7, where this was first
  // seen, now takes a worse chord heading at its pull-away, and a re-anchor
  // there is right.)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_nlos", 6, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  std::printf("ground_nlos:6: rmse_h %.3f m, integrity fails %u, inflations %u, re-anchors %u, re-aligns %u\n",
              s.rmse_h_m, s.diag.integrity_fails, s.diag.inflations, s.diag.reanchors, s.diag.reinits);
  // THEN a disagreement that NLOS-lengthened ranges explain is no integrity
  // failure: the filter is neither re-anchored to the pulled fix nor re-aligned
  EXPECT_TRUE(s.all_finite);
  EXPECT_EQ(s.diag.reanchors, 0U);
  EXPECT_EQ(s.diag.reinits, 0U);
  EXPECT_LT(s.rmse_h_m, 2.5);
}

TEST(NavigatorIntegrity, AFilterPushedOffItsRangesIsBroughtBackWithoutAReset) {
  // GIVEN a line-of-sight drive (family ground_los, seed 3) whose accelerometer
  // reads 3 m/s^2 too much along body x for 2 s from t = 40 s: the filter is
  // pushed metres away from its ranges and gates them out as NLOS
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_los", 3, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  push_accelerometer(so.rec);
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  const double e_push = max_error(s, kPushFrom_us, kPushTo_us + 3000000);
  const double e_after = error_at(s, kPushTo_us + 10000000);
  std::printf("ground_los:3 pushed: error up to %.2f m during and after the push, %.3f m 10 s later; integrity fails %u, "
              "inflations %u, re-anchors %u, re-aligns %u, resets %u\n",
              e_push, e_after, s.diag.integrity_fails, s.diag.inflations, s.diag.reanchors, s.diag.reinits,
              s.diag.resets);
  // THEN the push carries the filter more than 1 m off, and the recovery
  // ladder (inflation, the gate's robust mode, the integrity check when ranges
  // are shorter than the filter's distances) brings the output back within
  // 0.3 m 10 s later, without a hard reset
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(e_push, 1.0);
  EXPECT_LT(e_after, 0.3);
  EXPECT_EQ(s.diag.resets, 0U);
}

TEST(NavigatorIntegrity, WithSparseRangingTheShortRangeTestBringsAPushedFilterBack) {
  // GIVEN the same pushed drive with its ranges thinned to about two per
  // second: no four ranges are ever fresh (0.5 s) together, so the
  // integrity check's LS fix never forms
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_los", 3, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  thin_ranges(so.rec, 450000);
  push_accelerometer(so.rec);
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  const double e_push = error_at(s, kPushTo_us);
  const double e_after = error_at(s, kPushTo_us + 20000000);
  std::printf("ground_los:3 pushed, 2 ranges/s: error %.2f m at the end of the push, %.3f m 20 s later; short-range "
              "fails %u, integrity fails %u, inflations %u, re-anchors %u, re-aligns %u, resets %u\n",
              e_push, e_after, s.diag.short_range_fails, s.diag.integrity_fails, s.diag.inflations, s.diag.reanchors,
              s.diag.reinits, s.diag.resets);
  // THEN ranges shorter than the filter's distances from two anchors widen
  // its claim, the gate lets them in, and the output is back within 1 m
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(e_push, 1.0);
  EXPECT_GE(s.diag.short_range_fails, 1U);
  EXPECT_EQ(s.diag.integrity_fails, 0U);
  EXPECT_LT(e_after, 1.0);
  EXPECT_EQ(s.diag.resets, 0U);
}

TEST(NavigatorIntegrity, APullAwayWithTwoAnchorsBlockedAndOneNlosHandsOverWithoutDrift) {
  // GIVEN a drive of the ground_blocked cell (seed 91, held out from the design
  // of the starved-geometry rule below but used to choose its threshold): the
  // car pulls away while two of the four anchors are blocked and a third is
  // NLOS behind the body (0.3-0.7 m excess). History on this drive: the IMU
  // filter once took over with its heading 37 degrees off and drifted along
  // the far anchor's line of sight, whose ranges then read 1-4 m shorter than
  // predicted; the short-range test was built on it (RMSE 1.77 m, MAX 32 m
  // before it; the short-range test's own check is now
  // WithSparseRangingTheShortRangeTestBringsAPushedFilterBack above). With that NLOS anchor's ranges dropped, the ranges-only filter
  // still slid 16 m along the one remaining range circle before the hand-over
  // (RMSE 0.92 m)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_blocked", 91, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  std::printf("ground_blocked:91: rmse_h %.3f m, max %.2f m, short-range fails %u, inflations %u, re-aligns %u, resets %u\n",
              s.rmse_h_m, s.max_h_m, s.diag.short_range_fails, s.diag.inflations, s.diag.reinits, s.diag.resets);
  // THEN the NLOS anchor's long ranges are fused by moment matching while one
  // line of sight is left (docs/nlos.md "Long NLOS ranges on a starved
  // geometry"): the filter holds, hands over near the truth and never needs
  // the recovery ladder
  EXPECT_TRUE(s.all_finite);
  EXPECT_EQ(s.diag.reinits, 0U);
  EXPECT_EQ(s.diag.resets, 0U);
  EXPECT_LT(s.max_h_m, 3.0);
  EXPECT_LT(s.rmse_h_m, 0.3);
}

TEST(NavigatorIntegrity, AReAlignedFilterStartsFromTheVehiclesVelocityAndStaysNearTheTrack) {
  // GIVEN a tuning drive of the ground_hard cell (seed 61: 8 anchors, 42 % of
  // the pairs' time NLOS, body NLOS) whose IMU filter is re-aligned while the
  // car drives (74 s, 5.6 m/s) and again in a U-turn. History: each time the
  // ranges-only filter restarted from zero velocity at a claimed 2 m/s; in
  // the U-turn NLOS ranges bent that velocity the wrong way while the gyro's
  // turn rotated it, and the published position (every epoch, degraded ones
  // included) ran 5.9 m off, with 5 re-alignments in all
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_hard", 61, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  uint64_t realign_us = 0;
  float speed_mps = 0.0F;
  double max_all_m = 0.0;  // over every published epoch with truth, whatever its status
  for (const test::ScoredOutput& o : s.outputs) {
    if (realign_us == 0 && o.out.mode == NavMode::kRecovering) {
      realign_us = o.out.t_us;
      speed_mps = std::hypot(o.out.vel_nav_mps.x, o.out.vel_nav_mps.y);
    }
    if (o.has_truth && o.out.mode != NavMode::kNone) {
      max_all_m = std::max(max_all_m, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
    }
  }
  std::printf("ground_hard:61: re-aligns %u, first at %.2f s publishing %.2f m/s; max error of all epochs %.2f m\n",
              s.diag.reinits, static_cast<double>(realign_us) * 1e-6, static_cast<double>(speed_mps), max_all_m);
  // THEN the ranges-only filter starts from the IMU filter's velocity (the car
  // does not stop when its filter re-aligns), the output stays within 2 m of
  // the track through the re-alignments, and they do not repeat
  ASSERT_GE(s.diag.reinits, 1U);
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(speed_mps, 4.0F);
  EXPECT_LT(max_all_m, 2.0);
  EXPECT_LE(s.diag.reinits, 3U);
}

TEST(NavigatorAir, AMulticoptersRangesOnlyVelocityDoesNotTurnWithItsYaw) {
  // GIVEN a tuning drive of the air_indoor cell (seed 1), the yaw bank's
  // hand-over at 0.01 rad (ekf.init_yaw_sigma: the ranges-only filter
  // publishes all the way), its ranges thinned to one every 0.5 s so that
  // the filter coasts between them,
  // flown twice: as simulated, and with the gyro reading an extra 0.3 rad/s
  // about body z for 10 s in flight (60-70 s), a yaw the body does not make.
  // A ground vehicle's ranges-only velocity turns with the gyro's vertical
  // rotation; a multicopter's does not follow its yaw (docs/ekf.md
  // "Initialisation", the ranges-only filter)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("air_indoor", 1, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  ASSERT_EQ(so.rec.site.platform, Platform::kAir);
  thin_ranges(so.rec, 500000);
  dataset::Recording yawed = so.rec;
  for (ImuSample& imu : yawed.imu) {
    if (imu.t_us >= 60000000 && imu.t_us < 70000000) imu.gyro_body_radps.z += 0.3F;
  }
  // WHEN the navigator runs over both
  Params params;
  ASSERT_EQ(params.set(ParamId::kEkfInitYawSigma, 0.01F), Status::kOk);
  const test::RunScore plain = test::replay(so.rec, params);
  const test::RunScore turned = test::replay(yawed, params);
  ASSERT_EQ(plain.outputs.size(), turned.outputs.size());
  double max_diff_m = 0.0;
  size_t ranges_only = 0;
  for (size_t i = 0; i < plain.outputs.size(); ++i) {
    const NavOutput& a = plain.outputs[i].out;
    const NavOutput& b = turned.outputs[i].out;
    if (a.mode == NavMode::kAligning && b.mode == NavMode::kAligning) {
      ++ranges_only;
      max_diff_m = std::max(max_diff_m, static_cast<double>(std::hypot(a.pos_nav_m.x - b.pos_nav_m.x,
                                                                        a.pos_nav_m.y - b.pos_nav_m.y)));
    }
  }
  std::printf("air_indoor:1, 2 ranges/s, with 3 rad of false yaw: %zu of %zu epochs ranges-only in both runs, "
              "largest horizontal difference %.4f m\n",
              ranges_only, plain.outputs.size(), max_diff_m);
  // THEN the published ranges-only solution stays within 1 m of the plain
  // run's; turned with the gyro, the velocity took the false 3 rad and the
  // output ran 4.7 m off. (Measured without the turn: 0.03 m on x86-64,
  // 0.27 m on aarch64, whose fused multiply-adds send the sparse run down
  // another path: the false yaw also reaches the levelled attitude's other
  // uses, such as the rest windows at its steps and the lever arm.)
  EXPECT_GT(ranges_only, plain.outputs.size() * 9 / 10);
  EXPECT_LT(max_diff_m, 1.0);
  EXPECT_TRUE(turned.all_finite);
}

TEST(NavigatorAir, AMulticopterWithoutHeadingStaysBoundedAndCoveredThroughUwbOutages) {
  // GIVEN a multicopter with a consumer IMU (turn-on gyro bias up to about
  // 0.5 deg/s, rotor vibration) that takes off without a heading source and
  // loses all ranges for 30 s and then 15 s (family outage, seed 2). Before the
  // levelled attitude was held by a complementary filter, its gyros alone
  // tilted it by 14 deg while aligning, the IMU filter took that tilt over at
  // a claimed 2.9 deg and drifted 795 m in the 30 s outage at a claimed 100 m.
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("outage", 2, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  ASSERT_EQ(so.scenario.uwb.outages.size(), 2U);
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  size_t n = 0, inside = 0;
  double worst_m = 0.0;
  for (const test::ScoredOutput& o : s.outputs) {
    const double t = static_cast<double>(o.out.t_us) * 1e-6;
    bool in_outage = false;
    for (const sim::Outage& g : so.scenario.uwb.outages) in_outage = in_outage || (t >= g.start_s && t < g.end_s);
    if (!in_outage || !o.has_truth || o.out.mode == NavMode::kNone) continue;
    const double e = std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
    const double sx = static_cast<double>(o.out.pos_sigma_m.x);
    const double sy = static_cast<double>(o.out.pos_sigma_m.y);
    worst_m = std::max(worst_m, e);
    inside += e <= 2.0 * std::sqrt(sx * sx + sy * sy) ? 1U : 0U;
    ++n;
  }
  std::printf("outage:2: %zu outputs inside the outages, worst error %.2f m, inside 2 sigma %.1f %%\n", n, worst_m,
              n > 0 ? 100.0 * static_cast<double>(inside) / static_cast<double>(n) : 0.0);
  // THEN the published solution stays bounded (5.3 m on x86-64, 11.9 m on
  // aarch64, where fused multiply-adds change the float rounding of this
  // chaotic flight; the bound is well below the 795 m it replaces) and its
  // claimed 2 sigma covers the error in at least 95 % of the outputs
  ASSERT_GT(n, 4000U);
  EXPECT_LT(worst_m, 25.0);
  EXPECT_GE(static_cast<double>(inside), 0.95 * static_cast<double>(n));
}

TEST(NavigatorHeadingSigma, IsNaNWhileTheHeadingIsNoEstimateAndCoversTheHeadingErrorAfterwards) {
  // GIVEN a line-of-sight drive with IMU that starts parked (family ground_los, seed 3)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_los", 3, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  size_t unknown = 0, known = 0, covered = 0;
  for (const test::ScoredOutput& o : s.outputs) {
    if (o.out.mode == NavMode::kNone) {
      EXPECT_TRUE(std::isnan(o.out.heading_sigma_rad));
      continue;
    }
    if (std::isnan(o.out.heading_sigma_rad)) {
      // THEN a heading that is no estimate only occurs before the IMU filter runs
      EXPECT_NE(o.out.mode, NavMode::kInertial);
      ++unknown;
      continue;
    }
    const auto& tr = so.rec.truth;
    auto it = std::lower_bound(tr.begin(), tr.end(), o.out.t_us,
                               [](const dataset::TruthRow& r, uint64_t t) { return r.t_us < t; });
    if (it == tr.end() || !it->has_attitude) continue;
    const double* q = it->q_nav_body;
    const double yaw = std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
    const double e = std::remainder(static_cast<double>(o.out.heading_rad) - yaw, 2.0 * M_PI);
    ++known;
    if (std::fabs(e) <= 2.0 * static_cast<double>(o.out.heading_sigma_rad)) ++covered;
  }
  std::printf("ground_los:3: heading unknown in %zu outputs, known in %zu, inside 2 sigma %.1f %%\n", unknown, known,
              known > 0 ? 100.0 * static_cast<double>(covered) / static_cast<double>(known) : 0.0);
  // AND once it is an estimate, its claimed sigma covers the heading error
  // (2 sigma, Gaussian 95 %) in at least 90 % of the outputs
  EXPECT_GT(unknown, 0U);
  EXPECT_GT(known, 1000U);
  EXPECT_GE(static_cast<double>(covered), 0.9 * static_cast<double>(known));
}

}  // namespace
}  // namespace uwbnav
