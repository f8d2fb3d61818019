// Dempster-Shafer combination (seed 000 eq. 7-8).
#include "estimator/nlos/dempster_shafer.hpp"

#include <cmath>

#include "estimator/types.hpp"

namespace uwbnav {

namespace {
constexpr float kClip = 1e-6F;
float clip(float p) { return std::fmin(std::fmax(p, kClip), 1.0F - kClip); }
}  // namespace

float ds_combine(float p1, float p2) {
  const bool has1 = std::isfinite(p1);
  const bool has2 = std::isfinite(p2);
  if (!has1 && !has2) return kNaNf;
  if (!has1) return clip(p2);
  if (!has2) return clip(p1);
  const float a = clip(p1);
  const float b = clip(p2);
  const float nlos = a * b;                    // M1(N) M2(N)
  const float k = nlos + (1.0F - a) * (1.0F - b);  // eq. 7
  return nlos / k;                             // eq. 8
}

float ds_combine_all(const float* p, size_t n) {
  float r = kNaNf;
  for (size_t i = 0; i < n; ++i) r = ds_combine(r, p[i]);
  return r;
}

}  // namespace uwbnav
