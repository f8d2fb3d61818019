// Normal and chi-square quantiles (seed 001 RAIM thresholds).
#include "estimator/nlos/chi_square.hpp"

#include <cmath>
#include <limits>

namespace uwbnav {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// log Gamma(dof / 2) by the recursion Gamma(a + 1) = a Gamma(a) from Gamma(1) = 1, Gamma(1/2) = sqrt(pi).
double log_gamma_half(int dof) {
  double a = (dof % 2 == 0) ? 1.0 : 0.5;
  double lg = (dof % 2 == 0) ? 0.0 : 0.5 * std::log(kPi);
  while (a < 0.5 * dof - 0.25) {
    lg += std::log(a);
    a += 1.0;
  }
  return lg;
}

// Regularised lower incomplete gamma P(a, x) (Numerical Recipes §6.2 series / Lentz continued fraction).
double gamma_p(double a, double x, double log_gamma_a) {
  if (x <= 0.0) return 0.0;
  constexpr int kMaxIter = 300;
  constexpr double kEps = 1e-15;
  const double log_prefix = a * std::log(x) - x - log_gamma_a;
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    double ap = a;
    for (int i = 0; i < kMaxIter; ++i) {
      ap += 1.0;
      term *= x / ap;
      sum += term;
      if (std::fabs(term) < std::fabs(sum) * kEps) break;
    }
    return sum * std::exp(log_prefix);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i <= kMaxIter; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < kEps) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

}  // namespace

double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) return kNaN;
  // Acklam (2003) coefficients.
  static constexpr double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                                  1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                  6.680131188771972e+01,  -1.328068155288572e+01};
  static constexpr double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                  -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                  3.754408661907416e+00};
  constexpr double kLow = 0.02425;
  double x = 0.0;
  if (p < kLow) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else if (p <= 1.0 - kLow) {
    const double q = p - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  } else {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  // One Halley step on Phi(x) - p with Phi from erfc.
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2.0 * kPi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

double chi_square_cdf(double x, int dof) {
  if (dof < 1 || dof > kChiSquareMaxDof || std::isnan(x)) return kNaN;
  if (x <= 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return gamma_p(0.5 * dof, 0.5 * x, log_gamma_half(dof));
}

double chi_square_quantile(double p, int dof) {
  if (!(p > 0.0 && p < 1.0) || dof < 1 || dof > kChiSquareMaxDof) return kNaN;
  if (dof == 1) {
    const double z = normal_quantile(0.5 + 0.5 * p);
    return z * z;
  }
  if (dof == 2) return -2.0 * std::log(1.0 - p);
  // Wilson-Hilferty start: k (1 - 2/(9k) + z sqrt(2/(9k)))^3.
  const double k = dof;
  const double z = normal_quantile(p);
  const double h = 2.0 / (9.0 * k);
  double x = k * std::pow(std::fmax(1.0 - h + z * std::sqrt(h), 1e-3), 3.0);
  const double a = 0.5 * k;
  const double lg = log_gamma_half(dof);
  for (int i = 0; i < 30; ++i) {
    const double f = gamma_p(a, 0.5 * x, lg) - p;
    // chi-square pdf: x^(a-1) e^(-x/2) / (2^a Gamma(a))
    const double pdf = std::exp((a - 1.0) * std::log(x) - 0.5 * x - a * std::log(2.0) - lg);
    if (!(pdf > 0.0)) break;
    double step = f / pdf;
    if (step > 0.5 * x) step = 0.5 * x;  // keep x positive
    x -= step;
    if (std::fabs(step) < 1e-12 * x) break;
  }
  return x;
}

}  // namespace uwbnav
