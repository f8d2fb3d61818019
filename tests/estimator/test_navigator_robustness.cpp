// Navigator failure mechanisms found on real recordings and tuning drives,
// reproduced in simulation: an NLOS range in the initial fix (excluded when
// redundant ranges allow, sized by its residuals when not), a gross outlier
// there that its pair's previous range contradicts (left out), the mirror solution
// of a first 3-D fix under anchors at one height, and process noise that follows
// the IMU's measured noise floor (a coasting filter that claims too small a
// sigma is locked out by its own gate afterwards).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "tests/estimator/nav_harness.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

TEST(NavigatorRobustness, InitialFixRejectsNlosRange) {
  // GIVEN a vehicle at rest among 5 planar anchors, one of which ranges 2.5 m long (NLOS)
  SiteConfig site;
  const float ax[5] = {0, 30, 30, 0, 15};
  const float ay[5] = {0, 0, 20, 20, -5};
  for (int i = 0; i < 5; ++i) ASSERT_EQ(site.add_anchor(static_cast<uint16_t>(i + 1), Vec3f{ax[i], ay[i], 1.5F}), Status::kOk);
  ASSERT_EQ(site.add_tag(0, Vec3f{0.0F, 0.0F, 1.5F}), Status::kOk);
  Navigator nav;
  ASSERT_EQ(nav.configure(site, Params{}), Status::kOk);
  const double truth[2] = {12.0, 7.0};
  std::mt19937 gen(5);
  std::normal_distribution<float> noise(0.0F, 0.05F);
  for (uint64_t k = 1; k <= 100; ++k) {
    const uint64_t t = k * 10000;
    ImuSample imu;
    imu.t_us = t;
    imu.accel_body_mps2 = Vec3f{0.0F, 0.0F, 9.80665F};
    ASSERT_EQ(nav.on_imu(imu), Status::kOk);
    UwbRange r;
    r.t_us = t + 3000;
    const size_t a = k % 5;
    r.anchor_id = static_cast<uint16_t>(a + 1);
    r.tag_id = 0;
    const double dx = truth[0] - static_cast<double>(ax[a]);
    const double dy = truth[1] - static_cast<double>(ay[a]);
    r.range_m = static_cast<float>(std::sqrt(dx * dx + dy * dy)) + noise(gen) + (a == 2 ? 2.5F : 0.0F);
    (void)nav.on_range(r);
  }
  // WHEN the first fixes are made, THEN the NLOS range is excluded and the fix is close to the truth
  const NavOutput o = nav.output(1010000);
  const double err = std::hypot(static_cast<double>(o.pos_nav_m.x) - truth[0], static_cast<double>(o.pos_nav_m.y) - truth[1]);
  std::printf("initial fix with one NLOS range: error %.3f m, status %s\n", err, nav_status_name(o.status));
  EXPECT_LT(err, 0.3);
}

// A range of tag 0 from anchor index a (id a + 1) at (ax[a], ay[a]) to a tag
// at (x, y) in the anchors' plane, plus extra_m (noise, NLOS, outlier).
UwbRange planar_range(uint64_t t_us, size_t a, const float* ax, const float* ay, double x, double y, float extra_m) {
  UwbRange r;
  r.t_us = t_us;
  r.anchor_id = static_cast<uint16_t>(a + 1);
  r.tag_id = 0;
  r.range_m = static_cast<float>(std::hypot(x - static_cast<double>(ax[a]), y - static_cast<double>(ay[a]))) + extra_m;
  return r;
}

// A gross outlier in the latest range of a pair whose anchor alone fixes one
// direction cannot be told from the truth by the first fix's own test (low
// redundancy): drive ground_nlos:62 (tuning seeds 61-99), a road with its four anchors in a
// zig-zag, started 4.3 m off at a claimed 0.8 m from one range 3.6 m short.
TEST(NavigatorRobustness, FirstFixLeavesOutAPairWhoseLatestRangeJumpedByMoreThanNoiseAndMotionAllow) {
  // GIVEN a car at rest near the first of four road anchors (nlos_62's layout),
  // whose second range from that anchor is 3.6 m short, the fourth anchor heard last
  SiteConfig site;
  const float ax[4] = {0.0F, 67.4F, 139.0F, 228.5F};
  const float ay[4] = {-2.7F, 17.9F, -2.7F, 17.9F};
  for (int i = 0; i < 4; ++i) ASSERT_EQ(site.add_anchor(static_cast<uint16_t>(i + 1), Vec3f{ax[i], ay[i], 1.8F}), Status::kOk);
  ASSERT_EQ(site.add_tag(0, Vec3f{0.0F, 0.0F, 1.8F}), Status::kOk);
  site.has_imu = false;
  Navigator nav;
  ASSERT_EQ(nav.configure(site, Params{}), Status::kOk);
  const double truth[2] = {3.8, 10.8};
  std::mt19937 gen(62);
  std::normal_distribution<float> noise(0.0F, 0.1F);
  const size_t order[5] = {0, 1, 2, 0, 3};  // then round robin
  double first_err_m = -1;
  double first_sigma_m = -1;
  for (uint64_t k = 0; k < 200 && first_err_m < 0; ++k) {
    const uint64_t t = 20000 + k * 22000;
    const size_t a = k < 5 ? order[k] : k % 4;
    (void)nav.on_range(planar_range(t, a, ax, ay, truth[0], truth[1], noise(gen) + (k == 3 ? -3.6F : 0.0F)));
    const NavOutput o = nav.output(t);
    if (std::isfinite(o.pos_nav_m.x)) {
      first_err_m = std::hypot(static_cast<double>(o.pos_nav_m.x) - truth[0], static_cast<double>(o.pos_nav_m.y) - truth[1]);
      first_sigma_m = std::hypot(static_cast<double>(o.pos_sigma_m.x), static_cast<double>(o.pos_sigma_m.y));
    }
  }
  std::printf("first fix after a 3.6 m short range: error %.3f m, claimed sigma_h %.3f m\n", first_err_m, first_sigma_m);
  // THEN the first fix waits for that pair to agree again and starts near the truth, inside its claim
  ASSERT_GE(first_err_m, 0.0);
  EXPECT_LT(first_err_m, 1.0);
  EXPECT_LT(first_err_m, 2.0 * first_sigma_m);
}

TEST(NavigatorRobustness, FirstFixOfAVehicleAlreadyMovingFastComesAtTheEndOfTheRedundancyWait) {
  // GIVEN a car that is at 12 m/s from its first range on: the two anchors
  // behind it see their ranges change faster than ekf.init_speed and noise
  // allow for, so those pairs "jump"; its first range 2 m long (NLOS), so the
  // first round of ranges gives no fix
  SiteConfig site;
  const float ax[4] = {0.0F, 100.0F, 100.0F, 0.0F};
  const float ay[4] = {0.0F, 0.0F, 40.0F, 40.0F};
  for (int i = 0; i < 4; ++i) ASSERT_EQ(site.add_anchor(static_cast<uint16_t>(i + 1), Vec3f{ax[i], ay[i], 1.8F}), Status::kOk);
  ASSERT_EQ(site.add_tag(0, Vec3f{0.0F, 0.0F, 1.8F}), Status::kOk);
  site.has_imu = false;
  Navigator nav;
  ASSERT_EQ(nav.configure(site, Params{}), Status::kOk);
  double first_t_s = -1;
  for (uint64_t k = 0; k < 200 && first_t_s < 0; ++k) {
    const uint64_t t = 20000 + k * 22000;
    const double x = 10.0 + 12.0 * static_cast<double>(t) * 1e-6;
    (void)nav.on_range(planar_range(t, k % 4, ax, ay, x, 20.0, k == 0 ? 2.0F : 0.0F));
    if (std::isfinite(nav.output(t).pos_nav_m.x)) first_t_s = static_cast<double>(t) * 1e-6;
  }
  std::printf("first fix of a car at 12 m/s: %.2f s\n", first_t_s);
  // WHEN its jumping pairs are left out of the first fix
  // THEN only for the redundancy wait (1 s): the fix comes at its end (the
  // delay is the rule's cost here: 0.11 s without it)
  EXPECT_GT(first_t_s, 0.9);
  EXPECT_LT(first_t_s, 1.2);
}

// A first fix from just enough anchors cannot leave an NLOS range out; where
// the site has more anchors it waits (ekf.init_redundancy_wait) for two
// redundant ranges and excludes it (tuning drives air_indoor:8 and ground_blocked:2
// started 3.2 m off at a claimed 0.56 / 0.78 m before).
struct FirstFixRun {
  double err_m = -1;      // horizontal error of the first published position
  double sigma_h_m = -1;  // its claimed horizontal 1-sigma
  double t_s = -1;        // when it was published
};

FirstFixRun first_fix_with_one_nlos_anchor(float nlos_bias_m, size_t num_anchors, const Params& params) {
  SiteConfig site;
  const float ax[6] = {0, 30, 30, 0, 15, 15};
  const float ay[6] = {0, 0, 20, 20, -5, 25};
  for (size_t i = 0; i < num_anchors; ++i) {
    EXPECT_EQ(site.add_anchor(static_cast<uint16_t>(i + 1), Vec3f{ax[i], ay[i], 1.5F}), Status::kOk);
  }
  EXPECT_EQ(site.add_tag(0, Vec3f{0.0F, 0.0F, 1.5F}), Status::kOk);
  site.has_imu = false;
  Navigator nav;
  EXPECT_EQ(nav.configure(site, params), Status::kOk);
  const double truth[2] = {12.0, 7.0};
  // Round robin, the NLOS anchor (index 2) among the first three heard.
  const size_t order[6] = {0, 2, 1, 3, 4, 5};
  FirstFixRun run;
  for (uint64_t k = 0; k < 600 && run.err_m < 0; ++k) {
    const uint64_t t = 10000 + k * 10000;
    const size_t a = order[k % num_anchors];
    UwbRange r;
    r.t_us = t;
    r.anchor_id = static_cast<uint16_t>(a + 1);
    r.tag_id = 0;
    const double dx = truth[0] - static_cast<double>(ax[a]);
    const double dy = truth[1] - static_cast<double>(ay[a]);
    r.range_m = static_cast<float>(std::sqrt(dx * dx + dy * dy)) + (a == 2 ? nlos_bias_m : 0.0F);
    (void)nav.on_range(r);
    const NavOutput o = nav.output(t);
    if (std::isfinite(o.pos_nav_m.x)) {
      run.err_m = std::hypot(static_cast<double>(o.pos_nav_m.x) - truth[0], static_cast<double>(o.pos_nav_m.y) - truth[1]);
      run.sigma_h_m = std::hypot(static_cast<double>(o.pos_sigma_m.x), static_cast<double>(o.pos_sigma_m.y));
      run.t_s = static_cast<double>(t) * 1e-6;
    }
  }
  std::printf("%zu anchors, NLOS %.1f m: first fix at %.2f s, error %.3f m, claimed sigma_h %.3f m\n", num_anchors,
              static_cast<double>(nlos_bias_m), run.t_s, run.err_m, run.sigma_h_m);
  return run;
}

TEST(NavigatorRobustness, FirstFixWaitsForRedundantRangesAndComesCloserThanFromJustEnough) {
  // GIVEN a vehicle at rest among 5 planar anchors, the NLOS one among the first three heard
  for (float bias : {0.5F, 1.0F, 2.0F, 4.0F}) {
    // WHEN the first fix is made with the redundancy wait and without it
    const FirstFixRun waited = first_fix_with_one_nlos_anchor(bias, 5, Params{});
    const FirstFixRun first = first_fix_with_one_nlos_anchor(bias, 5, test::first_consistent_fix_params());
    // THEN the waited fix holds the error inside its claim, is no worse, and
    // where the three first ranges were consistent enough to be taken (0.5 and
    // 1 m) it is closer: the five ranges halve what the NLOS excess bends
    EXPECT_GT(waited.t_s, 0.0);
    EXPECT_LT(waited.t_s, 0.1);
    EXPECT_LE(waited.err_m, 2.0 * waited.sigma_h_m);
    EXPECT_LE(waited.err_m, first.err_m + 1e-3);
    if (bias < 1.5F) {
      EXPECT_LT(waited.err_m, 0.6 * first.err_m);
    }
    // AND an excess the test can single out (2 and 4 m) is left out
    if (bias > 1.5F) {
      EXPECT_LT(waited.err_m, 0.05);
    }
  }
}

TEST(NavigatorRobustness, FirstFixAmongJustEnoughAnchorsComesAfterTheWaitWithTheSizeItsResidualsShow) {
  // GIVEN 4 planar anchors, one of them NLOS for good: no consistent subset with redundancy exists
  for (float bias : {2.0F, 4.0F}) {
    // WHEN ekf.init_redundancy_wait (1 s) has passed, THEN the rejected fix is published,
    // its claim scaled by its residuals so that it covers the error
    const FirstFixRun r = first_fix_with_one_nlos_anchor(bias, 4, Params{});
    EXPECT_GE(r.t_s, 1.0);
    EXPECT_LT(r.t_s, 1.1);
    EXPECT_LE(r.err_m, 2.0 * r.sigma_h_m);
  }
}

struct MirrorCount {
  int on_mirror = 0;          // first fixes more than 1.5 m above the truth
  int dishonest = 0;          // first fixes with |z error| > 3 sigma_z
  size_t mirror_counted = 0;  // NavDiagnostics::start_height_switches (mirror or 2-D at the start height), summed
};

// A 9 x 6 m room with 6 anchors at 1.4-2.8 m (as the air_indoor cell), a
// multicopter standing on the floor (tag at 0.1 m) at 40 places, 0.1 m range
// noise, each anchor's ranges long by its excess_m (NLOS): the first fix of each.
MirrorCount first_fixes_on_the_floor(const Params& params, const float (&excess_m)[6]) {
  const float ax[6] = {0.2F, 4.5F, 8.8F, 8.8F, 4.5F, 0.2F};
  const float ay[6] = {0.2F, 0.2F, 0.2F, 5.8F, 5.8F, 5.8F};
  const float az[6] = {1.4F, 2.8F, 1.9F, 2.3F, 1.5F, 2.6F};
  std::mt19937 gen(11);
  std::uniform_real_distribution<float> ux(1.0F, 8.0F);
  std::uniform_real_distribution<float> uy(1.0F, 5.0F);
  std::normal_distribution<float> noise(0.0F, 0.1F);
  MirrorCount c;
  for (int trial = 0; trial < 40; ++trial) {
    SiteConfig site;
    for (int i = 0; i < 6; ++i) {
      EXPECT_EQ(site.add_anchor(static_cast<uint16_t>(i + 1), Vec3f{ax[i], ay[i], az[i]}), Status::kOk);
    }
    EXPECT_EQ(site.add_tag(0, Vec3f{0.0F, 0.0F, 0.0F}), Status::kOk);
    site.platform = Platform::kAir;
    Navigator nav;
    EXPECT_EQ(nav.configure(site, params), Status::kOk);
    const double truth[3] = {static_cast<double>(ux(gen)), static_cast<double>(uy(gen)), 0.1};
    // WHEN the first fix is made from the ranges of one round
    NavOutput o;
    o.pos_nav_m.x = std::nanf("");
    for (uint64_t k = 0; k < 60 && !std::isfinite(o.pos_nav_m.x); ++k) {
      const size_t a = k % 6;
      ImuSample imu;
      imu.t_us = 8000 + k * 8000;
      imu.accel_body_mps2 = Vec3f{0.0F, 0.0F, 9.80665F};
      EXPECT_EQ(nav.on_imu(imu), Status::kOk);
      UwbRange r;
      r.t_us = 10000 + k * 8000;
      r.anchor_id = static_cast<uint16_t>(a + 1);
      r.tag_id = 0;
      const double dx = truth[0] - static_cast<double>(ax[a]);
      const double dy = truth[1] - static_cast<double>(ay[a]);
      const double dz = truth[2] - static_cast<double>(az[a]);
      r.range_m = static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz)) + noise(gen) + excess_m[a];
      (void)nav.on_range(r);
      o = nav.output(r.t_us);
    }
    EXPECT_TRUE(std::isfinite(o.pos_nav_m.x));
    const double ez = static_cast<double>(o.pos_nav_m.z) - truth[2];
    c.on_mirror += ez > 1.5 ? 1 : 0;
    c.dishonest += std::fabs(ez) > 3.0 * static_cast<double>(o.pos_sigma_m.z) ? 1 : 0;
    c.mirror_counted += nav.diagnostics().start_height_switches;
  }
  return c;
}

TEST(NavigatorRobustness, FirstFixOfAMulticopterOnTheFloorIsBelowItsAnchorsNotOnTheMirrorAbove) {
  // GIVEN a multicopter standing on the floor below its anchors, 40 places
  for (int wait = 0; wait < 2; ++wait) {
    // WHEN the first fix comes from the first 4 ranges (redundancy wait off) or from all 6
    const Params params = wait == 0 ? test::first_consistent_fix_params() : Params{};
    const MirrorCount c = first_fixes_on_the_floor(params, {0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F});
    std::printf("redundancy wait %s: 40 first fixes on the floor, %d on the mirror above the anchors, %d with "
                "|z error| > 3 sigma_z, %zu switched to the mirror or the 2-D fix at the start height\n",
                wait == 0 ? "off" : "on", c.on_mirror, c.dishonest, c.mirror_counted);
    // THEN none starts on the mirror above the anchors. (Without NLOS the
    // fix is already the right mode here: the switches counted before were
    // the mirror solve converging back onto the fix, no longer counted; the
    // test below makes the modes switch.)
    EXPECT_EQ(c.on_mirror, 0);
    EXPECT_EQ(c.dishonest, 0);
  }
}

TEST(NavigatorRobustness, FirstFixOnTheFloorAmongNlosLowAnchorsLeavesARangeOutRatherThanRiseToTheMirror) {
  // GIVEN the multicopter on the floor of the same room, the ranges of its
  // three lowest anchors (1.4-1.9 m) long by 0.4-1.2 m: NLOS excess that all
  // six ranges explain best with a fix high above the anchors
  const float excess_m[6] = {0.8F, 0.0F, 0.4F, 0.0F, 1.2F, 0.0F};
  // WHEN the first fix is made from all six (redundancy wait on)
  const MirrorCount c = first_fixes_on_the_floor(Params{}, excess_m);
  std::printf("low anchors NLOS: 40 first fixes on the floor, %d on the mirror above the anchors, %d with "
              "|z error| > 3 sigma_z, %zu switched mode\n",
              c.on_mirror, c.dishonest, c.mirror_counted);
  // THEN the modes that leave a range out compete too (each range left out
  // costs a 3-sigma residual): most first fixes switch from the fix of all
  // six ranges (36 of 40 measured), and at most an eighth start on the
  // mirror above (4 measured; 39 of 40 did when only modes with the same
  // ranges competed)
  EXPECT_GT(c.mirror_counted, 20U);
  EXPECT_LE(c.on_mirror, 5);
  // AND the modes passed over widen the claim of a close call: at most 2 of
  // 40 with the height error beyond 3 sigma_z (1 measured; 4 with the mode
  // choice alone, 39 before both)
  EXPECT_LE(c.dishonest, 2);
}

TEST(NavigatorRobustness, UwbOutageSigmaCoversDriftWithVibratingImu) {
  // GIVEN the outage drive with strong white vibration on the accelerometers
  // (0.03 m/s^2/sqrt(Hz), 15x the data-sheet density of param 101)
  dataset::Recording rec;
  std::string err;
  ASSERT_EQ(sim::simulate("parking_outages", 24, rec, &err), Status::kOk) << err;
  std::mt19937 gen(24);
  std::normal_distribution<float> vib(0.0F, 0.3F);  // per sample at 100 Hz
  for (auto& s : rec.imu) {
    s.accel_body_mps2.x += vib(gen);
    s.accel_body_mps2.y += vib(gen);
    s.accel_body_mps2.z += vib(gen);
  }
  // WHEN it coasts through the 10 s and 15 s outages
  const test::RunScore s = test::replay(rec, Params{});
  EXPECT_TRUE(s.all_finite);
  EXPECT_EQ(s.diag.reinits, 0U);
  const double starts[2] = {80, 120};
  const double ends[2] = {90, 135};
  for (int k = 0; k < 2; ++k) {
    double err_end = 0;
    double sigma_end = 0;
    for (const auto& o : s.outputs) {
      const double t = static_cast<double>(o.out.t_us) * 1e-6;
      if (t > starts[k] && t < ends[k] && o.has_truth) {
        err_end = std::hypot(o.err_nav_m[0], o.err_nav_m[1]);
        sigma_end = std::hypot(static_cast<double>(o.out.pos_sigma_m.x), static_cast<double>(o.out.pos_sigma_m.y));
      }
    }
    double err_after = 0;
    for (const auto& o : s.outputs) {
      const double t = static_cast<double>(o.out.t_us) * 1e-6;
      if (t > ends[k] + 3 && t < ends[k] + 5 && o.has_truth) {
        err_after = std::max(err_after, std::hypot(o.err_nav_m[0], o.err_nav_m[1]));
      }
    }
    std::printf("vibrating IMU, outage %.0f s: error at its end %.3f m, claimed 1-sigma %.3f m, 3-5 s later %.3f m\n",
                ends[k] - starts[k], err_end, sigma_end, err_after);
    // THEN the claimed sigma grows with the measured noise and covers the
    // drift, and the gate lets the ranges pull the filter back
    EXPECT_LT(err_end, 3.0 * sigma_end);
    EXPECT_LT(err_after, 0.5);
  }
}

// Microsecond parameters reach the filter as integers without a float -> uint64_t
// conversion (soft double on the M4F): truncated, 0 for non-positive or NaN values,
// clamped instead of undefined above the uint32_t range.
TEST(ParamUs, ConvertsTruncatesAndClampsMicrosecondParameters) {
  EXPECT_EQ(param_us(200000.0F), 200000U);
  EXPECT_EQ(param_us(1.5F * 1e6F), 1500000U);
  EXPECT_EQ(param_us(999.9F), 999U);
  EXPECT_EQ(param_us(0.0F), 0U);
  EXPECT_EQ(param_us(-3.0F), 0U);
  EXPECT_EQ(param_us(std::nanf("")), 0U);
  EXPECT_EQ(param_us(1e12F), 4000000000U);
  EXPECT_EQ(param_us(INFINITY), 4000000000U);
  size_t checked = 0;
  for (size_t i = 0; i < kNumParams; ++i) {
    const ParamDef& d = kParamDefs[i];
    const std::string unit(d.unit);
    if (unit == "us") {
      EXPECT_EQ(param_us(d.max), static_cast<uint64_t>(d.max)) << d.name << ": maximum beyond the uint32_t path";
      ++checked;
    } else if (unit == "s") {
      EXPECT_EQ(param_us(d.max * 1e6F), static_cast<uint64_t>(d.max * 1e6F)) << d.name << ": maximum beyond the uint32_t path";
      ++checked;
    }
  }
  EXPECT_GT(checked, 5U);
}

}  // namespace
}  // namespace uwbnav
