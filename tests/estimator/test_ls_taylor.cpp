// Unit tests of the LS-Taylor multilateration (seed 003 eq. 1-4): exact fixes,
// weighting, 2-D mode, covariance/GDOP and singular geometries staying finite.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "estimator/ls_taylor.hpp"

namespace uwbnav {
namespace {

std::vector<LsRange> exact_ranges(const std::vector<Vec3f>& anchors, Vec3f tag, float sigma_m = 0.1F) {
  std::vector<LsRange> out;
  for (const Vec3f& a : anchors) {
    const double dx = static_cast<double>(a.x) - static_cast<double>(tag.x);
    const double dy = static_cast<double>(a.y) - static_cast<double>(tag.y);
    const double dz = static_cast<double>(a.z) - static_cast<double>(tag.z);
    out.push_back(LsRange{a, static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz)), sigma_m});
  }
  return out;
}

bool fix_finite(const LsFix& f) {
  bool ok = std::isfinite(f.pos_nav_m.x) && std::isfinite(f.pos_nav_m.y) && std::isfinite(f.pos_nav_m.z) &&
            std::isfinite(f.weighted_ssr) && std::isfinite(f.gdop);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) ok = ok && std::isfinite(f.cov_nav_m2[r][c]);
  }
  for (size_t i = 0; i < kLsMaxRanges; ++i) ok = ok && std::isfinite(f.residual_m[i]);
  return ok;
}

const std::vector<Vec3f> kVolumeAnchors = {
    {0, 0, 0.5F}, {20, 0, 3.0F}, {20, 15, 0.8F}, {0, 15, 2.6F}, {10, -5, 4.0F}};
const std::vector<Vec3f> kPlanarAnchors = {{0, 0, 2.5F}, {40, 0, 2.5F}, {40, 30, 2.5F}, {0, 30, 2.5F}};

TEST(LsTaylor, ThreeDExactRangesRecoverTagPosition) {
  const Vec3f tag{7.3F, 4.1F, 1.7F};
  const auto r = exact_ranges(kVolumeAnchors, tag);
  LsFix fix;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kOk);
  EXPECT_NEAR(fix.pos_nav_m.x, tag.x, 1e-3);
  EXPECT_NEAR(fix.pos_nav_m.y, tag.y, 1e-3);
  EXPECT_NEAR(fix.pos_nav_m.z, tag.z, 1e-3);
  EXPECT_TRUE(fix.converged);
  EXPECT_EQ(fix.dof, 2);
  EXPECT_LT(fix.weighted_ssr, 1e-3F);
  EXPECT_GT(fix.gdop, 0.5F);
  EXPECT_TRUE(fix_finite(fix));
}

TEST(LsTaylor, TwoDModeOnPlanarAnchorsUsesKnownHeight) {
  const Vec3f tag{12.0F, 21.0F, 1.2F};
  const auto r = exact_ranges(kPlanarAnchors, tag);
  LsOptions opt;
  opt.two_d = true;
  opt.known_z_m = 1.2F;
  LsFix fix;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), opt, fix), Status::kOk);
  EXPECT_NEAR(fix.pos_nav_m.x, tag.x, 1e-3);
  EXPECT_NEAR(fix.pos_nav_m.y, tag.y, 1e-3);
  EXPECT_FLOAT_EQ(fix.pos_nav_m.z, 1.2F);
  EXPECT_EQ(fix.dof, 2);
  EXPECT_EQ(fix.cov_nav_m2[2][2], 0.0F);
  EXPECT_GT(fix.cov_nav_m2[0][0], 0.0F);
}

TEST(LsTaylor, ThreeDOnCoplanarAnchorsWithTagInPlaneIsSingularAndFinite) {
  const auto r = exact_ranges(kPlanarAnchors, Vec3f{12.0F, 21.0F, 2.5F});
  LsFix fix;
  EXPECT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kSingular);
  EXPECT_TRUE(fix_finite(fix));
}

TEST(LsTaylor, ThreeDOnCoplanarAnchorsWithoutGuessIsSingular) {
  // The linear step (seed 003 eq. 2) has no information on z when all anchors share one plane.
  const auto r = exact_ranges(kPlanarAnchors, Vec3f{12.0F, 21.0F, 0.5F});
  LsFix fix;
  EXPECT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kSingular);
  EXPECT_TRUE(fix_finite(fix));
}

TEST(LsTaylor, TwoDColinearAnchorsAreSingularAndFinite) {
  const std::vector<Vec3f> line = {{0, 0, 2}, {10, 0, 2}, {20, 0, 2}, {30, 0, 2}};
  const auto r = exact_ranges(line, Vec3f{12.0F, 5.0F, 1.0F});
  LsOptions opt;
  opt.two_d = true;
  opt.known_z_m = 1.0F;
  LsFix fix;
  EXPECT_EQ(ls_taylor_solve(r.data(), r.size(), opt, fix), Status::kSingular);
  EXPECT_TRUE(fix_finite(fix));
  // The linear step is singular, but Gauss-Newton from a guess on one side of
  // the line resolves the mirror ambiguity (tag off the line).
  opt.has_initial_guess = true;
  opt.initial_guess_nav_m = Vec3f{12.0F, 4.0F, 1.0F};
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), opt, fix), Status::kOk);
  EXPECT_NEAR(fix.pos_nav_m.y, 5.0F, 1e-3F);
  // Tag on the line: no cross-line information at all.
  const auto on_line = exact_ranges(line, Vec3f{12.0F, 0.0F, 1.0F});
  opt.initial_guess_nav_m = Vec3f{12.0F, 0.0F, 1.0F};
  EXPECT_EQ(ls_taylor_solve(on_line.data(), on_line.size(), opt, fix), Status::kSingular);
  EXPECT_TRUE(fix_finite(fix));
  EXPECT_FLOAT_EQ(fix.pos_nav_m.x, 12.0F);  // failure reports the guess, not garbage
}

TEST(LsTaylor, TagOnAnchorWithZeroRangeStaysFiniteAndCorrect) {
  const Vec3f tag = kVolumeAnchors[1];
  const auto r = exact_ranges(kVolumeAnchors, tag);
  ASSERT_EQ(r[1].range_m, 0.0F);
  LsFix fix;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kOk);
  EXPECT_TRUE(fix_finite(fix));
  EXPECT_NEAR(fix.pos_nav_m.x, tag.x, 1e-2);
  EXPECT_NEAR(fix.pos_nav_m.y, tag.y, 1e-2);
  EXPECT_NEAR(fix.pos_nav_m.z, tag.z, 1e-2);
  // Starting exactly on the anchor too.
  LsOptions opt;
  opt.has_initial_guess = true;
  opt.initial_guess_nav_m = tag;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), opt, fix), Status::kOk);
  EXPECT_TRUE(fix_finite(fix));
}

TEST(LsTaylor, RejectsNonFiniteAndTooFewRanges) {
  auto r = exact_ranges(kVolumeAnchors, Vec3f{1, 2, 1});
  LsFix fix;
  EXPECT_EQ(ls_taylor_solve(r.data(), 3, LsOptions{}, fix), Status::kInvalidArgument);
  LsOptions guess;
  guess.has_initial_guess = true;
  guess.initial_guess_nav_m = Vec3f{2, 2, 1};
  EXPECT_EQ(ls_taylor_solve(r.data(), 3, guess, fix), Status::kOk);
  r[2].range_m = std::nanf("");
  EXPECT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kInvalidArgument);
  EXPECT_TRUE(fix_finite(fix));
  r[2].range_m = 5.0F;
  r[2].sigma_m = 0.0F;
  EXPECT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kInvalidArgument);
  EXPECT_EQ(ls_taylor_solve(nullptr, 5, LsOptions{}, fix), Status::kInvalidArgument);
}

TEST(LsTaylor, WeightsDownweightTheNoisyRange) {
  const Vec3f tag{8.0F, 6.0F, 1.5F};
  auto r = exact_ranges(kVolumeAnchors, tag, 0.05F);
  r[0].range_m += 2.0F;  // one grossly wrong range...
  LsFix equal;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, equal), Status::kOk);
  r[0].sigma_m = 5.0F;   // ...that the caller knows is poor
  LsFix weighted;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, weighted), Status::kOk);
  const auto err = [&](const LsFix& f) {
    return std::hypot(f.pos_nav_m.x - tag.x, f.pos_nav_m.y - tag.y, f.pos_nav_m.z - tag.z);
  };
  EXPECT_LT(err(weighted), 0.5F * err(equal));
  EXPECT_GT(equal.weighted_ssr, 30.0F);  // chi-square (2 dof, 99.9 % = 13.8) flags the blunder
  for (size_t i = 1; i < r.size(); ++i) EXPECT_GT(std::fabs(weighted.residual_m[0]), std::fabs(weighted.residual_m[i]));
}

TEST(LsTaylor, CovarianceMatchesMonteCarloScatter) {
  const Vec3f tag{9.0F, 5.0F, 1.5F};
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0F, 0.1F);
  double sx = 0, sy = 0, sxx = 0, syy = 0;
  const int kTrials = 2000;
  float claimed_xx = 0, claimed_yy = 0;
  double ssr_sum = 0;
  for (int k = 0; k < kTrials; ++k) {
    auto r = exact_ranges(kVolumeAnchors, tag);
    for (auto& x : r) x.range_m += noise(rng);
    LsFix fix;
    ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kOk);
    const double ex = static_cast<double>(fix.pos_nav_m.x - tag.x);
    const double ey = static_cast<double>(fix.pos_nav_m.y - tag.y);
    sx += ex;
    sy += ey;
    sxx += ex * ex;
    syy += ey * ey;
    claimed_xx = fix.cov_nav_m2[0][0];
    claimed_yy = fix.cov_nav_m2[1][1];
    ssr_sum += static_cast<double>(fix.weighted_ssr);
  }
  const double var_x = sxx / kTrials - (sx / kTrials) * (sx / kTrials);
  const double var_y = syy / kTrials - (sy / kTrials) * (sy / kTrials);
  EXPECT_NEAR(var_x / static_cast<double>(claimed_xx), 1.0, 0.2);
  EXPECT_NEAR(var_y / static_cast<double>(claimed_yy), 1.0, 0.2);
  EXPECT_NEAR(ssr_sum / kTrials, 2.0, 0.3);  // chi-square with n - 3 = 2 dof
}

TEST(LsTaylor, FarFromOriginStaysAccurateInFloat) {
  std::vector<Vec3f> far = kVolumeAnchors;
  for (auto& a : far) {
    a.x += 3000.0F;
    a.y -= 2000.0F;
  }
  const Vec3f tag{3007.0F, -1994.0F, 1.5F};
  const auto r = exact_ranges(far, tag);
  LsFix fix;
  ASSERT_EQ(ls_taylor_solve(r.data(), r.size(), LsOptions{}, fix), Status::kOk);
  EXPECT_NEAR(fix.pos_nav_m.x, tag.x, 5e-3);
  EXPECT_NEAR(fix.pos_nav_m.y, tag.y, 5e-3);
}

}  // namespace
}  // namespace uwbnav
