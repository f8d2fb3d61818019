// Protects seed 001 RAIM: no exclusion on consistent ranges, the faulty range
// located and excluded, no location attempt without redundancy (dof 1), and
// repeated exclusion of two faults when redundancy remains; thresholds down
// to the smallest allowed false-alarm probability.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "estimator/nlos/raim.hpp"

namespace uwbnav {
namespace {

constexpr Vec3f kTag{20.0F, 15.0F, 1.7F};

LsRange make_range(float x, float y, float z, float bias_m, float noise_m) {
  LsRange r;
  r.anchor_pos_nav_m = Vec3f{x, y, z};
  const float dx = kTag.x - x;
  const float dy = kTag.y - y;
  const float dz = kTag.z - z;
  r.range_m = std::sqrt(dx * dx + dy * dy + dz * dz) + bias_m + noise_m;
  r.sigma_m = 0.1F;
  return r;
}

LsOptions planar_options() {
  LsOptions o;
  o.two_d = true;
  o.known_z_m = kTag.z;
  o.has_initial_guess = true;
  o.initial_guess_nav_m = Vec3f{18.0F, 16.0F, kTag.z};
  return o;
}

RaimThresholds thresholds() {
  RaimThresholds t;
  raim_compute_thresholds(1e-3F, 1e-3F, t);
  return t;
}

TEST(Raim, ThresholdsFromFalseAlarmProbability) {
  const RaimThresholds t = thresholds();
  EXPECT_NEAR(t.chi2_by_dof[1], 10.8276F, 1e-3F);
  EXPECT_NEAR(t.chi2_by_dof[2], 13.8155F, 1e-3F);
  EXPECT_NEAR(t.local, 3.2905F, 1e-3F);
}

TEST(Raim, ThresholdsAtSmallestFalseAlarmProbabilityKeepTheTail) {
  // gate.raim_pfa = 1e-9 (its minimum): 1 - 1e-9 rounds to 1 in float, so the
  // thresholds must come from the tail probability itself (scipy chi2.isf /
  // norm.isf: 37.32489, 41.44653, 75.65418; local 6.109410 at 5e-10).
  RaimThresholds t;
  raim_compute_thresholds(1e-9F, 1e-9F, t);
  EXPECT_NEAR(t.chi2_by_dof[1], 37.32489F, 1e-4F);
  EXPECT_NEAR(t.chi2_by_dof[2], 41.44653F, 1e-4F);
  EXPECT_NEAR(t.chi2_by_dof[16], 75.65418F, 2e-4F);
  EXPECT_NEAR(t.local, 6.109410F, 1e-5F);
}

TEST(Raim, ConsistentEpochKeepsAllRanges) {
  std::mt19937 rng(3);
  std::normal_distribution<float> n(0.0F, 0.05F);
  const LsRange r[6] = {make_range(0, 0, 0.2F, 0, n(rng)),   make_range(60, 0, 0.2F, 0, n(rng)),
                        make_range(60, 40, 0.2F, 0, n(rng)), make_range(0, 40, 0.2F, 0, n(rng)),
                        make_range(30, -5, 0.3F, 0, n(rng)), make_range(30, 45, 0.3F, 0, n(rng))};
  RaimResult res;
  ASSERT_TRUE(ok(raim_run(r, 6, planar_options(), thresholds(), res)));
  EXPECT_TRUE(res.available);
  EXPECT_TRUE(res.consistent);
  EXPECT_EQ(res.num_excluded, 0);
  EXPECT_NEAR(res.fix.pos_nav_m.x, kTag.x, 0.2F);
}

TEST(Raim, SingleNlosRangeIsLocatedAndExcluded) {
  const LsRange r[5] = {make_range(0, 0, 0.2F, 0, 0.02F), make_range(60, 0, 0.2F, 0, -0.03F),
                        make_range(60, 40, 0.2F, 1.5F, 0.0F), make_range(0, 40, 0.2F, 0, 0.01F),
                        make_range(30, -5, 0.3F, 0, -0.02F)};
  RaimResult res;
  ASSERT_TRUE(ok(raim_run(r, 5, planar_options(), thresholds(), res)));
  EXPECT_TRUE(res.excluded[2]);
  EXPECT_EQ(res.num_excluded, 1);
  EXPECT_TRUE(res.consistent);
  EXPECT_NEAR(res.fix.pos_nav_m.x, kTag.x, 0.1F);
  EXPECT_NEAR(res.fix.pos_nav_m.y, kTag.y, 0.1F);
}

TEST(Raim, TwoFaultsExcludedWhileRedundancyRemains) {
  const LsRange r[6] = {make_range(0, 0, 0.2F, 2.0F, 0.0F),   make_range(60, 0, 0.2F, 0, 0.01F),
                        make_range(60, 40, 0.2F, 1.2F, 0.0F), make_range(0, 40, 0.2F, 0, -0.01F),
                        make_range(30, -5, 0.3F, 0, 0.02F),   make_range(30, 45, 0.3F, 0, 0.0F)};
  RaimResult res;
  ASSERT_TRUE(ok(raim_run(r, 6, planar_options(), thresholds(), res)));
  EXPECT_TRUE(res.excluded[0]);
  EXPECT_TRUE(res.excluded[2]);
  EXPECT_EQ(res.num_excluded, 2);
  EXPECT_TRUE(res.consistent);
}

TEST(Raim, FaultWithOneDegreeOfFreedomIsDetectedButNotLocated) {
  const LsRange r[3] = {make_range(0, 0, 0.2F, 0, 0), make_range(60, 0, 0.2F, 2.0F, 0),
                        make_range(30, 40, 0.2F, 0, 0)};
  RaimResult res;
  ASSERT_TRUE(ok(raim_run(r, 3, planar_options(), thresholds(), res)));
  EXPECT_TRUE(res.available);
  EXPECT_FALSE(res.consistent);
  EXPECT_EQ(res.num_excluded, 0);
}

TEST(Raim, NoRedundancyMeansNotAvailable) {
  const LsRange r[2] = {make_range(0, 0, 0.2F, 0, 0), make_range(60, 0, 0.2F, 0, 0)};
  RaimResult res;
  ASSERT_TRUE(ok(raim_run(r, 2, planar_options(), thresholds(), res)));
  EXPECT_FALSE(res.available);
}

TEST(Raim, NonFiniteRangeIsInvalidArgument) {
  LsRange r[4] = {make_range(0, 0, 0.2F, 0, 0), make_range(60, 0, 0.2F, 0, 0), make_range(60, 40, 0.2F, 0, 0),
                  make_range(0, 40, 0.2F, 0, 0)};
  r[1].range_m = std::nanf("");
  RaimResult res;
  EXPECT_EQ(raim_run(r, 4, planar_options(), thresholds(), res), Status::kInvalidArgument);
}

}  // namespace
}  // namespace uwbnav
