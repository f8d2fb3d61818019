// Protects the closed-form NLOS models: seed 000 eq. 3-6 (consistency p2),
// eq. 7-8 (Dempster-Shafer), seed 003 eq. 21-23 (residual factor), the
// channel power-gap evidence and the chi-square / normal quantiles of seed 001.
#include <cmath>

#include <gtest/gtest.h>

#include "estimator/nlos/channel.hpp"
#include "estimator/nlos/chi_square.hpp"
#include "estimator/nlos/consistency.hpp"
#include "estimator/nlos/dempster_shafer.hpp"
#include "estimator/nlos/residual_inflation.hpp"

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

TEST(Channel, PowerGapEvidenceNeutralBelowLoAndFullAboveHi) {
  EXPECT_FLOAT_EQ(channel_p_nlos(-80.0F, -78.0F, 6.0F, 10.0F, 0.9F), 0.5F);   // 2 dB gap
  EXPECT_FLOAT_EQ(channel_p_nlos(-92.0F, -84.0F, 6.0F, 10.0F, 0.9F), 0.7F);   // 8 dB: half way
  EXPECT_FLOAT_EQ(channel_p_nlos(-100.0F, -85.0F, 6.0F, 10.0F, 0.9F), 0.9F);  // 15 dB
  EXPECT_TRUE(std::isnan(channel_p_nlos(std::nanf(""), -85.0F, 6.0F, 10.0F, 0.9F)));
}

TEST(ChiSquare, NormalQuantileKnownValues) {
  EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 1e-9);
  EXPECT_NEAR(normal_quantile(0.999), 3.090232306167813, 1e-9);
  EXPECT_NEAR(normal_quantile(0.01), -2.326347874040841, 1e-9);
  EXPECT_NEAR(normal_quantile(1e-9), -5.997807015007686, 1e-7);
  EXPECT_TRUE(std::isnan(normal_quantile(0.0)));
}

TEST(ChiSquare, QuantileKnownValues) {
  // Reference values: standard chi-square tables (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4).
  EXPECT_NEAR(chi_square_quantile(0.95, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chi_square_quantile(0.99, 1), 6.634897, 1e-5);
  EXPECT_NEAR(chi_square_quantile(0.99, 2), 9.210340, 1e-5);
  EXPECT_NEAR(chi_square_quantile(0.95, 3), 7.814728, 1e-5);
  EXPECT_NEAR(chi_square_quantile(0.999, 4), 18.466827, 1e-4);
  EXPECT_NEAR(chi_square_quantile(0.99, 10), 23.209251, 1e-4);
  EXPECT_NEAR(chi_square_quantile(0.05, 5), 1.145476, 1e-5);
  EXPECT_NEAR(chi_square_quantile(0.999999, 3), 30.664, 1e-2);
}

TEST(ChiSquare, CdfInvertsQuantile) {
  for (int dof = 1; dof <= 16; ++dof) {
    for (double p : {0.5, 0.9, 0.99, 0.999}) {
      EXPECT_NEAR(chi_square_cdf(chi_square_quantile(p, dof), dof), p, 1e-9) << "dof " << dof;
    }
  }
  EXPECT_TRUE(std::isnan(chi_square_quantile(0.99, 0)));
}

}  // namespace
}  // namespace uwbnav
