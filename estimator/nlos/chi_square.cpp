// Normal and chi-square upper-tail quantiles in float (seed 001 RAIM thresholds).
#include "estimator/nlos/chi_square.hpp"

#include <cmath>
#include <limits>

namespace uwbnav {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kEps = std::numeric_limits<float>::epsilon();
constexpr float kTwoPi = 6.28318530717958647692F;
constexpr int kMaxIter = 300;
// Smallest tail probability taken by the quantiles: the smallest normal float
// (subnormal q carries too few bits, and q/2 of the dof 1 case may underflow).
constexpr float kMinQ = std::numeric_limits<float>::min();

// Inverse CDF of N(0,1) for p in (0, 0.5]: x <= 0 with Phi(x) = p. Wichura's
// AS 241 PPND7 (Applied Statistics 37(3), 1988), the single-precision variant:
// relative error about 1e-7, and every polynomial has positive coefficients
// on its interval, so float evaluation adds only rounding. (Acklam's
// approximation loses up to 6e-5 in float near p = 0.03 to cancellation in
// its central polynomials.)
float normal_lower_quantile(float p) {
  const float s = p - 0.5F;  // in [-0.5, 0]
  if (s >= -0.425F) {
    const float r = 0.180625F - s * s;
    return s * (((59.109374720F * r + 159.29113202F) * r + 50.434271938F) * r + 3.3871327179F) /
           (((67.187563600F * r + 78.757757664F) * r + 17.895169469F) * r + 1.0F);
  }
  float r = std::sqrt(-std::log(p));
  float x = 0.0F;
  if (r <= 5.0F) {
    r -= 1.6F;
    x = (((0.17023821103F * r + 1.3067284816F) * r + 2.7568153900F) * r + 1.4234372777F) /
        ((0.12021132975F * r + 0.73700164250F) * r + 1.0F);
  } else {
    r -= 5.0F;
    x = (((0.017337203997F * r + 0.42868294337F) * r + 3.0812263860F) * r + 6.6579051150F) /
        ((0.012258202635F * r + 0.24197894225F) * r + 1.0F);
  }
  return -x;
}

// ln Gamma*(a), Gamma*(a) = Gamma(a) / (sqrt(2 pi) a^(a - 1/2) e^-a) (Stirling's
// correction factor), a > 0. Stirling series for a >= 8 (next term 1/(1188 a^9)
// < 1e-11); below, the exact recursion ln Gamma*(b) = ln Gamma*(b + 1) +
// (b + 1/2) ln(1 + 1/b) - 1, whose right-hand part is the positive series
// sum_{j>=1} w^(2j) / (2j + 1), w = 1/(2b + 1) (ln(1 + 1/b) = 2 artanh w):
// no cancellation, unlike ln Gamma(a) minus its Stirling approximation in float.
float log_gamma_star(float a) {
  constexpr float kStirlingFrom = 8.0F;
  float sum = 0.0F;
  while (a < kStirlingFrom) {
    const float w = 1.0F / (2.0F * a + 1.0F);
    const float w2 = w * w;
    float wp = w2;
    float part = 0.0F;
    for (int j = 1; j < 40; ++j) {
      const float term = wp / static_cast<float>(2 * j + 1);
      part += term;
      if (term < part * kEps) break;
      wp *= w2;
    }
    sum += part;
    a += 1.0F;
  }
  const float inv = 1.0F / a;
  const float inv2 = inv * inv;
  return sum + inv * (1.0F / 12.0F - inv2 * (1.0F / 360.0F - inv2 * (1.0F / 1260.0F - inv2 * (1.0F / 1680.0F))));
}

// y^a e^-y / Gamma(a) written as sqrt(a / 2 pi) exp(-(y - a - a ln(y/a))) / Gamma*(a)
// (Temme's form): the exponent is small near the bulk of the distribution, where
// a ln y - y - ln Gamma(a) would subtract terms of size ~a ln a in float.
float gamma_prefix(float a, float y, float log_gamma_star_a) {
  const float expo = a * std::log(y / a) - (y - a) - log_gamma_star_a;
  return std::sqrt(a / kTwoPi) * std::exp(expo);
}

// Regularised incomplete gamma at y > 0 (Numerical Recipes 3rd ed. §6.2):
// the series gives P, the Lentz continued fraction gives Q; the other one is
// 1 minus it (never small there: Q >= 0.08 in the series region y < a + 1).
// Also returns prefix = y^a e^-y / Gamma(a) (y times the gamma pdf).
struct GammaPQ {
  float p;
  float q;
  float prefix;
};

GammaPQ gamma_pq(float a, float y, float log_gamma_star_a) {
  const float prefix = gamma_prefix(a, y, log_gamma_star_a);
  if (y < a + 1.0F) {
    float term = 1.0F;
    float sum = 1.0F;
    for (int n = 1; n <= kMaxIter; ++n) {
      term *= y / (a + static_cast<float>(n));
      sum += term;
      if (term < sum * kEps) break;
    }
    const float p = prefix * sum / a;
    return GammaPQ{p, 1.0F - p, prefix};
  }
  constexpr float kTiny = 1e-30F;
  float b = y + 1.0F - a;
  float c = 1.0F / kTiny;
  float d = 1.0F / b;
  float h = d;
  for (int i = 1; i <= kMaxIter; ++i) {
    const float fi = static_cast<float>(i);
    const float an = -fi * (fi - a);
    b += 2.0F;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0F / d;
    const float del = d * c;
    h *= del;
    if (std::fabs(del - 1.0F) <= kEps) break;
  }
  const float q = prefix * h;
  return GammaPQ{1.0F - q, q, prefix};
}

bool valid_dof(int dof) { return dof >= 1 && dof <= kChiSquareMaxDof; }

}  // namespace

float normal_upper_quantile(float q) {
  if (!(q >= kMinQ && q < 1.0F)) return kNaN;
  // Upper tail q <= 1/2: x = -Phi^-1(q). Above, 1 - q is exact (Sterbenz).
  return q <= 0.5F ? -normal_lower_quantile(q) : normal_lower_quantile(1.0F - q);
}

float chi_square_upper_tail(float x, int dof) {
  if (!valid_dof(dof) || std::isnan(x)) return kNaN;
  if (x <= 0.0F) return 1.0F;
  if (std::isinf(x)) return 0.0F;
  const float a = 0.5F * static_cast<float>(dof);
  return gamma_pq(a, 0.5F * x, log_gamma_star(a)).q;
}

float chi_square_cdf(float x, int dof) {
  if (!valid_dof(dof) || std::isnan(x)) return kNaN;
  if (x <= 0.0F) return 0.0F;
  if (std::isinf(x)) return 1.0F;
  const float a = 0.5F * static_cast<float>(dof);
  return gamma_pq(a, 0.5F * x, log_gamma_star(a)).p;
}

float chi_square_upper_quantile(float q, int dof) {
  if (!(q >= 2.0F * kMinQ && q < 1.0F) || !valid_dof(dof)) return kNaN;
  if (dof == 1) {  // Q = 2 (1 - Phi(sqrt(x)))
    const float z = normal_upper_quantile(0.5F * q);
    return z * z;
  }
  if (dof == 2) return -2.0F * std::log(q);  // Q = exp(-x/2)
  const float k = static_cast<float>(dof);
  const float a = 0.5F * k;
  const float lgs = log_gamma_star(a);
  // Start: Wilson-Hilferty x = k (1 - h + z sqrt(h))^3, h = 2/(9k), and not
  // below the lower bound from P(a, y) <= y^a / Gamma(a + 1) (it matters for
  // q near 1, where the Wilson-Hilferty cube goes negative).
  const float h = 2.0F / (9.0F * k);
  const float base = std::fmax(1.0F - h + normal_upper_quantile(q) * std::sqrt(h), 0.0F);
  float y = 0.5F * k * base * base * base;
  // ln Gamma(a + 1) = ln Gamma*(a) + (a + 1/2) ln a - a + ln sqrt(2 pi).
  const float log_gamma_a1 = lgs + (a + 0.5F) * std::log(a) - a + 0.5F * std::log(kTwoPi);
  y = std::fmax(y, std::exp((std::log(1.0F - q) + log_gamma_a1) / a));
  // Newton on the logarithm of the smaller tail: ln Q(a, y) - ln q for q <= 1/2,
  // else ln P(a, y) - ln(1 - q) (1 - q exact there), as the side that is not
  // small is 1 minus the other in float. d/dy ln Q = -y^(a-1) e^-y / (Gamma(a) Q),
  // d/dy ln P = +y^(a-1) e^-y / (Gamma(a) P). For a >= 1 the gamma distribution
  // is log-concave, so ln Q and ln P are concave: after at most one step past
  // the root the iterates approach it monotonically.
  const bool upper = q <= 0.5F;
  const float target = upper ? q : 1.0F - q;
  for (int i = 0; i < 40; ++i) {
    const GammaPQ g = gamma_pq(a, y, lgs);
    const float tail = upper ? g.q : g.p;
    if (!(tail > 0.0F)) {  // so far out that the tail underflowed: come back
      y = upper ? 0.5F * y : 2.0F * y;
      continue;
    }
    const float ratio = tail / target;
    const float dlog = std::isfinite(ratio) ? std::log(ratio) : std::log(tail) - std::log(target);
    const float step = (upper ? dlog : -dlog) * tail * y / g.prefix;
    if (!std::isfinite(step)) break;
    const float next = std::fmax(y + step, 0.125F * y);
    const bool done = std::fabs(next - y) <= 2.0F * kEps * y;
    y = next;
    if (done) break;
  }
  return 2.0F * y;
}

}  // namespace uwbnav
