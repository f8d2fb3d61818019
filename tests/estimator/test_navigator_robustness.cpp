// Navigator failure mechanisms found on real recordings, reproduced in
// simulation: an NLOS range in the initial fix, and process noise that follows
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
