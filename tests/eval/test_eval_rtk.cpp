// Tests of tools/eval/eval_rtk: the street-canyon run family and the BDS vs
// BDS + UWB evaluation of estimator/rtk_baseline (issue 16 items 3-5). Tuning
// seeds only: the reporting seeds are for docs/lambda.md's figures.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "tools/eval/eval_rtk.hpp"

#if UWBNAV_LAMBDA

namespace uwbnav::eval {
namespace {

TEST(EvalRtk, RunFamilyDrawsNoiseAndCanyonFromTheSeedWithinTheDocumentedRanges) {
  const sim::GnssRawConfig a = rtk_eval_sim_config(3);
  const sim::GnssRawConfig b = rtk_eval_sim_config(3);
  const sim::GnssRawConfig d = rtk_eval_sim_config(4);
  EXPECT_EQ(a.sigma_code_m, b.sigma_code_m);
  EXPECT_NE(a.sigma_code_m, d.sigma_code_m);
  for (uint64_t seed = 1; seed <= 99; ++seed) {
    const sim::GnssRawConfig c = rtk_eval_sim_config(seed);
    EXPECT_GE(c.sigma_code_m, 0.3);
    EXPECT_LE(c.sigma_code_m, 0.8);
    EXPECT_GE(c.canyon_end_s - c.canyon_start_s, 20.0);
    EXPECT_LE(c.canyon_end_s - c.canyon_start_s, 40.0);
    EXPECT_LE(c.canyon_end_s, c.duration_s);
    const sim::GnssRawConfig o = rtk_eval_sim_config(seed, true);
    EXPECT_LE(o.canyon_end_s, o.canyon_start_s) << "open sky has no canyon";
  }
}

TEST(EvalRtk, FilterSettingsAreTheFilterDefaultsNotTheSimulatorsNoise) {
  const RtkEvalSettings s = rtk_eval_settings();
  const RtkParams d;
  EXPECT_EQ(s.params.sigma_code_m, d.sigma_code_m);
  EXPECT_EQ(s.params.sigma_phase_m, d.sigma_phase_m);
  EXPECT_EQ(s.params.sigma_uwb_m, d.sigma_uwb_m);
  // The baseline-walk PSD is the design value, the upper end of the family,
  // not any run's drawn walk.
  EXPECT_DOUBLE_EQ(s.relative_motion_psd_m2_s, 0.05 * 0.05);
  for (uint64_t seed = 1; seed <= 99; ++seed) {
    const sim::GnssRawConfig c = rtk_eval_sim_config(seed);
    EXPECT_LE(c.relative_walk_m_sqrt_s * c.relative_walk_m_sqrt_s, s.relative_motion_psd_m2_s);
    EXPECT_NE(c.sigma_code_m, s.params.sigma_code_m);
  }
}

TEST(EvalRtk, SummaryCountsNeverFixedRunsAsInfiniteInTheMedian) {
  std::vector<RtkRunMetrics> runs(3);
  runs[0].epochs = 10;
  runs[0].fixed_epochs = 5;
  runs[0].ttff_s = 2.0;
  runs[1].epochs = 10;
  runs[1].ttff_s = -1.0;
  runs[2].epochs = 10;
  runs[2].ttff_s = -1.0;
  const RtkSummary r = summarise_rtk("x", runs);
  EXPECT_EQ(r.never_fixed, 2);
  EXPECT_TRUE(std::isinf(r.ttff_median_s));
  EXPECT_EQ(r.ttff_max_s, 2.0);
  EXPECT_DOUBLE_EQ(r.fix_rate, 5.0 / 30.0);
  EXPECT_TRUE(std::isnan(r.canyon_fix_rate)) << "no canyon epochs: no canyon rate";
}

// The robustness model (carrier fault exclusion, residual-based R inflation,
// min_fix_sats) is what keeps canyon wrong fixes rare: without it, multipath
// absorbed into the float ambiguities is fixed to wrong integers.
TEST(EvalRtk, StreetCanyonWrongFixesStayRareOnlyWithTheRobustnessModelOnTuningSeeds) {
  RtkEvalSettings robust = rtk_eval_settings();
  RtkEvalSettings plain = robust;
  plain.params.carrier_gate_sigma = 1e9;
  plain.params.adapt_nis_threshold = 1e9;
  plain.params.min_fix_sats = kRtkMinSats;
  std::vector<RtkRunMetrics> with, without;
  for (uint64_t seed = 1; seed <= 99; ++seed) {
    const auto run = sim::simulate_gnss_raw(rtk_eval_sim_config(seed));
    with.push_back(run_rtk_once(run, true, robust));
    without.push_back(run_rtk_once(run, true, plain));
  }
  const RtkSummary a = summarise_rtk("robust", with);
  const RtkSummary b = summarise_rtk("plain", without);
  std::printf("canyon wrong fixes %.2f %% (robust) vs %.2f %% (plain); canyon fix rate %.1f %% vs %.1f %%\n",
              100.0 * a.canyon_wrong_rate, 100.0 * b.canyon_wrong_rate, 100.0 * a.canyon_fix_rate,
              100.0 * b.canyon_fix_rate);
  EXPECT_LT(a.canyon_wrong_rate, 0.04);
  EXPECT_GT(b.canyon_wrong_rate, 2.0 * a.canyon_wrong_rate);
  EXPECT_GT(a.canyon_fix_rate, b.canyon_fix_rate);
  EXPECT_LT(a.never_refixed, b.never_refixed);
}

// Seed 002's claim on this family: the inter-vehicle range shortens the time
// to first fix and raises the fix rate.
TEST(EvalRtk, UwbRangeShortensTimeToFirstFixOnTheCanyonFamilyTuningSeeds) {
  const RtkEvalSettings s = rtk_eval_settings();
  std::vector<RtkRunMetrics> bds, uwb;
  for (uint64_t seed = 1; seed <= 99; ++seed) {
    const auto run = sim::simulate_gnss_raw(rtk_eval_sim_config(seed));
    bds.push_back(run_rtk_once(run, false, s));
    uwb.push_back(run_rtk_once(run, true, s));
  }
  const RtkSummary a = summarise_rtk("BDS", bds);
  const RtkSummary b = summarise_rtk("BDS+UWB", uwb);
  EXPECT_LE(b.ttff_median_s, a.ttff_median_s - 1.0);
  EXPECT_LE(b.never_fixed, a.never_fixed);
  EXPECT_GT(b.fix_rate, a.fix_rate);
}

}  // namespace
}  // namespace uwbnav::eval

#endif  // UWBNAV_LAMBDA
