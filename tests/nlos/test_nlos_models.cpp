// Protects the closed-form NLOS models: seed 000 eq. 3-6 (consistency p2),
// eq. 7-8 (Dempster-Shafer), seed 003 eq. 21-23 (residual factor), the
// channel power-gap evidence, the innovation evidence of the default policy
// and the chi-square / normal quantiles of seed 001.
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "estimator/nlos/channel.hpp"
#include "estimator/nlos/chi_square.hpp"
#include "estimator/nlos/consistency.hpp"
#include "estimator/nlos/dempster_shafer.hpp"
#include "estimator/nlos/innovation_evidence.hpp"
#include "estimator/nlos/residual_inflation.hpp"
#include "estimator/params.hpp"

namespace uwbnav {
namespace {

TEST(Consistency, Eq6StepsAtOneTwoThreeSigma) {
  const float sigma = 0.1F;
  // |Δρ| - Δd with Δd = 1 m.
  EXPECT_FLOAT_EQ(consistency_p_nlos(1.05F, 1.0F, sigma), 0.35F);   // 0.05 <= σ
  EXPECT_FLOAT_EQ(consistency_p_nlos(-1.15F, 1.0F, sigma), 0.55F);  // |Δρ| used: 0.15 > σ
  EXPECT_FLOAT_EQ(consistency_p_nlos(1.25F, 1.0F, sigma), 0.7F);    // > 2σ
  EXPECT_FLOAT_EQ(consistency_p_nlos(1.35F, 1.0F, sigma), 0.9F);    // > 3σ
  EXPECT_FLOAT_EQ(consistency_p_nlos(0.2F, 1.0F, sigma), 0.35F);    // triangle inequality holds
}

TEST(Consistency, MissingInputGivesNaN) {
  EXPECT_TRUE(std::isnan(consistency_p_nlos(std::nanf(""), 1.0F, 0.1F)));
  EXPECT_TRUE(std::isnan(consistency_p_nlos(1.0F, std::nanf(""), 0.1F)));
  EXPECT_TRUE(std::isnan(consistency_p_nlos(1.0F, 1.0F, 0.0F)));
}

TEST(DempsterShafer, Eq8HandComputed) {
  // p1 = 0.9, p2 = 0.7: R = 0.63 / (0.63 + 0.03) = 0.954545...
  EXPECT_NEAR(ds_combine(0.9F, 0.7F), 0.63F / 0.66F, 1e-6F);
  // Conflicting evidence: p1 = 0.8, p2 = 0.35: 0.28 / (0.28 + 0.13) = 0.682926...
  EXPECT_NEAR(ds_combine(0.8F, 0.35F), 0.28F / 0.41F, 1e-6F);
  // Neutral evidence does not move the other source.
  EXPECT_NEAR(ds_combine(0.5F, 0.3F), 0.3F, 1e-6F);
}

TEST(DempsterShafer, AbsentEvidenceAndTotalConflict) {
  EXPECT_NEAR(ds_combine(std::nanf(""), 0.7F), 0.7F, 1e-6F);
  EXPECT_TRUE(std::isnan(ds_combine(std::nanf(""), std::nanf(""))));
  const float r = ds_combine(1.0F, 0.0F);  // K would be 0 without clipping
  EXPECT_TRUE(std::isfinite(r));
  const float p[3] = {0.9F, std::nanf(""), 0.7F};
  EXPECT_NEAR(ds_combine_all(p, 3), ds_combine(0.9F, 0.7F), 1e-6F);
}

TEST(ResidualInflation, Eq23) {
  EXPECT_FLOAT_EQ(residual_inflation_factor(2.9F, 3.0F, 2.0F), 1.0F);
  EXPECT_FLOAT_EQ(residual_inflation_factor(-6.0F, 3.0F, 2.0F), 4.0F);  // δ = |d - l| (eq. 21)
  EXPECT_TRUE(std::isnan(residual_inflation_factor(std::nanf(""), 3.0F, 2.0F)));
  EXPECT_TRUE(std::isnan(residual_inflation_factor(1.0F, 0.0F, 2.0F)));
}

// The exponentially modified Gaussian's likelihood ratio against N(0, S),
// from its definition in double (docs/nlos.md "Innovation evidence"):
// f_nlos(nu) = (1/mu) exp(S/(2 mu^2) - nu/mu) Phi(nu/sqrt(S) - sqrt(S)/mu).
double emg_p_nlos_reference(double nu, double s, double mu) {
  const double pi = 3.14159265358979323846;
  const double sd = std::sqrt(s);
  const double x = nu / sd - sd / mu;
  const double phi_cdf = 0.5 * std::erfc(-x / std::sqrt(2.0));
  const double f_nlos = std::exp(s / (2.0 * mu * mu) - nu / mu) * phi_cdf / mu;
  const double f_los = std::exp(-0.5 * nu * nu / s) / std::sqrt(2.0 * pi * s);
  const double lr = f_nlos / f_los;
  return lr / (1.0 + lr);
}

TEST(InnovationEvidence, MillsRatioWithinThreeTenthsOfAPercentOfTheNormalTail) {
  const double pi = 3.14159265358979323846;
  for (int i = 0; i <= 800; ++i) {
    const double t = 0.01 * i;
    const double exact = 0.5 * std::erfc(t / std::sqrt(2.0)) / (std::exp(-0.5 * t * t) / std::sqrt(2.0 * pi));
    EXPECT_NEAR(static_cast<double>(normal_mills_ratio(static_cast<float>(t))) / exact, 1.0, 0.003) << "t " << t;
  }
}

TEST(InnovationEvidence, MatchesTheExponentiallyModifiedGaussianFromMinusEightToPlusFourSigma) {
  // Over the range where the evidence is not clipped the float form follows
  // the definition to 0.3 % of its value (the Mills ratio's error); a
  // logistic stand-in for Phi was off by a factor 10 at 4 sigma short.
  const float mus_m[] = {0.2F, 0.5F, 2.0F};
  const float ss_m2[] = {0.0025F, 0.02F, 0.25F};
  for (const float mu_m : mus_m) {
    for (const float s_m2 : ss_m2) {
      const float sd_m = std::sqrt(s_m2);
      for (int i = -80; i <= 40; ++i) {
        const float nu_m = 0.1F * static_cast<float>(i) * sd_m;
        const double reference = emg_p_nlos_reference(nu_m, s_m2, mu_m);
        const float p = innovation_p_nlos(nu_m, s_m2, mu_m);
        const double clip = static_cast<double>(kInnovEvidenceClip);
        const double clipped = std::fmin(std::fmax(reference, clip), 1.0 - clip);
        EXPECT_NEAR(p, clipped, 0.003 * clipped + 1e-6) << "mu " << mu_m << " S " << s_m2 << " nu " << nu_m;
      }
    }
  }
}

TEST(InnovationEvidence, ShorterRangeIsNeverMoreNlosAndNonFiniteInputGivesNaN) {
  float previous = 1.0F;
  for (int i = 40; i >= -80; --i) {
    const float p = innovation_p_nlos(0.1F * static_cast<float>(i) * 0.1414F, 0.02F, 0.5F);
    EXPECT_LE(p, previous + 1e-6F) << "innovation " << 0.1F * static_cast<float>(i) << " sigma";
    previous = p;
  }
  EXPECT_LT(innovation_p_nlos(-4.0F * 0.1414F, 0.02F, 0.5F), 0.07F);
  EXPECT_TRUE(std::isnan(innovation_p_nlos(std::numeric_limits<float>::quiet_NaN(), 0.02F, 0.5F)));
  EXPECT_TRUE(std::isnan(innovation_p_nlos(0.1F, std::numeric_limits<float>::infinity(), 0.5F)));
  EXPECT_TRUE(std::isnan(innovation_p_nlos(0.1F, 0.0F, 0.5F)));
  EXPECT_TRUE(std::isnan(innovation_p_nlos(0.1F, 0.02F, 0.0F)));
  EXPECT_FLOAT_EQ(innovation_p_nlos(1000.0F, 0.02F, 0.5F), 1.0F - kInnovEvidenceClip);
}

TEST(Channel, PowerGapEvidenceNeutralBelowLoAndFullAboveHi) {
  EXPECT_FLOAT_EQ(channel_p_nlos(-80.0F, -78.0F, 6.0F, 10.0F, 0.9F), 0.5F);   // 2 dB gap
  EXPECT_FLOAT_EQ(channel_p_nlos(-92.0F, -84.0F, 6.0F, 10.0F, 0.9F), 0.7F);   // 8 dB: half way
  EXPECT_FLOAT_EQ(channel_p_nlos(-100.0F, -85.0F, 6.0F, 10.0F, 0.9F), 0.9F);  // 15 dB
  EXPECT_TRUE(std::isnan(channel_p_nlos(std::nanf(""), -85.0F, 6.0F, 10.0F, 0.9F)));
}

// Test-only double-precision references, independent of the float code's
// Temme prefix, Stirling series and Newton iteration: the regularised upper
// incomplete gamma by series / Lentz continued fraction (Numerical Recipes
// 3rd ed. §6.2) with std::lgamma, and quantiles by bisection.

// {P(a, y), Q(a, y)}, each computed directly where it is the small one.
std::pair<double, double> ref_gamma_pq(double a, double y) {
  if (y <= 0.0) return {0.0, 1.0};
  const double prefix = std::exp(a * std::log(y) - y - std::lgamma(a));
  if (y < a + 1.0) {  // series for P; Q >= 0.08 here
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 1000 && term > sum * 1e-17; ++n) {
      term *= y / (a + n);
      sum += term;
    }
    return {prefix * sum, 1.0 - prefix * sum};
  }
  double b = y + 1.0 - a;  // continued fraction for Q; P >= 0.5 here
  double c = 1e300;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = 1.0 / (an * d + b);
    c = b + an / c;
    h *= d * c;
    if (std::fabs(d * c - 1.0) < 1e-16) break;
  }
  return {1.0 - prefix * h, prefix * h};
}

double ref_gamma_q(double a, double y) { return ref_gamma_pq(a, y).second; }
double ref_gamma_p(double a, double y) { return ref_gamma_pq(a, y).first; }

// x with Q(dof/2, x/2) = q, by bisection (Q decreasing in x).
double ref_chi2_upper_quantile(double q, int dof) {
  const double a = 0.5 * dof;
  double lo = 0.0;
  double hi = 1.0;
  while (ref_gamma_q(a, hi) > q) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ref_gamma_q(a, mid) > q ? lo : hi) = mid;
  }
  return lo + hi;  // 2 y at the midpoint
}

double ref_normal_upper_quantile(double q) {
  double lo = -40.0;
  double hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * std::fmax(1.0, std::fabs(lo)); ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double rel_err(float got, double want) { return std::fabs(static_cast<double>(got) - want) / std::fabs(want); }

// n log-spaced false-alarm probabilities over [lo, hi], both ends included.
std::vector<float> log_grid(float lo, float hi, int n) {
  std::vector<float> q;
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / (n - 1);
    q.push_back(static_cast<float>(std::exp(std::log(static_cast<double>(lo)) * (1.0 - t) +
                                            std::log(static_cast<double>(hi)) * t)));
  }
  q.front() = lo;
  q.back() = hi;
  return q;
}

const ParamDef& pfa_def() { return kParamDefs[static_cast<size_t>(ParamId::kGateRaimPfa)]; }
const ParamDef& pfa_local_def() { return kParamDefs[static_cast<size_t>(ParamId::kGateRaimPfaLocal)]; }

TEST(ChiSquare, DoubleReferenceMatchesTables) {
  // scipy 1.10 stats.chi2.isf / stats.norm.isf at the same arguments.
  EXPECT_NEAR(ref_chi2_upper_quantile(1e-9, 16), 75.6541845085738, 1e-10);
  EXPECT_NEAR(ref_chi2_upper_quantile(0.5, 3), 2.36597388437534, 1e-12);
  EXPECT_NEAR(ref_chi2_upper_quantile(1e-3, 4), 18.4668269529032, 1e-11);
  EXPECT_NEAR(ref_normal_upper_quantile(1e-3), 3.090232306167813, 1e-12);
}

TEST(ChiSquare, NormalUpperQuantileKnownValues) {
  // References: scipy 1.10 stats.norm.isf at the float value of q (what the
  // function receives; e.g. 0.025F = 0.02500000037...). Measured error of the
  // float code (PPND7 + rounding): below 3e-7 relative.
  EXPECT_LT(rel_err(normal_upper_quantile(0.025F), 1.95996397816605), 1e-6);
  EXPECT_LT(rel_err(normal_upper_quantile(1e-3F), 3.09023229206143), 1e-6);
  EXPECT_LT(rel_err(normal_upper_quantile(0.01F), 2.32634788242731), 1e-6);
  EXPECT_LT(rel_err(normal_upper_quantile(5e-10F), 6.10941020938345), 1e-6);  // half the smallest gate.raim_pfa_local
  EXPECT_LT(rel_err(normal_upper_quantile(0.75F), -0.674489750196082), 1e-6);
  EXPECT_LT(rel_err(normal_upper_quantile(0.9F), -1.28155142969228), 1e-6);
  EXPECT_EQ(normal_upper_quantile(0.5F), 0.0F);
  EXPECT_TRUE(std::isnan(normal_upper_quantile(0.0F)));
  EXPECT_TRUE(std::isnan(normal_upper_quantile(1.0F)));
  EXPECT_TRUE(std::isnan(normal_upper_quantile(std::nanf(""))));
}

TEST(ChiSquare, UpperQuantileKnownValues) {
  // References: standard chi-square tables (NIST/SEMATECH e-Handbook 1.3.6.7.4),
  // to more digits by scipy 1.10 stats.chi2.isf at the float value of q.
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.05F, 1), 3.84145879570849), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.01F, 1), 6.63489664083816), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.01F, 2), 9.21034041667967), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.05F, 3), 7.81472787000286), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-3F, 4), 18.4668268476201), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.01F, 10), 23.2092512237958), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.95F, 5), 1.14547635571375), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-6F, 3), 30.6648497114229), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.5F, 1), 0.454936423119572), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.5F, 64), 63.334582023532), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(0.75F, 64), 56.050009266382), 2e-6);
  // The smallest allowed gate.raim_pfa: 1 - 1e-9 is 1 in float, the upper-tail API keeps it.
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-9F, 1), 37.3248931065187), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-9F, 2), 41.4465317304567), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-9F, 3), 44.8412753883613), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-9F, 16), 75.6541845775099), 2e-6);
  EXPECT_LT(rel_err(chi_square_upper_quantile(1e-9F, 64), 156.597202931536), 2e-6);
}

TEST(ChiSquare, UpperQuantileWithinTwoPpmOverPfaRangeAndAllDof) {
  // Every dof and the whole gate.raim_pfa range (RAIM needs <= 1e-5; the
  // float code measures 6e-7 at worst), plus q above 1/2 (Newton on ln P).
  std::vector<float> qs = log_grid(pfa_def().min, pfa_def().max, 41);
  for (float q : {0.6F, 0.75F, 0.9F, 0.99F, 0.999F, 0.99999F}) qs.push_back(q);
  double worst = 0.0;
  for (int dof = 1; dof <= kChiSquareMaxDof; ++dof) {
    for (float q : qs) {
      const double want = ref_chi2_upper_quantile(static_cast<double>(q), dof);
      const double err = rel_err(chi_square_upper_quantile(q, dof), want);
      worst = std::fmax(worst, err);
      EXPECT_LT(err, 2e-6) << "dof " << dof << " q " << q;
    }
  }
  std::printf("worst relative error of chi_square_upper_quantile: %.2g\n", worst);
}

TEST(ChiSquare, NormalUpperQuantileWithinOnePpmOverLocalPfaRange) {
  // RAIM's local threshold is the upper quantile of p_fa_local / 2.
  for (float pfa : log_grid(pfa_local_def().min, pfa_local_def().max, 81)) {
    const float q = 0.5F * pfa;
    EXPECT_LT(rel_err(normal_upper_quantile(q), ref_normal_upper_quantile(static_cast<double>(q))), 1e-6)
        << "q " << q;
  }
}

TEST(ChiSquare, TailAndCdfMatchDoubleReference) {
  // Float evaluation of Q and P: the exponent a ln(y/a) - (y - a) is rounded
  // (y/a to 1 ulp, times a), so the relative error grows with a and with the
  // size of the exponent's terms; bounded here by 2 ulp (1.2e-7) per unit of
  // them plus 10 ulp for the sums.
  for (int dof = 1; dof <= kChiSquareMaxDof; ++dof) {
    const double a = 0.5 * dof;
    for (float x : {1e-3F, 0.1F, 0.5F, 1.0F, 2.5F, 7.0F, 15.0F, 31.0F, 60.0F, 64.0F, 66.0F, 100.0F, 157.0F}) {
      const double y = 0.5 * static_cast<double>(x);
      const double q_ref = ref_gamma_q(a, y);
      const double p_ref = ref_gamma_p(a, y);
      const double tol = 1.2e-7 * (a + std::fabs(a * std::log(y / a)) + std::fabs(y - a) + 10.0);
      const float q = chi_square_upper_tail(x, dof);
      const float p = chi_square_cdf(x, dof);
      if (q_ref > 1e-30) {
        EXPECT_LT(rel_err(q, q_ref), tol) << "dof " << dof << " x " << x;
      }
      if (p_ref > 1e-30) {
        EXPECT_LT(rel_err(p, p_ref), tol) << "dof " << dof << " x " << x;
      }
      EXPECT_NEAR(static_cast<double>(p) + static_cast<double>(q), 1.0, 2e-7) << "dof " << dof << " x " << x;
    }
  }
}

TEST(ChiSquare, TailAndCdfInvertQuantile) {
  // Round trip on the small side: Q(quantile(q)) = q for q <= 1/2, P = 1 - q
  // above. d ln Q / d ln x is about x/2 in the tail, so the quantile's
  // relative error (<= 2e-6) shows up multiplied by up to x/2 here.
  for (int dof = 1; dof <= kChiSquareMaxDof; ++dof) {
    for (float q : {pfa_def().min, 1e-6F, 1e-3F, 0.05F, 0.5F}) {
      const float x = chi_square_upper_quantile(q, dof);
      const double tol = 2e-6 * (1.0 + 0.5 * static_cast<double>(x));
      EXPECT_LT(rel_err(chi_square_upper_tail(x, dof), static_cast<double>(q)), tol) << "dof " << dof << " q " << q;
    }
    for (float q : {0.9F, 0.999F}) {
      const float x = chi_square_upper_quantile(q, dof);
      const double tol = 2e-6 * (1.0 + static_cast<double>(dof));
      EXPECT_LT(rel_err(chi_square_cdf(x, dof), static_cast<double>(1.0F - q)), tol) << "dof " << dof << " q " << q;
    }
  }
}

TEST(ChiSquare, InvalidInputs) {
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(0.01F, 0)));
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(0.01F, kChiSquareMaxDof + 1)));
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(0.0F, 3)));
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(1.0F, 3)));
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(std::nanf(""), 3)));
  // Tail probabilities down to the smallest normal float (2x for dof 1: q/2).
  const float q_min = std::numeric_limits<float>::min();
  EXPECT_TRUE(std::isnan(normal_upper_quantile(std::numeric_limits<float>::denorm_min())));
  EXPECT_TRUE(std::isfinite(normal_upper_quantile(q_min)));
  EXPECT_TRUE(std::isnan(chi_square_upper_quantile(q_min, 1)));
  for (int dof = 1; dof <= kChiSquareMaxDof; ++dof) {
    EXPECT_TRUE(std::isfinite(chi_square_upper_quantile(2.0F * q_min, dof))) << "dof " << dof;
  }
  EXPECT_TRUE(std::isnan(chi_square_upper_tail(std::nanf(""), 3)));
  EXPECT_TRUE(std::isnan(chi_square_cdf(1.0F, 0)));
  EXPECT_EQ(chi_square_upper_tail(0.0F, 3), 1.0F);
  EXPECT_EQ(chi_square_cdf(-1.0F, 3), 0.0F);
  EXPECT_EQ(chi_square_upper_tail(std::numeric_limits<float>::infinity(), 3), 0.0F);
}

}  // namespace
}  // namespace uwbnav
