// Navigator scenario tests on simulated drives (seeds differ from the tuning
// seeds 1-3): accuracy and consistency targets of issue 8, UWB outages, no-IMU
// mode and recovery, robustness to garbage input, real recordings end to end.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "tests/estimator/nav_harness.hpp"
#include "tools/sim/family.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

dataset::Recording simulate_or_fail(const std::string& preset, uint64_t seed) {
  dataset::Recording rec;
  std::string err;
  EXPECT_EQ(sim::simulate(preset, seed, rec, &err), Status::kOk) << err;
  return rec;
}

TEST(NavigatorScenario, ParkingLosMeetsRmseAndConsistencyTargets) {
  // GIVEN the LOS parking-lot drive (4 planar corner anchors, 100 Hz IMU)
  for (uint64_t seed : {11U, 12U}) {
    const dataset::Recording rec = simulate_or_fail("parking_los", seed);
    // WHEN the navigator runs from power-on without truth
    const test::RunScore s = test::replay(rec, Params{});
    // THEN horizontal RMSE <= 0.07 m, at least 90 % of errors lie inside 2 sigma,
    // and the claim is not inflated beyond use. (The preset has no antenna
    // offsets while the filter's prior allows 0.1 m per anchor on an unknown
    // site, of which four anchors observe little: the claim is pessimistic here,
    // close to 100 % inside 2 sigma - docs/ekf.md "What sigma means".)
    std::printf("parking_los seed %llu: rmse_h %.4f m, max %.3f m, inside 2sigma %.4f, mean sigma_h %.3f m, valid %zu\n",
                static_cast<unsigned long long>(seed), s.rmse_h_m, s.max_h_m, s.inside_2sigma, s.mean_sigma_h_m,
                s.n_valid);
    EXPECT_TRUE(s.all_finite);
    EXPECT_GT(s.n_scored, 12000U);  // valid for most of the 180 s drive
    EXPECT_LE(s.rmse_h_m, 0.07);
    EXPECT_GE(s.inside_2sigma, 0.90);
    EXPECT_LE(s.mean_sigma_h_m, 4.0 * s.rmse_h_m);
    EXPECT_EQ(s.diag.resets, 0U);
    EXPECT_EQ(s.diag.reinits, 0U);
  }
}

// The parking_los drive with the IMU of one grade (tools/sim apply_imu_grade).
dataset::Recording parking_los_with_imu(const std::string& grade, uint64_t seed) {
  sim::Scenario sc;
  std::string err;
  EXPECT_EQ(sim::parse_scenario("base = parking_los\n[imu]\ngrade = " + grade + "\n", "test", sc, &err), Status::kOk)
      << err;
  sim::SimOutput out;
  sim::SimOptions opt;
  opt.seed = seed;
  EXPECT_EQ(sim::simulate_scenario(sc, opt, out, &err), Status::kOk) << err;
  return out.rec;
}

TEST(NavigatorScenario, BiasInstabilityIsLearnedUpForAConsumerGyroAndStaysAtTheParameterForAnAutomotiveOne) {
  // GIVEN the same 180 s drive with a consumer IMU (gyro bias walk 3.5e-5
  // rad/s/sqrt(s), 3.5x imu.gyro_bias_rw) and with an automotive one (1.7e-6)
  for (uint64_t seed : {41U, 42U}) {
    const test::RunScore consumer = test::replay(parking_los_with_imu("consumer", seed), Params{});
    const test::RunScore automotive = test::replay(parking_los_with_imu("automotive", seed), Params{});
    Params off;
    ASSERT_EQ(off.set(ParamId::kImuBiasRwMaxGain, 1.0F), Status::kOk);
    const test::RunScore consumer_off = test::replay(parking_los_with_imu("consumer", seed), off);
    std::printf("seed %llu: gyro_rw_gain consumer %.2f automotive %.2f; accel_rw_gain consumer %.2f automotive %.2f; "
                "consumer inside 2sigma %.4f (learning off %.4f), rmse %.3f (off %.3f)\n",
                static_cast<unsigned long long>(seed), static_cast<double>(consumer.diag.gyro_bias_rw_gain),
                static_cast<double>(automotive.diag.gyro_bias_rw_gain), static_cast<double>(consumer.diag.accel_bias_rw_gain),
                static_cast<double>(automotive.diag.accel_bias_rw_gain), consumer.inside_2sigma, consumer_off.inside_2sigma,
                consumer.rmse_h_m, consumer_off.rmse_h_m);
    // THEN the consumer gyro's walk is learned well above the parameter, the
    // automotive one's stays near it (the parameter is the floor), and with
    // learning off nothing moves
    EXPECT_GT(consumer.diag.gyro_bias_rw_gain, 1.5F);
    EXPECT_LT(automotive.diag.gyro_bias_rw_gain, 1.3F);
    EXPECT_GE(automotive.diag.gyro_bias_rw_gain, 1.0F);
    EXPECT_EQ(consumer_off.diag.gyro_bias_rw_gain, 1.0F);
    EXPECT_EQ(consumer_off.diag.accel_bias_rw_gain, 1.0F);
    EXPECT_LE(consumer.diag.gyro_bias_rw_gain, 4.0F);  // imu.bias_rw_max_gain
  }
}

// Largest horizontal error of the outputs inside the recording's UWB outages.
double max_error_in_outages(const test::RunScore& s, const std::vector<sim::Outage>& outages) {
  double worst = 0.0;
  for (const auto& o : s.outputs) {
    const double t = static_cast<double>(o.out.t_us) * 1e-6;
    for (const sim::Outage& w : outages) {
      if (!o.has_truth || t < w.start_s || t >= w.end_s) continue;
      worst = std::fmax(worst, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
    }
  }
  return worst;
}

TEST(NavigatorScenario, RoadFrameNhcKeepsABrakingCarOnTrackThroughOutagesWithAnIdealImu) {
  // GIVEN two drives of the outage cell (tuning seeds; 0.49 and 0.45 deg of
  // nose-down pitch per m/s^2 of braking; outages of 5-30 s) simulated with an
  // ideal IMU: the error while coasting is what the constraints tell the filter
  for (uint64_t seed : {4U, 42U}) {
    sim::Scenario sc;
    std::string err;
    ASSERT_EQ(sim::draw_family_scenario("outage", seed, sim::FamilyOptions{}, sc, &err), Status::kOk) << err;
    sim::SimOptions opt;
    opt.seed = seed;
    opt.ideal_imu = true;
    sim::SimOutput out;
    ASSERT_EQ(sim::simulate_scenario(sc, opt, out, &err), Status::kOk) << err;
    ASSERT_FALSE(sc.uwb.outages.empty());
    // WHEN it coasts with the vertical NHC in the road frame (ekf.pitch_gradient
    // at its default, 0.2 deg/(m/s^2)) and with the body-frame NHC (0)
    const test::RunScore road = test::replay(out.rec, Params{});
    Params body_frame;
    ASSERT_EQ(body_frame.set(ParamId::kEkfPitchGradient, 0.0F), Status::kOk);
    const test::RunScore body = test::replay(out.rec, body_frame);
    const double e_road = max_error_in_outages(road, sc.uwb.outages);
    const double e_body = max_error_in_outages(body, sc.uwb.outages);
    std::printf("outage:%llu (pitch gain %.2f deg/(m/s^2)), ideal IMU: worst error in the outages %.3f m (body-frame "
                "NHC %.3f m)\n",
                static_cast<unsigned long long>(seed), sc.vehicle.pitch_gain_deg_per_mps2, e_road, e_body);
    // THEN the road-frame constraint drifts less than the body-frame one
    EXPECT_TRUE(road.all_finite);
    EXPECT_LT(e_road, 0.8 * e_body);
  }
}

TEST(NavigatorScenario, Indoor3dTracksRampsWithoutHeightConstraint) {
  const dataset::Recording rec = simulate_or_fail("indoor3d", 13);
  const test::RunScore s = test::replay(rec, Params{});
  std::printf("indoor3d seed 13: rmse_h %.4f m, inside 2sigma %.4f\n", s.rmse_h_m, s.inside_2sigma);
  EXPECT_TRUE(s.all_finite);
  EXPECT_LE(s.rmse_h_m, 0.10);
  EXPECT_GE(s.inside_2sigma, 0.85);
}

TEST(NavigatorScenario, UwbOutagesCoastDegradeAndRecover) {
  // GIVEN outages of 5 s [40,45), 10 s [80,90), 15 s [120,135)
  const dataset::Recording rec = simulate_or_fail("parking_outages", 14);
  const test::RunScore s = test::replay(rec, Params{});
  EXPECT_TRUE(s.all_finite);
  const double starts[3] = {40, 80, 120};
  const double ends[3] = {45, 90, 135};
  for (int k = 0; k < 3; ++k) {
    double err_end = 0;
    double sigma_end = 0;
    bool degraded = false;
    bool valid_after = false;
    for (const auto& o : s.outputs) {
      const double t = static_cast<double>(o.out.t_us) * 1e-6;
      if (t > starts[k] && t < ends[k] && o.has_truth) {
        err_end = std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
        sigma_end = std::hypot(static_cast<double>(o.out.pos_sigma_m.x), static_cast<double>(o.out.pos_sigma_m.y));
        degraded = degraded || o.out.status == NavStatus::kDegraded;
      }
      if (t > ends[k] + 3 && t < ends[k] + 5) valid_after = valid_after || o.out.status == NavStatus::kValid;
    }
    std::printf("outage %.0f s: horizontal error at its end %.3f m, claimed 1-sigma %.3f m\n", ends[k] - starts[k],
                err_end, sigma_end);
    // THEN the status says degraded, the claimed sigma covers the drift, and it recovers
    EXPECT_TRUE(degraded);
    EXPECT_TRUE(valid_after);
    EXPECT_LT(err_end, 3.0 * sigma_end + 0.1);
  }
}

TEST(NavigatorScenario, WithoutImuRunsRangesOnlyFromTheFirstFix) {
  // GIVEN a vehicle without IMU (has_imu false): the ranges-only filter is its nominal mode
  const dataset::Recording rec = simulate_or_fail("parking_los", 15);
  const test::RunScore s = test::replay(rec, Params{}, 0, UINT64_MAX, nullptr, /*drop_imu=*/true);
  EXPECT_TRUE(s.all_finite);
  size_t published = 0;
  double sum_sq = 0;
  size_t n = 0;
  for (const auto& o : s.outputs) {
    if (o.out.mode == NavMode::kNone) continue;
    EXPECT_EQ(o.out.mode, NavMode::kUwbOnly);
    EXPECT_TRUE(o.out.status == NavStatus::kValid || o.out.status == NavStatus::kDegraded);
    ++published;
    if (o.has_truth) {
      sum_sq += o.err_nav_m[0] * o.err_nav_m[0] + o.err_nav_m[1] * o.err_nav_m[1];
      ++n;
    }
  }
  ASSERT_GT(published, 17900U);  // from the first fix on, every epoch
  const double rmse = std::sqrt(sum_sq / static_cast<double>(n));
  std::printf("parking_los without IMU: rmse_h %.4f m\n", rmse);
  EXPECT_LT(rmse, 0.40);  // the constant-velocity model lags in turns; the parked start carries the lever arm
}

TEST(NavigatorScenario, WithoutImuALongRangeGapMeanRevertsTheVelocityAndStaysCovered) {
  // GIVEN a vehicle without IMU whose ranges stop for 20 s (60-80 s) while it
  // keeps driving its loops with stops and turns
  dataset::Recording rec = simulate_or_fail("parking_los", 21);
  std::vector<dataset::UwbRow> kept;
  for (const auto& r : rec.uwb) {
    if (r.range.t_us < 60000000 || r.range.t_us >= 80000000) kept.push_back(r);
  }
  rec.uwb = kept;
  // WHEN it runs with the mean-reverting velocity (default) and with constant
  // velocity (ekf.cv_vel_tau at its maximum)
  Params cv;
  ASSERT_EQ(cv.set(ParamId::kEkfCvVelTau, 1000.0F), Status::kOk);
  const test::RunScore ou_run = test::replay(rec, Params{}, 0, UINT64_MAX, nullptr, /*drop_imu=*/true);
  const test::RunScore cv_run = test::replay(rec, cv, 0, UINT64_MAX, nullptr, /*drop_imu=*/true);
  ASSERT_TRUE(ou_run.all_finite);
  ASSERT_TRUE(cv_run.all_finite);
  auto gap_stats = [](const test::RunScore& s, double& rms, double& covered, double& speed_end) {
    double sq = 0;
    size_t n = 0, in = 0;
    for (const auto& o : s.outputs) {
      const double t = static_cast<double>(o.out.t_us) * 1e-6;
      if (t < 60.5 || t >= 80 || !o.has_truth) continue;
      const double e2 = o.err_nav_m[0] * o.err_nav_m[0] + o.err_nav_m[1] * o.err_nav_m[1];
      const double sx = static_cast<double>(o.out.pos_sigma_m.x), sy = static_cast<double>(o.out.pos_sigma_m.y);
      sq += e2;
      ++n;
      // Inside the 2-sigma circle of the larger axis (95 % for a circular error).
      if (std::sqrt(e2) <= 2.45 * std::max(sx, sy)) ++in;
      speed_end = std::hypot(static_cast<double>(o.out.vel_nav_mps.x), static_cast<double>(o.out.vel_nav_mps.y));
    }
    rms = n > 0 ? std::sqrt(sq / static_cast<double>(n)) : 1e9;
    covered = n > 0 ? static_cast<double>(in) / static_cast<double>(n) : 0.0;
  };
  double ou_rms = 0, ou_cov = 0, ou_speed = 0, cv_rms = 0, cv_cov = 0, cv_speed = 0;
  gap_stats(ou_run, ou_rms, ou_cov, ou_speed);
  gap_stats(cv_run, cv_rms, cv_cov, cv_speed);
  std::printf("20 s gap without IMU: mean-reverting rms %.2f m (covered %.1f %%, speed at end %.2f m/s), "
              "constant velocity rms %.2f m (covered %.1f %%, speed at end %.2f m/s)\n",
              ou_rms, 100 * ou_cov, ou_speed, cv_rms, 100 * cv_cov, cv_speed);
  // THEN the predicted velocity has decayed (tau 5 s: e^-4 after 20 s), the
  // position error during the gap is smaller than the constant-velocity
  // extrapolation's, and the claimed sigma still covers it
  EXPECT_LT(ou_speed, 0.1 * cv_speed + 0.05);
  EXPECT_LT(ou_rms, cv_rms);
  EXPECT_GT(ou_cov, 0.9);
}

TEST(NavigatorScenario, ImuDropoutFallsBackAndRecovers) {
  dataset::Recording rec = simulate_or_fail("parking_los", 16);
  // Remove the IMU between 60 s and 75 s.
  std::vector<ImuSample> kept;
  for (const auto& s : rec.imu) {
    if (s.t_us < 60000000 || s.t_us >= 75000000) kept.push_back(s);
  }
  rec.imu = kept;
  const test::RunScore s = test::replay(rec, Params{});
  EXPECT_TRUE(s.all_finite);
  bool degraded_during = false;
  bool valid_after = false;
  double max_err_during = 0;
  for (const auto& o : s.outputs) {
    const double t = static_cast<double>(o.out.t_us) * 1e-6;
    if (t > 61 && t < 75) {
      degraded_during = degraded_during || o.out.status == NavStatus::kDegraded;
      if (o.has_truth) max_err_during = std::max(max_err_during, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
    }
    if (t > 80 && t < 90) valid_after = valid_after || o.out.status == NavStatus::kValid;
  }
  EXPECT_TRUE(degraded_during);
  EXPECT_TRUE(valid_after);
  EXPECT_LT(max_err_during, 1.0);
  EXPECT_EQ(s.diag.resets, 0U);
}

TEST(NavigatorScenario, GarbageInputNeverProducesNaN) {
  dataset::Recording rec = simulate_or_fail("parking_los", 17);
  // Corrupt: gross range outliers, a burst of huge accelerations, non-finite samples.
  for (size_t i = 0; i < rec.uwb.size(); i += 37) rec.uwb[i].range.range_m += 40.0F;
  for (size_t i = 3000; i < 3100 && i < rec.imu.size(); ++i) rec.imu[i].accel_body_mps2.x = 150.0F;
  rec.imu[5000].gyro_body_radps.z = std::nanf("");
  rec.uwb[2000].range.range_m = std::nanf("");
  const test::RunScore s = test::replay(rec, Params{});
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(s.n_valid, 5000U);
}

TEST(NavigatorScenario, StatusIsInitialisingBeforeAnyFix) {
  const dataset::Recording rec = simulate_or_fail("parking_los", 18);
  Navigator nav;
  ASSERT_EQ(nav.configure(rec.site, Params{}), Status::kOk);
  for (size_t i = 0; i < 50; ++i) ASSERT_EQ(nav.on_imu(rec.imu[i]), Status::kOk);
  const NavOutput o = nav.output(rec.imu[49].t_us);
  EXPECT_EQ(o.status, NavStatus::kInitialising);
  // No estimate yet: no position is published (NaN; estimates.csv leaves it empty).
  EXPECT_EQ(o.mode, NavMode::kNone);
  EXPECT_TRUE(std::isnan(o.pos_nav_m.x) && std::isnan(o.pos_nav_m.y));
}

TEST(NavigatorScenario, ResetRestartsInitialisation) {
  const dataset::Recording rec = simulate_or_fail("parking_los", 19);
  Navigator nav;
  ASSERT_EQ(nav.configure(rec.site, Params{}), Status::kOk);
  size_t j = 0;
  for (const auto& s : rec.imu) {
    if (s.t_us > 30000000) break;
    (void)nav.on_imu(s);
    while (j < rec.uwb.size() && rec.uwb[j].range.t_us <= s.t_us) (void)nav.on_range(rec.uwb[j++].range);
  }
  EXPECT_EQ(nav.output(30000000).status, NavStatus::kValid);
  nav.reset();
  EXPECT_EQ(nav.output(30000000).status, NavStatus::kInitialising);
}

void run_real(const std::string& rel, bool expect_imu) {
  const std::string dir = std::string(UWBNAV_DATA_DIR) + "/" + rel;
  dataset::Recording rec;
  dataset::ReadReport rr;
  ASSERT_EQ(dataset::read_recording(dir, rec, rr), Status::kOk) << "shipped recording unreadable: " << rr.error;
  EXPECT_EQ(!rec.imu.empty(), expect_imu);
  const test::RunScore s = test::replay(rec, Params{});
  EXPECT_TRUE(s.all_finite);
  double sum_sq = 0;
  size_t n = 0;
  for (const auto& o : s.outputs) {
    if ((o.out.status == NavStatus::kValid || o.out.status == NavStatus::kDegraded) && o.has_truth) {
      sum_sq += o.err_nav_m[0] * o.err_nav_m[0] + o.err_nav_m[1] * o.err_nav_m[1];
      ++n;
    }
  }
  std::printf("%s: %zu outputs with a solution, rmse_h %.3f m, resets %u, reinits %u\n", rel.c_str(), n,
              n ? std::sqrt(sum_sq / static_cast<double>(n)) : 0.0, s.diag.resets, s.diag.reinits);
  EXPECT_GT(n, 0U);
}

TEST(NavigatorRealData, AWalkFarFromItsAnchorClusterIsNotPulledAlongTheRangeCircles) {
  // GIVEN a real recording (hanyang LOS case 2, no IMU): four anchors within
  // 3 m of each other, a walker up to 50 m away, and a 22 s range gap after
  // which the ranges-only filter's position is uncertain by metres across
  // lines of sight that are all nearly the same. A first-order update moved
  // the position metres along the range circles' tangents on the strength of
  // the tiny slope the range has there (MAX 8.6 m, RMSE 1.41 m over the
  // published outputs with truth)
  const std::string dir = std::string(UWBNAV_DATA_DIR) + "/hanyang/hanyang_los_trajA_case2";
  dataset::Recording rec;
  dataset::ReadReport rr;
  ASSERT_EQ(dataset::read_recording(dir, rec, rr), Status::kOk) << "shipped recording unreadable: " << rr.error;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(rec, Params{});
  double sum2 = 0.0, worst_m = 0.0;
  size_t n = 0;
  for (const test::ScoredOutput& o : s.outputs) {
    if (!o.has_truth || o.out.mode == NavMode::kNone) continue;
    const double e = std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
    sum2 += e * e;
    worst_m = std::max(worst_m, e);
    ++n;
  }
  ASSERT_GT(n, 10000U);
  const double rmse_m = std::sqrt(sum2 / static_cast<double>(n));
  std::printf("hanyang LOS case 2: rmse_h %.3f m, max %.2f m, iterated range updates %u\n", rmse_m, worst_m,
              s.diag.iterated_updates);
  // THEN a range whose first-order step the circle's curvature contradicts is
  // re-linearised at the corrected position (iterated update): the step
  // shrinks to what the range supports, and the error stays within 6.5 m
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(s.diag.iterated_updates, 0U);
  EXPECT_LT(worst_m, 6.5);
  EXPECT_LT(rmse_m, 1.3);
}

TEST(NavigatorRealData, MiluvDroneRunsEndToEndWithoutNaN) { run_real("miluv/miluv_3drone_ifo001", true); }
TEST(NavigatorRealData, HanyangLosWalkRunsEndToEndWithoutNaN) { run_real("hanyang/hanyang_los_trajA_case1", false); }
TEST(NavigatorRealData, HanyangNlosWalkRunsEndToEndWithoutNaN) { run_real("hanyang/hanyang_nlos_trajA_case2", false); }

TEST(NavigatorScenario, APullAwayUnderNlosIsHeldByTheShortRangesOfItsNlosAnchors) {
  // GIVEN the README's main job (parking_nlos, seed 1): the car pulls away at
  // 13 s while anchors 2 and 4 are NLOS and anchor 1 turns NLOS at 14.4 s. The
  // ranges-only filter (heading not yet known) fused anchor 3 alone and ran
  // 11 m off at a claimed 1.5-2.8 m (MAX 17.3 m), although anchor 2 kept
  // reading shorter than predicted - which no NLOS path does.
  std::string err;
  dataset::Recording rec;
  ASSERT_TRUE(ok(sim::simulate("parking_nlos", 1, rec, &err))) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(rec, Params{});
  // THEN short ranges of NLOS anchors bound the filter: over every published
  // output the error stays small and inside the claimed 2 sigma
  size_t n = 0, inside = 0;
  double sum2 = 0.0, worst_m = 0.0;
  for (const test::ScoredOutput& o : s.outputs) {
    if (!o.has_truth || o.out.mode == NavMode::kNone) continue;
    const double e = std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
    const double sx = static_cast<double>(o.out.pos_sigma_m.x);
    const double sy = static_cast<double>(o.out.pos_sigma_m.y);
    ++n;
    sum2 += e * e;
    worst_m = std::max(worst_m, e);
    inside += e <= 2.0 * std::sqrt(sx * sx + sy * sy) ? 1U : 0U;
  }
  ASSERT_GT(n, 15000U);
  const double rmse_m = std::sqrt(sum2 / static_cast<double>(n));
  const double share = static_cast<double>(inside) / static_cast<double>(n);
  std::printf("parking_nlos seed 1, every published output: rmse_h %.3f m, max %.2f m, inside 2sigma %.4f, n %zu\n",
              rmse_m, worst_m, share, n);
  EXPECT_TRUE(s.all_finite);
  EXPECT_LT(rmse_m, 0.5);
  EXPECT_LT(worst_m, 3.0);
  EXPECT_GE(share, 0.95);
}

}  // namespace
}  // namespace uwbnav

namespace uwbnav {
namespace {

TEST(NavigatorScenario, GroundStartIsAccurateAndHonestFromItsFirstValidEpoch) {
  // GIVEN short parking-lot drives (12 s parked, then driving off): the first
  // seconds after the filter starts are where an optimistic heading shows.
  for (uint64_t seed : {3U, 31U}) {
    std::string err;
    dataset::Recording rec;
    ASSERT_TRUE(ok(sim::simulate("parking_nlos", seed, rec, &err))) << err;
    // Keep the first 25 s only.
    const uint64_t t_end = rec.imu.front().t_us + 25000000U;
    while (!rec.imu.empty() && rec.imu.back().t_us > t_end) rec.imu.pop_back();
    while (!rec.uwb.empty() && rec.uwb.back().range.t_us > t_end) rec.uwb.pop_back();
    // WHEN the navigator starts from power-on
    const test::RunScore s = test::replay(rec, Params{});
    std::printf("parking_nlos first 25 s, seed %llu: rmse_h %.4f m, max %.3f m, inside 2sigma %.4f, valid %zu\n",
                static_cast<unsigned long long>(seed), s.rmse_h_m, s.max_h_m, s.inside_2sigma, s.n_valid);
    // THEN the start is close to the steady state and its sigma covers the error.
    // The IMU filter takes over from the ranges-only filter, whose error it
    // inherits: since short NLOS ranges bound the ranges-only filter during the
    // pull-away it is 0.4-0.6 m off at an honest sigma (before: 4.5 m off, then
    // re-anchored to an LS fix just before the hand-over), and the first valid
    // seconds carry that (seed 3: 0.07 -> 0.18 m over 995 valid epochs instead of
    // 812, the hand-over being earlier; the published start as a whole improved).
    EXPECT_TRUE(s.all_finite);
    EXPECT_GT(s.n_scored, 500U);
    EXPECT_LE(s.rmse_h_m, 0.20);
    EXPECT_GE(s.inside_2sigma, 0.80);
  }
}

TEST(NavigatorScenario, ASparseRangingPullAwayStartsTheImuFilterWithAnHonestHeading) {
  // GIVEN tuning drive ground_sparse:1: four anchors ranged 1.1 times a second
  // each, 13 s parked, then a pull-away to 7.5 m/s. A fix of the LS track
  // combines ranges up to a second old, during which the car moved metres, and
  // allowed only ekf.init_speed (1 m/s) for that: the track's chords started
  // the IMU filter 20 degrees off at a claimed few, and it ran 7 m off at a
  // claimed 0.3 m (valid epochs: RMSE 1.59 m, MAX 9.2 m, 76 % inside 2 sigma).
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("ground_sparse", 1, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore s = test::replay(so.rec, Params{});
  std::printf("ground_sparse:1: rmse_h %.3f m, max %.2f m, inside 2sigma %.4f, valid %zu, re-aligns %u\n", s.rmse_h_m,
              s.max_h_m, s.inside_2sigma, s.n_valid, s.diag.reinits);
  // THEN each chord counts the travel its fixes' ranges missed (its own length
  // over its time, less the fixes' noise, above ekf.init_speed, times each
  // fix's oldest range age): the heading is taken later, from longer chords,
  // at an honest sigma.
  EXPECT_TRUE(s.all_finite);
  EXPECT_GT(s.n_scored, 5000U);
  EXPECT_LE(s.rmse_h_m, 0.5);
  EXPECT_GE(s.inside_2sigma, 0.90);
  EXPECT_EQ(s.diag.reinits, 0U);
}

}  // namespace
}  // namespace uwbnav
