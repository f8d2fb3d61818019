// sin_cos(): quadrant reduction plus minimax polynomials on [-pi/4, pi/4]
// (see trig.hpp for the accuracy contract).
#include "estimator/trig.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

namespace uwbnav {

#ifdef UWBNAV_ESTIMATOR_DOUBLE

SinCos sin_cos(Real angle_rad) { return SinCos{std::sin(angle_rad), std::cos(angle_rad)}; }

#else

namespace {

// pi/2 split into two 17-bit heads and a tail: n * head is exact for
// |n| <= 128, so r = x - n pi/2 keeps float precision (Cody & Waite 1980).
constexpr float kPio2Head1 = 0x1.921fp+0F;
constexpr float kPio2Head2 = 0x1.6a88p-17F;
constexpr float kPio2Tail = 0x1.0b4612p-34F;
constexpr float kTwoOverPi = 0x1.45f306p-1F;
constexpr float kTwoPi = 6.28318530717958647692F;

// Relative least-squares fits on Chebyshev nodes of [-pi/4, pi/4]
// (max error 0.74 ulp for sin, 1.2 ulp for cos, before reduction).
//   sin r = r + r^3 (S1 + S2 r^2 + S3 r^4)
//   cos r = 1 - r^2/2 + r^4 (C1 + C2 r^2 + C3 r^4)
constexpr float kS1 = -0x1.555544p-3F;   // -1.666665375e-01
constexpr float kS2 = 0x1.110720p-7F;    //  8.332148194e-03
constexpr float kS3 = -0x1.993c9cp-13F;  // -1.951392915e-04
constexpr float kC1 = 0x1.55554ap-5F;    //  4.166664556e-02
constexpr float kC2 = -0x1.6c0c06p-10F;  // -1.388728968e-03
constexpr float kC3 = 0x1.99e080p-16F;   //  2.443057019e-05

}  // namespace

SinCos sin_cos(Real angle_rad) {
  float x = angle_rad;
  if (!std::isfinite(x)) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    return SinCos{nan, nan};
  }
  if (std::fabs(x) > kTrigExactLimit_rad) x = std::fmod(x, kTwoPi);
  const float q = x * kTwoOverPi;
  const auto n = static_cast<std::int32_t>(q + (q < 0.0F ? -0.5F : 0.5F));
  const float nf = static_cast<float>(n);
  const float r = ((x - nf * kPio2Head1) - nf * kPio2Head2) - nf * kPio2Tail;
  const float z = r * r;
  const float s = r + r * z * (kS1 + z * (kS2 + z * kS3));
  const float c = 1.0F - 0.5F * z + z * z * (kC1 + z * (kC2 + z * kC3));
  switch (static_cast<std::uint32_t>(n) & 3U) {
    case 0U:
      return SinCos{s, c};
    case 1U:
      return SinCos{c, -s};
    case 2U:
      return SinCos{-s, -c};
    default:
      return SinCos{-c, s};
  }
}

#endif

}  // namespace uwbnav
