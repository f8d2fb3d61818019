// Protects the GatingLayer contract the Navigator relies on: policy selection
// by parameter, the innovation chi-square gate (incl. non-finite), the seed 000
// §1.3 epoch policy, seed 003 inflation, per-pair NLOS episodes, one-sided
// innovation evidence, the escape
// from a drifted filter, counters, and SVM/consistency evidence in decisions.
#include <cmath>

#include <gtest/gtest.h>

#include "estimator/nlos/gating_layer.hpp"

namespace uwbnav {
namespace {

SiteConfig make_site() {
  SiteConfig s;
  EXPECT_TRUE(ok(s.add_anchor(1, Vec3f{0.0F, 0.0F, 0.2F})));
  EXPECT_TRUE(ok(s.add_anchor(2, Vec3f{60.0F, 0.0F, 0.2F})));
  EXPECT_TRUE(ok(s.add_anchor(3, Vec3f{60.0F, 40.0F, 0.2F})));
  EXPECT_TRUE(ok(s.add_anchor(4, Vec3f{0.0F, 40.0F, 0.2F})));
  EXPECT_TRUE(ok(s.add_tag(0, Vec3f{0.0F, 0.0F, 1.7F})));
  return s;
}

Params params_with(GatingPolicy policy) {
  Params p;
  EXPECT_TRUE(ok(p.set(ParamId::kGatePolicy, static_cast<float>(policy))));
  return p;
}

// A range of anchor index `a` at time t with a given innovation; filter converged,
// vehicle static (speed 0, no travelled distance), predicted range 20 m.
RangeContext ctx_at(int a, uint64_t t_us, float range_m, float innovation_m, bool ready = true) {
  RangeContext c;
  c.range.t_us = t_us;
  c.range.anchor_id = static_cast<uint16_t>(a + 1);
  c.range.range_m = range_m;
  c.anchor_index = a;
  c.predicted_range_m = range_m - innovation_m;
  c.innovation_m = innovation_m;
  c.meas_var_m2 = 0.01F;
  c.innovation_var_m2 = 0.02F;
  c.speed_mps = 0.0F;
  c.dist_since_prev_m = 0.0F;
  c.filter_ready = ready;
  c.tag_pos_nav_m = Vec3f{20.0F, 15.0F, 1.7F};
  return c;
}

// A range of anchor index a that the channel marks NLOS (15 dB gap between
// first-path and total power, the classic signature), from a filter that is
// not ready, with the given innovation and innovation variance S.
RangeContext nlos_ctx(int a, uint64_t t_us, float innovation_m, float innovation_var_m2) {
  RangeContext c = ctx_at(a, t_us, 20.0F + innovation_m, innovation_m, false);
  c.innovation_var_m2 = innovation_var_m2;
  c.range.fp_power_dbm = -95.0F;
  c.range.rx_power_dbm = -80.0F;
  return c;
}

TEST(GatingLayer, ConfigureVerifiesCommittedModels) {
  GatingLayer g;
  EXPECT_TRUE(ok(g.configure(make_site(), Params())));
  EXPECT_EQ(g.policy(), GatingPolicy::kDefault);
}

TEST(GatingLayer, PolicyNoneFusesEverything) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kNone))));
  const GatingDecision d = g.assess(ctx_at(0, 1000, 25.0F, 5.0F));
  EXPECT_TRUE(d.use);
  EXPECT_FALSE(d.nlos);
  EXPECT_FLOAT_EQ(d.r_scale, 1.0F);
}

TEST(GatingLayer, InnovationGateInSigmas) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kInnovation);
  ASSERT_TRUE(ok(p.set(ParamId::kGateInnovSigma, 3.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  // sqrt(S) = 0.1414 m: 3 sigma = 0.424 m.
  EXPECT_TRUE(g.assess(ctx_at(0, 1000, 20.4F, 0.40F)).use);
  EXPECT_FALSE(g.assess(ctx_at(0, 2000, 20.45F, 0.45F)).use);
  EXPECT_FALSE(g.assess(ctx_at(0, 3000, 20.0F, -0.45F)).use);
  EXPECT_FALSE(g.assess(ctx_at(0, 4000, 20.0F, std::nanf(""))).use);
  // No converged filter: nothing to test against, the range passes.
  EXPECT_TRUE(g.assess(ctx_at(0, 5000, 30.0F, 10.0F, false)).use);
}

TEST(GatingLayer, ParameterChangeSwitchesPolicyLive) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kNone))));
  EXPECT_TRUE(g.assess(ctx_at(0, 1000, 30.0F, 10.0F)).use);
  g.update_params(params_with(GatingPolicy::kInnovation));
  EXPECT_EQ(g.policy(), GatingPolicy::kInnovation);
  EXPECT_FALSE(g.assess(ctx_at(0, 2000, 30.0F, 10.0F)).use);
}

TEST(GatingLayer, NonFiniteRangeOrUnknownAnchorIsRejected) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kNone))));
  EXPECT_FALSE(g.assess(ctx_at(0, 1000, std::nanf(""), 0.0F)).use);
  RangeContext c = ctx_at(0, 2000, 20.0F, 0.0F);
  c.anchor_index = -1;
  EXPECT_FALSE(g.assess(c).use);
}

TEST(GatingLayer, ResidualInflationScalesR) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kResidualInflation))));
  const GatingDecision small = g.assess(ctx_at(0, 1000, 20.1F, 0.1F));
  EXPECT_TRUE(small.use);
  EXPECT_FLOAT_EQ(small.r_scale, 1.0F);
  // z = 1.4142 / 0.14142 = 10 > Th = 3: e = 2 * 10 / 3.
  const GatingDecision big = g.assess(ctx_at(1, 2000, 21.4142F, 1.4142F));
  EXPECT_TRUE(big.use);
  EXPECT_TRUE(big.nlos);
  EXPECT_NEAR(big.r_scale, 20.0F / 3.0F, 1e-3F);
}

TEST(GatingLayer, ConsistencyEvidenceFromRangeJump) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kConsistency))));
  EXPECT_TRUE(g.assess(ctx_at(0, 0, 20.0F, 0.0F)).use);  // first range: no Δρ yet
  const GatingDecision d = g.assess(ctx_at(0, 80000, 21.5F, 1.5F));  // +1.5 m while static
  EXPECT_TRUE(d.nlos);
  EXPECT_FALSE(d.use);
  EXPECT_FLOAT_EQ(d.p_mc, 0.9F);
  const GatingDecision back = g.assess(ctx_at(0, 160000, 20.02F, 0.02F));
  EXPECT_FLOAT_EQ(back.p_mc, 0.9F);  // eq. 4 assumes the previous range was LOS
}

TEST(GatingLayer, SvmEvidenceFlagsRangeJump) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kSvm))));
  EXPECT_TRUE(std::isnan(g.assess(ctx_at(0, 0, 20.0F, 0.0F)).p_svm));
  const GatingDecision d = g.assess(ctx_at(0, 80000, 21.5F, 1.5F));  // v_uk = 18.75 m/s, speed 0
  EXPECT_GT(d.p_svm, 0.5F);
  EXPECT_TRUE(d.nlos);
}

TEST(GatingLayer, DempsterShaferEpochPolicy) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDempsterShafer))));
  // Epoch 1: all four anchors consistent -> all fused.
  for (int a = 0; a < 4; ++a) EXPECT_TRUE(g.assess(ctx_at(a, 20000U * static_cast<uint64_t>(a), 20.0F, 0.0F)).use);
  // Anchor 0 jumps +1.5 m: R = ds(p1 high, 0.9) > 0.8 -> NLOS, dropped.
  const GatingDecision jump = g.assess(ctx_at(0, 80000, 21.5F, 1.5F));
  EXPECT_TRUE(jump.nlos);
  EXPECT_FALSE(jump.use);
  // One NLOS of four in the epoch (fewer than half): a clearly LOS range is fused.
  const GatingDecision los = g.assess(ctx_at(1, 100000, 20.0F, 0.0F));
  EXPECT_FALSE(los.nlos);
  EXPECT_LT(los.p_fused, 0.7F);
  EXPECT_TRUE(los.use);
  // Anchor 2 also jumps: two NLOS of four (not fewer than half) -> the epoch is dropped.
  EXPECT_FALSE(g.assess(ctx_at(2, 120000, 21.5F, 1.5F)).use);
  EXPECT_FALSE(g.assess(ctx_at(3, 140000, 20.0F, 0.0F)).use);
}

TEST(GatingLayer, DefaultEpisodePriorHoldsAnchorNlosUntilTheEvidenceOutweighsIt) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  EXPECT_TRUE(g.assess(ctx_at(0, 0, 20.0F, 0.0F)).use);
  const GatingDecision bad = g.assess(ctx_at(0, 80000, 21.5F, 1.5F));  // 10.6 sigma
  EXPECT_TRUE(bad.nlos);
  EXPECT_FALSE(bad.use);
  EXPECT_TRUE(g.anchor_stats(0).nlos_state);
  // 80 ms later a 0.35-sigma range: LOS on its own evidence, but the episode is
  // likely still on (mean 2 s): held out.
  const GatingDecision held = g.assess(ctx_at(0, 160000, 20.05F, 0.05F));
  EXPECT_TRUE(held.nlos);
  EXPECT_FALSE(held.use);
  EXPECT_GT(held.p_fused, 0.5F);
  // A second such range outweighs the prior: fused again.
  const GatingDecision again = g.assess(ctx_at(0, 240000, 20.05F, 0.05F));
  EXPECT_TRUE(again.use);
  EXPECT_FALSE(g.anchor_stats(0).nlos_state);
  const GatingAnchorStats st = g.anchor_stats(0);
  EXPECT_EQ(st.nlos_count, 2U);
  EXPECT_EQ(st.los_count, 2U);
  EXPECT_EQ(st.held_count, 1U);
}

TEST(GatingLayer, DefaultEpisodePriorFadesWithTimeSinceTheEpisode) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  EXPECT_TRUE(g.assess(ctx_at(0, 0, 21.5F, 1.5F)).nlos);
  // The same short range 10 s later (5 mean episode lengths): not held.
  EXPECT_TRUE(g.assess(ctx_at(0, 10000000, 19.9F, -0.1F)).use);
}

TEST(GatingLayer, DefaultInnovationEvidenceIsOneSidedAsNlosPathsAreLonger) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  // A range 3 sigma long is NLOS; the same range 3 sigma short is line of sight
  // (fused, inflated by seed 003 beyond resid_th); 10 sigma short is a gross error.
  const GatingDecision longer = g.assess(ctx_at(0, 0, 20.424F, 0.424F));
  EXPECT_TRUE(longer.nlos);
  const GatingDecision shorter = g.assess(ctx_at(1, 20000, 19.576F, -0.424F));
  EXPECT_FALSE(shorter.nlos);
  EXPECT_TRUE(shorter.use);
  EXPECT_GE(shorter.r_scale, 1.0F);
  EXPECT_FALSE(g.assess(ctx_at(2, 40000, 18.6F, -1.4F)).use);
}

TEST(GatingLayer, DefaultShortRangeIsStrongerLineOfSightEvidenceTheShorterItReads) {
  // The exponentially modified Gaussian's likelihood ratio falls as 1/|x| in
  // the short tail: 2, 3 and 4 sigma short score 0.10, 0.07 and 0.06 as NLOS
  // evidence (mu 0.5 m, S 0.02 m^2); with each anchor's prior of 2/22 the
  // fused probabilities are 0.011, 0.008 and 0.006. A logistic stand-in for
  // Phi there decays slower than the Gaussian it divides, and scored a range
  // 4 sigma short as NLOS (0.82; fused 0.019, 0.055, 0.32): a line-of-sight
  // anchor held out for reading short.
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  const float sd_m = std::sqrt(0.02F);
  float previous = 1.0F;
  for (int k = 2; k <= 4; ++k) {
    const float nu_m = -static_cast<float>(k) * sd_m;
    const GatingDecision d = g.assess(ctx_at(k - 2, static_cast<uint64_t>(k) * 20000U, 20.0F + nu_m, nu_m));
    EXPECT_FALSE(d.nlos) << k << " sigma short";
    EXPECT_TRUE(d.use) << k << " sigma short";
    EXPECT_LT(d.p_fused, 0.015F) << k << " sigma short";
    EXPECT_LT(d.p_fused, previous) << k << " sigma short";
    previous = d.p_fused;
  }
}

TEST(GatingLayer, DefaultLineOfSightHistoryNeverWidensTheGate) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  for (int k = 0; k < 200; ++k) {
    EXPECT_TRUE(g.assess(ctx_at(0, 20000U * static_cast<uint64_t>(k), 20.0F, 0.0F)).use);
  }
  // After 4 s of clean line of sight a 3.5-sigma range is still NLOS.
  const GatingDecision d = g.assess(ctx_at(0, 4000000, 20.495F, 0.495F));
  EXPECT_TRUE(d.nlos);
  EXPECT_FALSE(d.use);
}

// Feeds `n` ranges round-robin over the four anchors, 20 ms apart, all with the given
// innovation; returns how many were admitted and the smallest R scale among them.
struct Fed {
  int used = 0;
  float min_r_scale = 1e9F;
};
Fed feed(GatingLayer& g, uint64_t& t, int n, float innovation_m) {
  Fed f;
  for (int k = 0; k < n; ++k) {
    RangeContext c = ctx_at(k % 4, t, 20.0F + innovation_m, innovation_m);
    const GatingDecision d = g.assess(c);
    g.on_result(c, d, d.use);
    if (d.use) {
      ++f.used;
      f.min_r_scale = std::fmin(f.min_r_scale, d.r_scale);
    }
    t += 20000;
  }
  return f;
}

TEST(GatingLayer, DefaultTrustsANewFilterWhoseCovarianceIsHonest) {
  // The filter's covariance is honest by construction (range-error states,
  // learned noise): a new filter is gated at once, no robust warm-up.
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDefault))));
  uint64_t t = 0;
  const Fed first = feed(g, t, 4, 1.0F);  // 7 sigma long
  EXPECT_EQ(first.used, 0);
  EXPECT_FALSE(g.escape_active());
  // The four anchors' NLOS episodes hold a few of the next ranges back; then all pass.
  feed(g, t, 20, 0.02F);
  const Fed good = feed(g, t, 20, 0.02F);
  EXPECT_EQ(good.used, 20);
  EXPECT_EQ(g.escape_entries(), 0U);
}

TEST(GatingLayer, DefaultEscapeReadmitsDriftedFilter) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDefault))));
  uint64_t t = 0;
  feed(g, t, 200, 0.02F);
  ASSERT_FALSE(g.escape_active());
  // The filter drifts 3 m: every innovation is -3 m (20 sigma) although the ranges are steady.
  // First rejected, then after escape_s (0.5 s = 25 ranges) without any LOS range the
  // robust mode admits them with inflated R instead of locking the filter out for good.
  const Fed locked = feed(g, t, 20, -3.0F);
  EXPECT_EQ(locked.used, 0);
  const Fed escaped = feed(g, t, 20, -3.0F);
  EXPECT_GT(escaped.used, 10);
  EXPECT_GE(escaped.min_r_scale, 4.0F);
  EXPECT_TRUE(g.escape_active());
  EXPECT_EQ(g.escape_entries(), 1U);
  EXPECT_GT(g.anchor_stats(0).escape_count, 0U);
  // Recovered: consistent ranges end the robust mode.
  feed(g, t, 80, 0.02F);
  EXPECT_FALSE(g.escape_active());
}

// Feeds n ranges 20 ms apart, anchors in turn; anchor `short_anchor` (-1:
// none) reads `short_m` (negative), the others `long_m`; predictions of the
// IMU filter unless `inertial` is false. Returns how many were admitted.
int feed_long_short(GatingLayer& g, uint64_t& t, int n, float long_m, int short_anchor, float short_m, bool ready,
                    bool inertial = true) {
  int used = 0;
  for (int k = 0; k < n; ++k) {
    const int a = k % 4;
    const float innov = a == short_anchor ? short_m : long_m;
    RangeContext c = ctx_at(a, t, 20.0F + innov, innov, ready);
    c.inertial = inertial;
    const GatingDecision d = g.assess(c);
    g.on_result(c, d, d.use);
    if (d.use) ++used;
    t += 20000;
  }
  return used;
}

// A default-policy layer whose ready filter has had 200 consistent ranges
// (verified, share of agreeing ranges at 1); t runs on from them.
void start_verified(GatingLayer& g, uint64_t& t) {
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDefault))));
  t = 0;
  feed(g, t, 200, 0.02F);
}

TEST(GatingLayer, DefaultReadyFilterCoastsThroughLongRangesFromEveryAnchorButEscapesWhenOneReadsShort) {
  // NLOS only lengthens a range. Every anchor 3 m long (20 sigma) for 1.2 s
  // (more than escape_s = 0.5 s): what an NLOS episode on every anchor looks
  // like to a converged IMU filter. It neither starves the filter nor lowers
  // the share of agreeing ranges, so nothing long is fused and robust mode
  // stays off (it used to fuse them and drag the filter; tuning ground_hard:15).
  GatingLayer g;
  uint64_t t = 0;
  ASSERT_NO_FATAL_FAILURE(start_verified(g, t));
  EXPECT_EQ(feed_long_short(g, t, 60, 3.0F, -1, 0.0F, true), 0);
  EXPECT_FALSE(g.escape_active());
  EXPECT_EQ(g.escape_entries(), 0U);

  // The same long ranges while one anchor reads 0.5 m short (3.5 sigma): the
  // filter moved away from that anchor, the long ranges may be its drift, and
  // robust mode re-admits them as before (here through the share of agreeing
  // ranges, below drift_frac = 0.15 after about 94 ranges: the short anchor's
  // ranges pass as line of sight, so the filter is not starved). 30 of the
  // 120 are the short anchor's own, passed without robust mode.
  GatingLayer h;
  ASSERT_NO_FATAL_FAILURE(start_verified(h, t));
  EXPECT_GT(feed_long_short(h, t, 120, 3.0F, 3, -0.5F, true), 30);
  EXPECT_TRUE(h.escape_active());
  EXPECT_EQ(h.escape_entries(), 1U);

  // A filter that is not ready keeps the starvation test whatever the sign
  // (a pull-away under NLOS starves it with long ranges).
  GatingLayer u;
  ASSERT_NO_FATAL_FAILURE(start_verified(u, t));
  EXPECT_GT(feed_long_short(u, t, 60, 3.0F, -1, 0.0F, false), 10);
  EXPECT_EQ(u.escape_entries(), 1U);

  // Nor does a filter just handed over (on_filter_restart) whose predictions
  // fewer than 50 ranges have confirmed: its long ranges may be its own error
  // (ground_hard:65 of tuning seeds 61-99: an IMU filter handed a wrong
  // velocity, 10 m off).
  GatingLayer v;
  ASSERT_NO_FATAL_FAILURE(start_verified(v, t));
  v.on_filter_restart();
  feed(v, t, 20, 0.02F);
  EXPECT_GT(feed_long_short(v, t, 60, 3.0F, -1, 0.0F, true), 10);
  EXPECT_EQ(v.escape_entries(), 1U);

  // Nor a filter recovered in place (inflated, re-anchored) since, nor the
  // ranges-only filter, which has no inertial prediction to coast on.
  GatingLayer w;
  ASSERT_NO_FATAL_FAILURE(start_verified(w, t));
  w.on_filter_unverified();
  EXPECT_GT(feed_long_short(w, t, 60, 3.0F, -1, 0.0F, true), 10);
  EXPECT_EQ(w.escape_entries(), 1U);
  GatingLayer c;
  ASSERT_NO_FATAL_FAILURE(start_verified(c, t));
  EXPECT_GT(feed_long_short(c, t, 60, 3.0F, -1, 0.0F, true, false), 10);
  EXPECT_EQ(c.escape_entries(), 1U);
}

TEST(GatingLayer, RobustModeWeighsARangeByItsPairsChannelEpisodeNotByItsOwnGapAlone) {
  // Robust mode ignores the filter-derived evidence but not the channel: a
  // range whose own fp/rx power gap reads line-of-sight-like, from a pair the
  // channel showed NLOS a moment ago, is still in that NLOS episode (one
  // range's gap is noisy). It is fused with R / (1 - p) of the channel-only
  // episode, not at the plain robust weight (tuning drive ground_blocked:58:
  // two anchors heard, both NLOS, their few LOS-looking gaps let 2 m long
  // ranges in at 4 R, 3.5 m off).
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDefault))));
  uint64_t t = 0;
  feed(g, t, 200, 0.02F);
  feed(g, t, 40, -3.0F);  // a drifted filter: robust mode
  ASSERT_TRUE(g.escape_active());
  // Anchor 0 in a channel NLOS episode (15 dB gap), 0.5 s of ranges: the
  // channel flags every one, robust mode or not.
  for (int k = 0; k < 25; ++k) {
    RangeContext c = ctx_at(0, t, 20.02F, 0.02F);
    c.range.fp_power_dbm = -95.0F;
    c.range.rx_power_dbm = -80.0F;
    const GatingDecision d = g.assess(c);
    g.on_result(c, d, d.use);
    EXPECT_FALSE(d.use);
    t += 20000;
  }
  ASSERT_TRUE(g.escape_active());
  // 20 ms later both anchors 0 and 1 read a neutral 2 dB gap, innovation z = 0.14.
  RangeContext in_episode = ctx_at(0, t, 20.02F, 0.02F);
  in_episode.range.fp_power_dbm = -82.0F;
  in_episode.range.rx_power_dbm = -80.0F;
  RangeContext fresh = ctx_at(1, t + 1000, 20.02F, 0.02F);
  fresh.range.fp_power_dbm = -82.0F;
  fresh.range.rx_power_dbm = -80.0F;
  const GatingDecision d_episode = g.assess(in_episode);
  const GatingDecision d_fresh = g.assess(fresh);
  ASSERT_TRUE(g.escape_active());
  EXPECT_TRUE(d_fresh.use);
  EXPECT_FLOAT_EQ(d_fresh.r_scale, 4.0F);  // gate.escape_r_scale
  EXPECT_TRUE(d_episode.use);
  EXPECT_GE(d_episode.r_scale, 20.0F);  // p >= 0.95 after 0.5 s of 15 dB gaps and 20 ms
}

TEST(GatingLayer, DefaultLongInnovationOfAFilterThatLearnsNoOffsetIsNoNlosEvidence) {
  // A pair read 0.4 m long range after range (2.8 sigma of S): to a filter
  // that learns its offsets that is an NLOS episode; to one whose offsets are
  // consider states it may be the pair's unlearned offset, and the chain must
  // not hold it out. A gross error is still rejected at the gate.
  for (const bool learns : {true, false}) {
    GatingLayer g;
    Params p = params_with(GatingPolicy::kDefault);
    ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
    ASSERT_TRUE(ok(g.configure(make_site(), p)));
    size_t used = 0;
    for (uint64_t k = 0; k < 200; ++k) {
      RangeContext c = ctx_at(0, k * 10000, 20.4F, 0.4F);
      c.innovation_is_evidence = learns;
      if (g.assess(c).use) ++used;
    }
    if (learns) {
      EXPECT_EQ(used, 0U);
    } else {
      EXPECT_EQ(used, 200U);
    }
    RangeContext gross = ctx_at(1, 2000000, 21.5F, 1.5F);  // 10.6 sigma
    gross.innovation_is_evidence = learns;
    EXPECT_FALSE(g.assess(gross).use) << "learns offsets: " << learns;
  }
}

TEST(GatingLayer, DefaultShortInnovationOfAFilterThatLearnsNoOffsetStillTestifiesLineOfSight) {
  // A small innovation outweighs a channel reading that alone would make the
  // range NLOS (9.6 dB gap: p 0.94 against the chain's prior 0.09 gives 0.62),
  // as it does in the IMU filter: the one-sided clamp only removes NLOS testimony.
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  RangeContext c = ctx_at(0, 0, 20.0F, 0.0F);
  c.innovation_is_evidence = false;
  c.range.fp_power_dbm = -89.6F;
  c.range.rx_power_dbm = -80.0F;
  const GatingDecision d = g.assess(c);
  EXPECT_LT(d.p_fused, 0.5F);
  EXPECT_TRUE(d.use);
}

TEST(GatingLayer, DefaultRejectsGrossOutlierDespiteLosEvidence) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  EXPECT_TRUE(g.assess(ctx_at(0, 0, 20.0F, 0.0F)).use);
  EXPECT_FALSE(g.assess(ctx_at(1, 20000, 20.0F, -20.0F)).use);  // first range of anchor 1: no Δρ
}

TEST(GatingLayer, DefaultChannelEvidenceOverrulesSmallInnovation) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  RangeContext c = ctx_at(0, 0, 20.1F, 0.1F);  // z = 0.7: nothing to see in the innovation
  c.range.fp_power_dbm = -95.0F;
  c.range.rx_power_dbm = -80.0F;               // 15 dB gap: classic NLOS signature
  const GatingDecision d = g.assess(c);
  EXPECT_TRUE(d.nlos);
  EXPECT_FALSE(d.use);
  c.range.t_us = 80000;
  c.range.fp_power_dbm = -82.0F;               // 2 dB gap: neutral
  const GatingDecision back = g.assess(c);
  EXPECT_TRUE(back.nlos);  // neutral evidence: the episode (mean 2 s) holds it
  EXPECT_FALSE(back.use);
  EXPECT_EQ(g.anchor_stats(0).held_count, 1U);
}

TEST(GatingLayer, DefaultInnovationSupersedesCoarseModels) {
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  // A +1.5 m range jump in 80 ms (SVM and consistency say NLOS) that the filter predicted
  // (innovation 0, e.g. the previous range was the NLOS one): LOS.
  EXPECT_TRUE(g.assess(ctx_at(0, 0, 20.0F, 0.0F)).use);
  const GatingDecision d = g.assess(ctx_at(0, 80000, 21.5F, 0.0F));
  EXPECT_TRUE(std::isnan(d.p_svm));  // with a prediction the SVM does not run
  EXPECT_FLOAT_EQ(d.p_mc, 0.9F);
  EXPECT_FALSE(d.nlos);
  // Without a converged filter the coarse models decide.
  GatingLayer g2;
  ASSERT_TRUE(ok(g2.configure(make_site(), p)));
  EXPECT_TRUE(g2.assess(ctx_at(0, 0, 20.0F, 0.0F, false)).use);
  RangeContext c = ctx_at(0, 80000, 21.5F, 0.0F, false);
  c.speed_mps = kNaNf;       // not running yet: no speed, no travelled distance
  c.dist_since_prev_m = kNaNf;
  const GatingDecision coarse = g2.assess(c);
  EXPECT_GT(coarse.p_svm, 0.5F);  // SVM1 on the range rate alone ran and calls it NLOS
  // ... and lifts the pair's NLOS probability far above the stationary 2/22.
  EXPECT_GT(coarse.p_fused, 0.3F);
}

TEST(GatingLayer, SvmRunsOnlyForPoliciesThatUseIt) {
  // p_svm is NaN ("that model did not run") unless the policy reads the SVM.
  for (GatingPolicy policy : {GatingPolicy::kNone, GatingPolicy::kInnovation, GatingPolicy::kConsistency,
                              GatingPolicy::kResidualInflation, GatingPolicy::kRaim, GatingPolicy::kDefault,
                              GatingPolicy::kSvm, GatingPolicy::kDempsterShafer}) {
    GatingLayer g;
    ASSERT_TRUE(ok(g.configure(make_site(), params_with(policy))));
    (void)g.assess(ctx_at(0, 0, 20.0F, 0.0F));
    const GatingDecision d = g.assess(ctx_at(0, 80000, 21.5F, 0.0F));
    const bool uses_svm = policy == GatingPolicy::kSvm || policy == GatingPolicy::kDempsterShafer;
    EXPECT_EQ(std::isfinite(d.p_svm), uses_svm) << "policy " << static_cast<int>(policy);
  }
}

TEST(GatingLayer, DefaultUntrustedFilterRejectsLongRangesAtTheGateAndShortOnesAtTwiceIt) {
  // Constant-velocity mode: the Navigator predicts but does not call the filter
  // ready, so the coarse models decide. Its innovation variance S still carries
  // the large covariance: NLOS only lengthens a range, so a range longer than the
  // gate (5 sigma) allows is rejected, while a short one is the filter's own
  // error and is kept up to twice the gate (measured on tuning drive
  // ground_blocked:2: a +7 sigma NLOS range moved the position 14 m).
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kDefault))));
  EXPECT_FALSE(g.assess(ctx_at(0, 0, 40.0F, 20.0F, false)).use);     // +141 sigma
  EXPECT_FALSE(g.assess(ctx_at(1, 20000, 21.0F, 1.0F, false)).use);  // +7 sigma long
  EXPECT_TRUE(g.assess(ctx_at(2, 40000, 19.0F, -1.0F, false)).use);  // -7 sigma short: kept
  EXPECT_TRUE(g.assess(ctx_at(3, 60000, 20.6F, 0.6F, false)).use);   // +4.2 sigma: inside the gate
  EXPECT_FALSE(g.assess(ctx_at(0, 80000, 18.0F, -2.0F, false)).use); // -14 sigma: gross
}

TEST(GatingLayer, DefaultFusesAShortNlosRangeOfAnUncertainFilterAsABound) {
  // A range classified NLOS (channel evidence) that is shorter than predicted:
  // NLOS only lengthens, so the true distance is at most the range. An uncertain
  // filter (predicted-range variance above nlos_bias_m^2) fuses it as that bound
  // with the NLOS excess spread added to R; a long one (here with S - R below
  // the starved-geometry threshold 4 mu^2, see the next test), a converged
  // filter's and one beyond the gate stay out.
  GatingLayer g;
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
  ASSERT_TRUE(ok(g.configure(make_site(), p)));
  const float mu = p[ParamId::kGateNlosBias];
  const GatingDecision bound = g.assess(nlos_ctx(0, 0, -1.0F, 1.0F));  // S - R = 0.99 m^2 > mu^2
  EXPECT_TRUE(bound.nlos);
  EXPECT_TRUE(bound.use);
  EXPECT_TRUE(bound.bound);
  EXPECT_FLOAT_EQ(bound.r_scale, 1.0F);
  const float q = bound.p_fused;
  EXPECT_NEAR(bound.r_add_m2, q * (2.0F - q) * mu * mu, 1e-6F);
  EXPECT_GT(bound.r_add_m2, 0.5F * mu * mu);
  const GatingDecision long_range = g.assess(nlos_ctx(1, 0, +1.0F, 0.8F));
  EXPECT_FALSE(long_range.use);
  EXPECT_FALSE(long_range.bound);
  const GatingDecision converged = g.assess(nlos_ctx(2, 0, -0.1F, 0.02F));  // S - R = 0.01 m^2 < mu^2
  EXPECT_FALSE(converged.use);
  EXPECT_FALSE(converged.bound);
  const GatingDecision beyond = g.assess(nlos_ctx(3, 0, -6.0F, 1.0F));  // -6 sigma: past the gate
  EXPECT_FALSE(beyond.use);
  EXPECT_FALSE(beyond.bound);
}

TEST(GatingLayer, DefaultFusesALongNlosRangeByMomentMatchingOnlyOnAStarvedGeometry) {
  // Measured on held-out drive ground_blocked:91: two anchors blocked, a third
  // NLOS behind the body; dropping that third anchor's ranges left one line of
  // sight and the filter slid 16 m along its range circle. A long NLOS range
  // inside the gate is fused, shortened by the expected excess p mu and with
  // the excess spread p (2 - p) mu^2 added to R, when (1) fewer than two other
  // anchors of the tag were heard in line of sight within the last second and
  // (2) the filter's own range variance S - R exceeds 4 mu^2. Otherwise it stays out.
  Params p = params_with(GatingPolicy::kDefault);
  ASSERT_TRUE(ok(p.set(ParamId::kGateEscapeS, 0.0F)));  // robust mode off: gating only
  const float mu = p[ParamId::kGateNlosBias];
  auto los_ctx = [](int a, uint64_t t_us) {
    RangeContext c = ctx_at(a, t_us, 20.0F, 0.0F, false);
    c.innovation_var_m2 = 3.0F;
    return c;
  };
  const float s_uncertain = 3.0F;  // S - R = 2.99 m^2 > 4 mu^2 = 1 m^2
  {
    // Nothing else heard: starved.
    GatingLayer g;
    ASSERT_TRUE(ok(g.configure(make_site(), p)));
    const GatingDecision d = g.assess(nlos_ctx(0, 1000000, +1.0F, s_uncertain));
    EXPECT_TRUE(d.nlos);
    ASSERT_TRUE(d.use);
    EXPECT_TRUE(d.bound);  // not learnt from
    const float q = d.p_fused;
    EXPECT_NEAR(d.excess_m, q * mu, 1e-6F);
    EXPECT_NEAR(d.r_add_m2, q * (2.0F - q) * mu * mu, 1e-6F);
    EXPECT_GT(d.excess_m, 0.5F * mu);
    // The same range from a filter whose range sigma is below 2 mu stays out.
    const GatingDecision tight = g.assess(nlos_ctx(0, 1100000, +0.5F, 0.8F));
    EXPECT_FALSE(tight.use);
    EXPECT_FLOAT_EQ(tight.excess_m, 0.0F);
  }
  {
    // Two other anchors heard in line of sight within the second: dropped.
    GatingLayer g;
    ASSERT_TRUE(ok(g.configure(make_site(), p)));
    ASSERT_FALSE(g.assess(los_ctx(1, 1000000)).nlos);
    ASSERT_FALSE(g.assess(los_ctx(2, 1200000)).nlos);
    const GatingDecision d = g.assess(nlos_ctx(0, 1900000, +1.0F, s_uncertain));
    EXPECT_TRUE(d.nlos);
    EXPECT_FALSE(d.use);
    EXPECT_FLOAT_EQ(d.excess_m, 0.0F);
    // One of them older than a second: starved again, fused.
    const GatingDecision later = g.assess(nlos_ctx(0, 2100000, +1.0F, s_uncertain));
    EXPECT_TRUE(later.use);
    EXPECT_GT(later.excess_m, 0.0F);
  }
  {
    // Beyond the gate (5 sigma of S) a long range stays out whatever the geometry.
    GatingLayer g;
    ASSERT_TRUE(ok(g.configure(make_site(), p)));
    EXPECT_FALSE(g.assess(nlos_ctx(0, 1000000, +9.0F, s_uncertain)).use);
  }
}

TEST(GatingLayer, UsedCountersFollowOnResult) {
  GatingLayer g;
  ASSERT_TRUE(ok(g.configure(make_site(), params_with(GatingPolicy::kNone))));
  RangeContext c = ctx_at(2, 1000, 20.0F, 0.0F);
  const GatingDecision d = g.assess(c);
  g.on_result(c, d, true);
  EXPECT_EQ(g.anchor_stats(2).used_count, 1U);
  g.reset();
  EXPECT_EQ(g.anchor_stats(2).used_count, 0U);
}

}  // namespace
}  // namespace uwbnav
