// Family evaluation: the honesty and availability formulas on hand-made
// outputs, seed sets, and the fast family subset producing a sane table
// (no accuracy targets: the estimator changes, the figures are not pinned).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "firmware/app.hpp"
#include "tools/eval/eval_family.hpp"
#include "tools/sim/family.hpp"

namespace uwbnav::eval {
namespace {

dataset::EstimateRow est(uint64_t t_us, double x, double y, double sx, double sy, double rho, int status = 1,
                         int mode = 1) {
  dataset::EstimateRow e;
  e.t_us = t_us;
  e.pos_nav_m[0] = x;
  e.pos_nav_m[1] = y;
  e.pos_sigma_m[0] = sx;
  e.pos_sigma_m[1] = sy;
  e.pos_sigma_m[2] = 1.0;
  e.pos_xy_corr = rho;
  e.status = status;
  e.mode = mode;
  return e;
}

// Truth at the origin from 0 to 10 s, one range at 0.5 s.
dataset::Recording still_truth() {
  dataset::Recording rec;
  for (uint64_t t = 0; t <= 10000000; t += 10000) {
    dataset::TruthRow r;
    r.t_us = t;
    rec.truth.push_back(r);
  }
  dataset::UwbRow u;
  u.range.t_us = 500000;
  u.range.anchor_id = 1;
  u.nlos_label = 1;
  rec.uwb.push_back(u);
  return rec;
}

TEST(EvalFamily, CountReinitsReadsResetsAndReinitsSeparately) {
  NavDiagnostics d;
  d.resets = 2;
  d.reinits = 5;
  const RecoveryCounts c = count_reinits(d);
  EXPECT_EQ(c.resets, 2U);
  EXPECT_EQ(c.reinits, 5U);
}

TEST(EvalFamily, HonestyFiguresFollowTheirDefinitions) {
  const dataset::Recording rec = still_truth();
  ReplayResult res;
  // Before the first fix: initialising.
  res.estimates.push_back(est(1000000, 0, 0, 1, 1, 0, 0, 0));
  // Error (1, 0), sigma (1, 1), uncorrelated: NEES 1, inside every 2-sigma test.
  res.estimates.push_back(est(2000000, 1, 0, 1, 1, 0));
  // Error (3, 0), sigma (1, 1): NEES 9, outside x and h (3 > 2 sqrt 2).
  res.estimates.push_back(est(2010000, 3, 0, 1, 1, 0));
  // Error (1, 1), sigma (1, 1), correlation 0.5: NEES (1 - 1 + 1) / 0.75 = 4/3; fallback mode.
  res.estimates.push_back(est(2020000, 1, 1, 1, 1, 0.5, 2, static_cast<int>(NavMode::kUwbOnly)));
  // A gap of 1 s (invalid epoch in between), then a good epoch with no sigma.
  res.estimates.push_back(est(2500000, 0, 0, 1, 1, 0, 3, 0));
  res.estimates.push_back(est(3030000, 0, 0, NAN, NAN, 0));
  RangeReport r;
  r.t_us = 500000;
  r.anchor_id = 1;
  r.used = true;
  r.nlos = true;
  r.innovation_m = 2.0F;
  r.innovation_var_m2 = 1.0F;  // NIS 4 > 3.841
  res.ranges.push_back(r);
  RangeReport r2 = r;
  r2.t_us = 600000;
  r2.innovation_m = 1.0F;
  r2.innovation_var_m2 = 4.0F;  // NIS 0.25
  res.ranges.push_back(r2);
  res.ranges_used = 2;
  res.ranges_rejected = 1;
  res.diag.reinits = 1;

  const DriveMetrics m = drive_metrics(rec, res);
  EXPECT_TRUE(m.ok);
  EXPECT_EQ(m.epochs, 5U);  // from the first good epoch on
  EXPECT_EQ(m.good, 4U);
  EXPECT_NEAR(m.ttfe_s, 1.5, 1e-9);
  EXPECT_NEAR(m.longest_gap_s, 1.0, 1e-9);  // 2.02 s -> 3.03 s minus one cycle
  EXPECT_EQ(m.err_n, 4U);
  EXPECT_NEAR(m.max_h_m, 3.0, 1e-12);
  EXPECT_NEAR(m.rmse_h_m, std::sqrt((1.0 + 9.0 + 2.0 + 0.0) / 4.0), 1e-12);
  EXPECT_EQ(m.hon_n, 3U);
  EXPECT_EQ(m.in2s_h, 2U);
  EXPECT_EQ(m.in2s_x, 2U);
  EXPECT_EQ(m.in2s_y, 3U);
  EXPECT_EQ(m.nees_n, 3U);
  EXPECT_NEAR(m.nees_sum, 1.0 + 9.0 + 4.0 / 3.0, 1e-9);
  EXPECT_EQ(m.nees_in, 2U);
  EXPECT_EQ(m.nis_n, 2U);
  EXPECT_NEAR(m.nis_sum, 4.25, 1e-9);
  EXPECT_EQ(m.nis_in, 1U);
  EXPECT_EQ(m.fallback_n, 1U);
  EXPECT_NEAR(m.fallback_sq_sum, 2.0, 1e-12);
  EXPECT_EQ(m.fallback_hon_n, 1U);   // the fallback epoch has a sigma
  EXPECT_EQ(m.fallback_in2s_h, 1U);  // sqrt 2 <= 2 sqrt 2
  EXPECT_EQ(m.recoveries.reinits, 1U);
  EXPECT_EQ(m.nlos.tp, 1U);  // only the first range carries a label

  const CellSummary c = summarise_cell("hand", {m, m});
  EXPECT_EQ(c.drives, 2U);
  EXPECT_NEAR(c.availability, 0.8, 1e-12);
  EXPECT_NEAR(c.in2s_h, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(c.nees_in, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(c.nis_mean, 4.25 / 2.0, 1e-12);
  EXPECT_NEAR(c.fallback_share, 0.25, 1e-12);
  EXPECT_NEAR(c.fallback_in2s_h, 1.0, 1e-12);
  EXPECT_NEAR(c.inertial_in2s_h, 0.5, 1e-12);  // the IMU filter's two epochs with a sigma: one inside
  EXPECT_NEAR(c.fused_share, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(c.rmse_med, m.rmse_h_m, 1e-12);
}

// Issue 19's "ranges fused on line-of-sight data": the denominator is every
// range the recording labels LOS, including one input validation dropped (it
// never reaches the gating), so dropping good data cannot raise the share.
TEST(EvalFamily, LosFusedShareCountsEveryLabelledLosRangeAndFalseAlarmsOnlyLosCalledNlos) {
  dataset::Recording rec = still_truth();
  rec.uwb.clear();  // six ranges instead: four LOS, one NLOS, one unlabelled
  const int8_t labels[] = {0, 0, 0, 0, 1, -1};
  for (int i = 0; i < 6; ++i) {
    dataset::UwbRow u;
    u.range.t_us = 1000000 + static_cast<uint64_t>(i) * 10000;
    u.range.anchor_id = 1;
    u.nlos_label = labels[i];
    rec.uwb.push_back(u);
  }
  ReplayResult res;
  res.estimates.push_back(est(2000000, 0, 0, 1, 1, 0));
  const auto report = [&](int i, bool used, bool nlos) {
    RangeReport r;
    r.t_us = rec.uwb[static_cast<size_t>(i)].range.t_us;
    r.anchor_id = 1;
    r.used = used;
    r.nlos = nlos;
    res.ranges.push_back(r);
  };
  report(0, true, false);
  report(1, false, true);   // LOS called NLOS: a false alarm, not fused
  report(2, true, false);
  // range 3 (LOS) was dropped by input validation: no report
  report(4, false, true);   // NLOS called NLOS
  report(5, true, false);   // unlabelled: in neither figure
  const DriveMetrics m = drive_metrics(rec, res);
  EXPECT_EQ(m.los_ranges, 4U);
  EXPECT_EQ(m.los_fused, 2U);
  const CellSummary c = summarise_cell("los", {m});
  EXPECT_NEAR(c.los_fused_share, 0.5, 1e-12);
  EXPECT_NEAR(c.nlos_false_alarm, 1.0 / 3.0, 1e-12);  // FP 1 of the 3 LOS ranges the gating judged
  EXPECT_NEAR(c.nlos_precision, 0.5, 1e-12);
}

TEST(EvalFamily, DriveWithoutAFixHasNoAccuracyAndZeroAvailability) {
  const dataset::Recording rec = still_truth();
  ReplayResult res;
  for (uint64_t t = 10000; t <= 3000000; t += 10000) res.estimates.push_back(est(t, 0, 0, 1, 1, 0, 0, 0));
  const DriveMetrics m = drive_metrics(rec, res);
  EXPECT_EQ(m.good, 0U);
  EXPECT_GT(m.epochs, 0U);
  EXPECT_TRUE(std::isnan(m.rmse_h_m));
  EXPECT_TRUE(std::isnan(m.ttfe_s));
  EXPECT_NEAR(m.longest_gap_s, 2.5, 1e-9);
  EXPECT_EQ(summarise_cell("none", {m}).availability, 0.0);
}

TEST(EvalFamily, SeedSetsAreTuning1To99AndReporting1000To1999) {
  uint64_t a = 0;
  uint64_t b = 0;
  ASSERT_TRUE(parse_seed_set("tuning", a, b));
  EXPECT_EQ(a, 1U);
  EXPECT_EQ(b, 99U);
  ASSERT_TRUE(parse_seed_set("reporting", a, b));
  EXPECT_EQ(a, 1000U);
  EXPECT_EQ(b, 1999U);
  ASSERT_TRUE(parse_seed_set("5-9", a, b));
  EXPECT_EQ(a, 5U);
  EXPECT_EQ(b, 9U);
  ASSERT_TRUE(parse_seed_set("42", a, b));
  EXPECT_EQ(a, 42U);
  EXPECT_EQ(b, 42U);
  EXPECT_FALSE(parse_seed_set("9-5", a, b));
  EXPECT_FALSE(parse_seed_set("x", a, b));
  EXPECT_FALSE(parse_seed_set("-3", a, b));
}

// The fast subset (one short drive per cell here) through the firmware: every
// figure is produced and inside its possible range.
TEST(EvalFamily, FastSubsetProducesSaneFiguresForEveryCell) {
  sim::FamilyOptions fopt;
  fopt.fast = true;
  std::vector<CellSummary> rows;
  for (const sim::FamilyCell& cell : sim::family_cells()) {
    sim::SimOutput so;
    std::string err;
    ASSERT_EQ(sim::simulate_family(cell.name, 1, fopt, so, &err), Status::kOk) << err;
    ReplayOptions ropt;
    ropt.keep_in_memory = true;
    ReplayResult res;
    ASSERT_EQ(run_replay(so.rec, ropt, res, &err), Status::kOk) << err;
    const DriveMetrics m = drive_metrics(so.rec, res);
    ASSERT_TRUE(m.ok) << cell.name;
    EXPECT_GT(m.hours, 0.0) << cell.name;
    EXPECT_GT(m.epochs, 0U) << cell.name;
    EXPECT_GT(m.ranges_used, 0U) << cell.name;
    const CellSummary c = summarise_cell(cell.name, {m});
    EXPECT_GE(c.availability, 0.0) << cell.name;
    EXPECT_LE(c.availability, 1.0) << cell.name;
    if (m.good > 0) {
      EXPECT_GE(c.rmse_med, 0.0) << cell.name;
      EXPECT_TRUE(std::isfinite(c.rmse_med)) << cell.name;
      EXPECT_GE(c.max_med, c.rmse_med) << cell.name;
      EXPECT_GE(c.ttfe_med_s, 0.0) << cell.name;
    }
    for (double share : {c.in2s_h, c.in2s_x, c.in2s_y, c.nees_in, c.nis_in, c.fused_share, c.los_fused_share,
                          c.nlos_false_alarm}) {
      if (std::isfinite(share)) {
        EXPECT_GE(share, 0.0) << cell.name;
        EXPECT_LE(share, 1.0) << cell.name;
      }
    }
    if (m.nees_n > 0) {
      EXPECT_GT(c.nees_mean, 0.0) << cell.name;
    }
    if (m.nis_n > 0) {
      EXPECT_GT(c.nis_mean, 0.0) << cell.name;
    }
    EXPECT_GE(c.resets_per_h, 0.0) << cell.name;
    EXPECT_GE(c.gap_max_s, 0.0) << cell.name;
    rows.push_back(c);
  }
  // The printed table has a row per cell.
  char* buf = nullptr;
  size_t len = 0;
  std::FILE* f = open_memstream(&buf, &len);
  ASSERT_NE(f, nullptr);
  print_family_tables(f, rows, true);
  std::fclose(f);
  const std::string text(buf, len);
  std::free(buf);
  for (const sim::FamilyCell& cell : sim::family_cells()) {
    EXPECT_NE(text.find("| " + cell.name + " "), std::string::npos) << text;
  }
  EXPECT_NE(text.find("NEES"), std::string::npos);
}

TEST(EvalFamily, SameSeedsGiveTheSameFigures) {
  sim::FamilyOptions fopt;
  fopt.fast = true;
  DriveMetrics m[2];
  for (DriveMetrics& x : m) {
    sim::SimOutput so;
    std::string err;
    ASSERT_EQ(sim::simulate_family("ground_nlos", 2, fopt, so, &err), Status::kOk) << err;
    ReplayResult res;
    ASSERT_EQ(run_replay(so.rec, ReplayOptions{}, res, &err), Status::kOk) << err;
    x = drive_metrics(so.rec, res);
  }
  EXPECT_EQ(m[0].err_sq_sum, m[1].err_sq_sum);
  EXPECT_EQ(m[0].nees_sum, m[1].nees_sum);
  EXPECT_EQ(m[0].nis_sum, m[1].nis_sum);
  EXPECT_EQ(m[0].good, m[1].good);
}

}  // namespace
}  // namespace uwbnav::eval
