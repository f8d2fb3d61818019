// The ranges-only filter that publishes while the IMU filter aligns, on
// simulated tuning drives where it failed: a quiet cruise at constant speed
// taken for rest (docs/ekf.md "Rest while aligning"), and a pull-away under
// heavy NLOS in which the coarse NLOS evidence, reading the filter's own
// lagging speed, flagged every range (docs/nlos.md "Robust mode"), and a
// cruise with two anchors in view, too few for an LS track; a multicopter
// whose IMU filter took over with the gyro bias its levelling made up; and a
// start heading taken from a mirror fix across a road's anchor line; a cruise
// after a pull-away taken for rest again; a consumer IMU's vertical balance
// bent by the turn that told its horizontal bias from tilt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/estimator/nav_harness.hpp"
#include "tools/eval/eval_outage.hpp"
#include "tools/sim/family.hpp"

namespace uwbnav {
namespace {

// Every published position (any status, any mode) against the truth.
struct DriveScore {
  test::RunScore run;
  double rmse_h_m = 0.0;
  double max_h_m = 0.0;
  double inertial_share = 0.0;  // share of published outputs from the IMU filter
  double inside_2sigma = 0.0;   // share of per-axis (x and y) errors inside the claimed 2 sigma, every published output
};

DriveScore run_family_drive(const char* cell, uint32_t seed, const Params& params = Params{}) {
  sim::SimOutput so;
  std::string err;
  EXPECT_EQ(sim::simulate_family(cell, seed, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  DriveScore d;
  d.run = test::replay(so.rec, params);
  double sum2 = 0.0;
  size_t n = 0, inertial = 0, inside = 0;
  for (const test::ScoredOutput& o : d.run.outputs) {
    if (!o.has_truth || !std::isfinite(o.out.pos_nav_m.x)) continue;
    const double e2 = o.err_nav_m[0] * o.err_nav_m[0] + o.err_nav_m[1] * o.err_nav_m[1];
    inside += (std::fabs(o.err_nav_m[0]) <= 2.0 * static_cast<double>(o.out.pos_sigma_m.x)) +
              (std::fabs(o.err_nav_m[1]) <= 2.0 * static_cast<double>(o.out.pos_sigma_m.y));
    sum2 += e2;
    d.max_h_m = std::max(d.max_h_m, std::sqrt(e2));
    ++n;
    if (o.out.mode == NavMode::kInertial) ++inertial;
  }
  EXPECT_GT(n, 1000U);
  d.rmse_h_m = n > 0 ? std::sqrt(sum2 / static_cast<double>(n)) : 1e9;
  d.inertial_share = n > 0 ? static_cast<double>(inertial) / static_cast<double>(n) : 0.0;
  d.inside_2sigma = n > 0 ? static_cast<double>(inside) / static_cast<double>(2 * n) : 0.0;
  std::printf("%s:%u: rmse_h %.3f m, max %.2f m, in 2-sigma %.1f %%, re-aligns %u, inflations %u, resets %u, IMU filter %.1f %%\n",
              cell, static_cast<unsigned>(seed), d.rmse_h_m, d.max_h_m, 100.0 * d.inside_2sigma, d.run.diag.reinits,
              d.run.diag.inflations, d.run.diag.resets, 100.0 * d.inertial_share);
  return d;
}

// Every output finite and no hard reset: what each drive below must keep,
// whatever else it checks.
void expect_finite_without_hard_reset(const DriveScore& s) {
  EXPECT_TRUE(s.run.all_finite);
  EXPECT_EQ(s.run.diag.resets, 0U);
}

TEST(NavigatorAlignment, AQuietCruiseAtConstantSpeedIsNotTakenForRest) {
  // GIVEN a tuning drive of the outage cell (seed 81): a car in a parking lot
  // drives straight legs at a constant 1.26 m/s with a quiet IMU, which alone
  // cannot tell such a cruise from rest; before the track's speed was part of
  // the rest check, rest was latched at 1.2 m/s, the ranges-only filter held at
  // zero speed and re-started 52 times, and the heading was never acquired
  // (RMSE 2.18 m, IMU filter 0 % of the drive)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("outage", 81);
  // THEN the cruise is seen as motion: the IMU filter takes over and stays
  EXPECT_TRUE(s.run.all_finite);
  EXPECT_EQ(s.run.diag.reinits, 0U);
  EXPECT_GT(s.inertial_share, 0.5);
  EXPECT_LT(s.rmse_h_m, 0.5);
}

TEST(NavigatorAlignment, ACruiseWithOnlyTwoAnchorsInViewIsNotTakenForRest) {
  // GIVEN a tuning drive of the ground_blocked cell (seed 60): a car drives a
  // 197 m road at a constant 2 m/s with a quiet IMU; for 14 s at a time two of
  // the four anchors are blocked, so no LS fix (three anchors) forms and the
  // track gave no evidence of motion; before single ranges' rates were
  // evidence too, rest was latched at 2 m/s, the ranges-only filter held at
  // zero speed ran 21-62 m behind with a claimed 0.5 m, and re-aligned 35
  // times in 11 min (RMSE 7.06 m, MAX 67 m)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_blocked", 60);
  // THEN the cruise is seen as motion from the two anchors' range rates: no
  // re-alignment, the IMU filter takes over early and stays
  EXPECT_TRUE(s.run.all_finite);
  EXPECT_LE(s.run.diag.reinits, 1U);
  EXPECT_GT(s.inertial_share, 0.8);
  EXPECT_LT(s.rmse_h_m, 0.5);
  EXPECT_LT(s.max_h_m, 5.0);
}

TEST(NavigatorAlignment, APullAwayWithOneLineOfSightLeftKeepsItsNlosRangesByMomentMatching) {
  // GIVEN a tuning drive of the ground_blocked cell (seed 6): the car pulls
  // away from its parked start while two anchors are blocked and a third is
  // NLOS behind the body, so one anchor is left in line of sight. With every
  // NLOS range dropped, the ranges-only filter was unobservable across that
  // line of sight and slid along its range circle: 8.6 m off at 16 s (claimed
  // sigma 10 m), RMSE 0.335 m
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_blocked", 6);
  // THEN the NLOS anchor's long ranges inside the gate are fused by moment
  // matching of the NLOS mixture (docs/nlos.md "Long NLOS ranges on a starved
  // geometry") and hold the position across the line of sight
  expect_finite_without_hard_reset(s);
  EXPECT_LT(s.max_h_m, 4.0);
  EXPECT_LT(s.rmse_h_m, 0.25);
  EXPECT_GT(s.inside_2sigma, 0.95);
}

// Angle between the body z axes of two body->nav quaternions (scalar first) [deg].
double tilt_between_deg(const float q_est[4], const double q_true[4]) {
  const Vec3 z_est = quat_to_dcm(Quat(q_est[0], q_est[1], q_est[2], q_est[3])).col(2);
  const Vec3 z_true = quat_to_dcm(Quat(static_cast<Real>(q_true[0]), static_cast<Real>(q_true[1]),
                                       static_cast<Real>(q_true[2]), static_cast<Real>(q_true[3])))
                          .col(2);
  const Real c = z_est.dot(z_true) / (z_est.norm() * z_true.norm());
  return static_cast<double>(std::acos(std::fmin(std::fmax(c, Real(-1)), Real(1))) * Real(180) / kPi);
}

TEST(NavigatorAlignment, APullAwayIsNotLevelledAsANewRestBeforeTheHandOver) {
  // GIVEN a tuning drive of the outage cell (seed 8): the car stands 13 s, then
  // pulls away at about 2 m/s^2. The IMU window is as quiet during the steady
  // pull-away as at rest and the track's speed bound still reads zero, so
  // rest used to be confirmed again 0.9 s into it: the attitude was re-levelled
  // along the accelerating specific force, 10 deg nose-down, and handed to the
  // IMU filter with a 13 deg tilt error (road 30 s outage MAX 2.80 m)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("outage", 8, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  // WHEN the navigator runs over it
  const test::RunScore run = test::replay(so.rec, Params{});
  // THEN the IMU filter starts with the tilt the accelerometer bias leaves
  // (this IMU's about 0.5 m/s^2 horizontal bias: 3-4 deg), not the pull-away's
  double tilt_deg = -1.0;
  size_t k = 0;
  for (const test::ScoredOutput& o : run.outputs) {
    if (o.out.mode != NavMode::kInertial) continue;
    while (k + 1 < so.rec.truth.size() && so.rec.truth[k + 1].t_us <= o.out.t_us) ++k;
    ASSERT_TRUE(so.rec.truth[k].has_attitude);
    tilt_deg = tilt_between_deg(o.out.q_nav_body, so.rec.truth[k].q_nav_body);
    std::printf("outage:8: IMU filter from %.2f s, tilt error %.2f deg\n", static_cast<double>(o.out.t_us) * 1e-6, tilt_deg);
    break;
  }
  EXPECT_TRUE(run.all_finite);
  EXPECT_GE(tilt_deg, 0.0);
  EXPECT_LT(tilt_deg, 6.0);
}

// The two drives below were found with the first consistent fix as the start;
// the first-fix redundancy wait (docs/ekf.md "Initialisation") starts them
// 0.06-0.1 s later and elsewhere. Replayed with it off
// (test::first_consistent_fix_params), they keep testing their mechanism on
// the trajectory it was found on. With it on (measured, not hidden):
// ground_nlos:58 meets a gate lock-out at 33-47 s, MAX 3.1 m (1.1 m before, the
// same place); ground_hard:15 re-aligns twice and reaches 3.6 m at 43.8 s
// while standing, RMSE 0.85 m (0.82 m before). Since stop 48 (robust mode no
// longer drags a verified IMU filter by long ranges alone): default setting
// ground_nlos:58 0.548 m, MAX 2.25 m; ground_hard:15 0.666 m, MAX 4.29 m.
TEST(NavigatorAlignment, ACruiseAfterAPullAwayIsNotTakenForRestAgainWhileTheImuSawTheSpeedGained) {
  // GIVEN a tuning drive of the ground_nlos cell (seed 58): the car stands
  // 13 s, then pulls away to 5.4 m/s under 26 % NLOS episodes. The IMU window
  // is as quiet in the steady part of the pull-away as at rest and the NLOS
  // track shows no speed, so the rest check confirmed rest 1.5 s into it
  // (about 1.7 m/s) and levelled the attitude there; the IMU filter drifted up
  // to 3 m off later (RMSE 0.633 m, MAX 3.02 m). The same hole let a rest held
  // since the start resume once a cruise's specific force matched the rest's
  // again (held-out drive ground_blocked:77, 19 m off).
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_nlos", 58, test::first_consistent_fix_params());
  // THEN the velocity the IMU integrated since the rest (1.6 m/s at that
  // moment, against a drift bound of about 0.1 m/s) says the car is still
  // moving: no rest is confirmed or resumed in the cruise. (Bounds 0.5 m RMSE
  // and 2.5 m MAX, were 0.4 / 2.0: a regression of stop 48's escape change,
  // docs/nlos.md "Long ranges of a ready filter", on this replay with the
  // wait off: it drifts 2.1 m in the gate lock-out at 35-50 s, RMSE 0.451 m,
  // MAX 2.12 m, where it gave 0.248 / 1.11 m; the default setting went 0.685
  // / 3.13 m -> 0.548 / 2.25 m on this drive. The rest failure this test
  // guards against gave 0.633 m and MAX 3.02 m.)
  expect_finite_without_hard_reset(s);
  EXPECT_LT(s.max_h_m, 2.5);
  EXPECT_LT(s.rmse_h_m, 0.5);
  EXPECT_GT(s.inside_2sigma, 0.9);
}

TEST(NavigatorAlignment, ARestAfterAReAlignmentAllowsTheGyroDriftSinceTheReAlignmentOnly) {
  // GIVEN a tuning drive of the ground_hard cell (seed 15): the IMU filter
  // diverges and re-aligns at 47.07 s while the car pulls away (1.5 m/s). The
  // attitude handed to the alignment is the failed filter's of that moment,
  // but the rest check's tilt allowance counted the gyro drift since the
  // levelling at 12.3 s: rest was confirmed at once, the attitude re-levelled
  // in the pull-away and the next hand-over diverged again at 51.7 s
  // (2 re-alignments, RMSE 0.840 m)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_hard", 15, test::first_consistent_fix_params());
  // THEN the allowance grows from the re-alignment: no rest in the pull-away
  // and no second re-alignment
  expect_finite_without_hard_reset(s);
  EXPECT_LE(s.run.diag.reinits, 1U);
  EXPECT_LT(s.max_h_m, 4.0);
}

TEST(NavigatorAlignment, ARangesOnlyFilterStarvedByNlosEvidenceDuringAPullAwayRecovers) {
  // GIVEN a tuning drive of the ground_hard cell (seed 12): a pull-away to
  // 8.9 m/s under 47 % NLOS episodes while the ranges-only filter publishes; its
  // coarse NLOS evidence compares the ranges with its own lagging speed and
  // flags every range, its covariance passes the "not ready" bound, and the
  // robust mode used to watch ready filters only (measured with that: no range
  // fused for up to 15 s, RMSE 10.4 m, MAX 43 m, 17 re-alignments)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_hard", 12);
  // THEN the starved filter enters the robust mode too and keeps its ranges
  expect_finite_without_hard_reset(s);
  EXPECT_LT(s.rmse_h_m, 2.0);
  EXPECT_LT(s.max_h_m, 20.0);
}

TEST(NavigatorAlignment, AMulticopterHandsOverTheLevellingsGyroBiasWithTheUncertaintyOfItsMove) {
  // GIVEN a tuning drive of the outage cell (seed 45): a multicopter levelled
  // at rest, then flew while the ranges-only filter published; the levelling's
  // bias integral moved the gyro bias by about 0.07 rad/s, and the IMU filter
  // that took over shortly before a long UWB outage was handed that bias with
  // the rest window's 2 mrad/s: it coasted through the outage 53 m off at a
  // claimed 13 m (RMSE 6.52 m, MAX 56.9 m, 81 % inside the claimed 2 sigma)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("outage", 45);
  // THEN the bias's move is handed over as its uncertainty: the ranges correct
  // it before the outage, and what remains is in the claimed sigma (which
  // filter publishes when depends on the platform's rounding: measured on
  // x86-64 the IMU filter takes over, under qemu-aarch64 it does not; both
  // must stay honest)
  expect_finite_without_hard_reset(s);
  EXPECT_GT(s.inside_2sigma, 0.9);
  EXPECT_LT(s.rmse_h_m, 4.0);
  EXPECT_LT(s.max_h_m, 40.0);
}

TEST(NavigatorAlignment, AMulticopterTurningOnTheSpotIsNotLevelledAsRestNorHandedItsTurnRateAsGyroBias) {
  // GIVEN a tuning drive of the outage cell (seed 28): a multicopter levelled
  // at rest hovers and turns on the spot, its yaw rate ramping up to 0.8 rad/s;
  // the rest check held "rest" through the ramp (quiet window, unchanged
  // specific force, still track), the levelling took the turn rate for the
  // gyro bias at the rest window's 2 mrad/s, and the IMU filter that took over
  // turned its yaw away at that rate until a re-alignment (98.6 % of the x/y
  // errors inside the claimed 2 sigma, 1 re-alignment)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("outage", 28);
  // THEN a held rest ends when the mean gyro moves, a later rest must find the
  // bias the first one measured, and a flying multicopter is handed over with
  // its complementary filter's tilt, not the rest window's: no filter is
  // started on a turn rate, and what is published stays inside its claim
  expect_finite_without_hard_reset(s);
  EXPECT_EQ(s.run.diag.reinits, 0U);
  EXPECT_GT(s.inside_2sigma, 0.99);
  EXPECT_LT(s.rmse_h_m, 4.0);
}

TEST(NavigatorAlignment, TheRangesOnlyFilterOfAPullAwayTurnsItsVelocityWithTheGyro) {
  // GIVEN tuning drive ground_hard:31: a car pulls away at 12 s and turns while
  // it aligns, 2.7 Hz per anchor, anchor 1 blocked, anchors 2 and 3 mostly NLOS;
  // the ranges-only filter kept its velocity straight through the turn, fused
  // the near anchor and the far one, slid 14 m off at a claimed 0.5-0.6 m, and
  // the IMU filter took over 2-3 m off (RMSE 1.66 m, MAX 15.7 m)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_hard", 31);
  // THEN the gyro's turn about the vertical turns the ranges-only velocity with
  // the body (a car goes where it points): the pull-away stays within metres
  expect_finite_without_hard_reset(s);
  EXPECT_LT(s.rmse_h_m, 0.6);
  EXPECT_LT(s.max_h_m, 4.0);
  EXPECT_GT(s.inside_2sigma, 0.85);
}

TEST(NavigatorAlignment, AChordLongerThanTheVehicleCanDriveGivesNoStartHeading) {
  // GIVEN a tuning drive of the ground_blocked cell (seed 57): a car pulls
  // away on a 293 m road whose four anchors stand near one line; 2 s into the
  // pull-away one LS fix lands on the mirror side of that line, 27 m off, and
  // the track's chord to it (27 m in 0.25 s at 2.7 m/s) gave the start heading
  // 88 degrees wrong at a claimed 4 degrees: the IMU filter ran 30 m off at a
  // claimed 1 m and re-aligned twice (RMSE 1.90 m, MAX 33 m)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_blocked", 57);
  // THEN no heading is taken from a track with such a chord: the next chords
  // give it, and the IMU filter takes over and stays
  EXPECT_TRUE(s.run.all_finite);
  EXPECT_EQ(s.run.diag.reinits, 0U);
  EXPECT_GT(s.inertial_share, 0.9);
  EXPECT_LT(s.rmse_h_m, 0.5);
  EXPECT_LT(s.max_h_m, 5.0);
}

TEST(NavigatorAlignment, TheVerticalBalanceSurvivesTheTurnThatToldAConsumerAccelerometerBiasFromTilt) {
  // GIVEN a tuning drive of the outage cell (seed 68): a consumer IMU with a
  // 1.2 m/s^2 horizontal accelerometer bias, levelled at rest (5.6 deg of roll
  // taken for that bias), 25 s of straight road, then a U-turn at 39-42 s that
  // tells the bias from the tilt, and a 10 s UWB outage from 47.5 s at 8.7 m/s.
  // The bias crossed the tangent plane on which the filter had learnt the
  // vertical balance: 0.04 m/s^2 of vertical acceleration under a bias sigma of
  // 1 mm/s^2 climbed at 0.14 m/s, which the vertical NHC turned into pitch and
  // along-track drift (2.82 m after 10 s, 20.9 % of the outage's x and y
  // errors inside 2 sigma)
  sim::SimOutput so;
  std::string err;
  ASSERT_EQ(sim::simulate_family("outage", 68, sim::FamilyOptions{}, so, &err), Status::kOk) << err;
  std::vector<eval::OutageSpan> spans;
  const auto meta = so.rec.meta.find("sim_outages_s");
  ASSERT_TRUE(meta != so.rec.meta.end() && eval::parse_outage_list(meta->second, spans));
  ASSERT_FALSE(spans.empty());
  const double t0_s = spans.front().start_s;
  const double t1_s = spans.front().end_s;
  ASSERT_NEAR(t0_s, 47.5, 0.1);
  // WHEN the navigator runs over it
  const test::RunScore run = test::replay(so.rec, Params{});
  // THEN the car's vertical velocity stays near zero after the turn, and the
  // outage coasts inside its claimed 2 sigma
  double max_vz_mps = 0.0, max_h_m = 0.0;
  size_t n = 0, inside = 0;
  for (const test::ScoredOutput& o : run.outputs) {
    const double t_s = static_cast<double>(o.out.t_us) * 1e-6;
    if (o.out.mode != NavMode::kInertial || t_s < 43.0 || t_s >= t1_s) continue;
    max_vz_mps = std::max(max_vz_mps, std::fabs(static_cast<double>(o.out.vel_nav_mps.z)));
    if (t_s < t0_s || !o.has_truth) continue;
    max_h_m = std::max(max_h_m, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
    inside += (std::fabs(o.err_nav_m[0]) <= 2.0 * static_cast<double>(o.out.pos_sigma_m.x)) +
              (std::fabs(o.err_nav_m[1]) <= 2.0 * static_cast<double>(o.out.pos_sigma_m.y));
    ++n;
  }
  std::printf("outage:68: |vz| <= %.3f m/s from 43 s, outage MAX %.2f m, %.1f %% inside 2 sigma (%zu epochs)\n", max_vz_mps,
              max_h_m, n > 0 ? 50.0 * static_cast<double>(inside) / static_cast<double>(n) : 0.0, n);
  EXPECT_TRUE(run.all_finite);
  ASSERT_GT(n, 900U);
  EXPECT_LT(max_vz_mps, 0.08);
  EXPECT_LT(max_h_m, 1.5);
  EXPECT_GE(static_cast<double>(inside), 0.9 * 2.0 * static_cast<double>(n));
}

TEST(NavigatorRobustMode, TwoNlosAnchorsLeftDoNotPullTheFilterInThroughTheirLineOfSightLookingRanges) {
  // GIVEN a tuning drive of the ground_blocked cell (seed 58): for 10 s two
  // anchors are blocked and the two heard are NLOS (one 1.5-3 m long). Nothing
  // passes the gate, the gating layer's robust mode starts, and it admitted
  // every range whose own first-path/total power gap did not flag it, at 4 R:
  // the NLOS anchor's occasional line-of-sight-looking gaps let 2 m long
  // ranges in, an integrity failure inflated the covariance and the filter
  // jumped 3.5 m (RMSE 0.155 m)
  // WHEN the navigator runs over it
  const DriveScore s = run_family_drive("ground_blocked", 58);
  // THEN robust mode weighs such a range by its pair's channel-only NLOS
  // episode, R / (1 - p) (docs/nlos.md item 6), and the IMU filter holds
  expect_finite_without_hard_reset(s);
  EXPECT_LT(s.max_h_m, 1.5);
  EXPECT_LT(s.rmse_h_m, 0.12);
  EXPECT_GT(s.inside_2sigma, 0.95);
}

}  // namespace
}  // namespace uwbnav
