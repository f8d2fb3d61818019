// Sine and cosine of one angle for the estimator, without libm's
// large-argument reduction (a Payne-Hanek table the estimator never needs:
// 3.2 KiB of the M4F image's 128 KiB flash, docs/footprint.md).
//
// Accuracy (float build, tests/estimator/test_trig.cpp): within 2.5 ulp of the
// exact value for |angle| <= kTrigExactLimit_rad (quadrant found by a
// three-part Cody-Waite reduction whose products are exact there). Beyond it
// the angle is first folded by fmod(angle, 2*pi rounded to float), which
// loses |angle| * 2.8e-8 rad: the estimator's angles are wrapped to +-pi and
// half-angles of one IMU step, far inside the limit. Not finite -> NaN, NaN.
// The double build (UWBNAV_ESTIMATOR_DOUBLE, the float-vs-double reference)
// uses std::sin / std::cos.
#pragma once

#include "estimator/types.hpp"

namespace uwbnav {

struct SinCos {
  Real sin;
  Real cos;
};

// |angle| below which the float reduction is exact [rad] (128 quadrants).
constexpr Real kTrigExactLimit_rad = Real(201);

[[nodiscard]] SinCos sin_cos(Real angle_rad);

}  // namespace uwbnav
