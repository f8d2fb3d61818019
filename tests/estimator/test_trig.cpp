// The estimator's own sin/cos (estimator/trig.*): within 2.5 ulp of the exact
// value wherever the estimator calls it, correct quadrants, NaN on bad input,
// and bounded loss past the exact-reduction limit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "estimator/trig.hpp"

namespace uwbnav {
namespace {

static_assert(sizeof(Real) == sizeof(float), "the default test build is float");

// Error of a float result against the double reference, in units of the
// float spacing at the reference value (ulp).
double ulp_error(float got, double exact) {
  const double ulp = std::nextafter(static_cast<float>(std::fabs(exact)), std::numeric_limits<float>::infinity()) -
                     static_cast<float>(std::fabs(exact));
  return std::fabs(static_cast<double>(got) - exact) / ulp;
}

TEST(Trig, SinAndCosAreWithinTwoAndAHalfUlpAcrossTheExactReductionRange) {
  double worst_sin = 0.0;
  double worst_cos = 0.0;
  const int n = 400001;
  for (int i = 0; i < n; ++i) {
    const float x = static_cast<float>(-200.0 + 400.0 * i / (n - 1));
    const SinCos sc = sin_cos(x);
    worst_sin = std::fmax(worst_sin, ulp_error(sc.sin, std::sin(static_cast<double>(x))));
    worst_cos = std::fmax(worst_cos, ulp_error(sc.cos, std::cos(static_cast<double>(x))));
  }
  EXPECT_LT(worst_sin, 2.5);
  EXPECT_LT(worst_cos, 2.5);
}

TEST(Trig, SmallAnglesKeepFullRelativePrecision) {
  // Half-angles of one 100 Hz IMU step are 1e-8..1e-2 rad (ekf_state.hpp quat_exp).
  for (float x = 1e-8F; x < 0.8F; x *= 1.37F) {
    for (const float s : {x, -x}) {
      const SinCos sc = sin_cos(s);
      EXPECT_LT(ulp_error(sc.sin, std::sin(static_cast<double>(s))), 2.0) << s;
      EXPECT_LT(ulp_error(sc.cos, std::cos(static_cast<double>(s))), 2.0) << s;
    }
  }
}

TEST(Trig, QuadrantBoundariesGiveTheRightSigns) {
  const float pio2 = 1.57079632679F;
  const float expect_sin[] = {0.0F, 1.0F, 0.0F, -1.0F, 0.0F, -1.0F, 0.0F, 1.0F};
  const float expect_cos[] = {1.0F, 0.0F, -1.0F, 0.0F, 1.0F, 0.0F, -1.0F, 0.0F};
  const float angles[] = {0.0F, pio2, 2 * pio2, 3 * pio2, 4 * pio2, -pio2, -2 * pio2, -3 * pio2};
  for (int i = 0; i < 8; ++i) {
    const SinCos sc = sin_cos(angles[i]);
    EXPECT_NEAR(sc.sin, expect_sin[i], 1e-6F) << angles[i];
    EXPECT_NEAR(sc.cos, expect_cos[i], 1e-6F) << angles[i];
  }
}

TEST(Trig, PythagoreanIdentityHoldsJustOffTheOctantEdges) {
  const float pio4 = 0.785398163F;
  for (int k = -16; k <= 16; ++k) {
    for (const float d : {-1e-6F, 0.0F, 1e-6F}) {
      const SinCos sc = sin_cos(static_cast<float>(k) * pio4 + d);
      EXPECT_NEAR(sc.sin * sc.sin + sc.cos * sc.cos, 1.0F, 4e-7F) << k;
    }
  }
}

TEST(Trig, NonFiniteAnglesGiveNanNotAQuadrantGuess) {
  for (const float x : {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                        std::numeric_limits<float>::quiet_NaN()}) {
    const SinCos sc = sin_cos(x);
    EXPECT_TRUE(std::isnan(sc.sin));
    EXPECT_TRUE(std::isnan(sc.cos));
  }
}

TEST(Trig, AnglesPastTheExactLimitLoseNoMoreThanTheDocumentedFold) {
  // trig.hpp: beyond kTrigExactLimit_rad the fold by float(2 pi) loses
  // |x| * 2.8e-8 rad; the identity and range still hold exactly.
  for (const float x : {250.0F, -1234.5F, 1e4F, -3e5F, 1e7F}) {
    const SinCos sc = sin_cos(x);
    const double bound = std::fabs(static_cast<double>(x)) * 2.8e-8 + 1e-6;
    EXPECT_NEAR(sc.sin, std::sin(static_cast<double>(x)), bound) << x;
    EXPECT_NEAR(sc.cos, std::cos(static_cast<double>(x)), bound) << x;
    EXPECT_NEAR(sc.sin * sc.sin + sc.cos * sc.cos, 1.0F, 4e-7F) << x;
  }
}

}  // namespace
}  // namespace uwbnav
