// `uwbnav calibrate` solver (tools/calib/calibrate.hpp): recovers known
// per-pair range offsets of a simulated 3-tag trolley (1 cm quantisation)
// within 2 cm from truth, from surveyed static points and by self-calibration
// up to the documented gauge; rejects outliers and reports what it rejected;
// reports an unobservable geometry instead of numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "calib/trolley_recording.hpp"
#include "tools/calib/calibrate.hpp"
#include "tools/dataset/calibration.hpp"

namespace uwbnav::testing {
namespace {

struct Errors {
  double max_abs_m = 0.0;        // max |estimated - true|
  double max_abs_demeaned_m = 0.0;  // the same after removing the mean difference (the gauge)
  double max_z = 0.0;            // max |estimated - true| / sigma
};

Errors compare(const calib::Result& r, const std::vector<double>& truth) {
  Errors e;
  EXPECT_EQ(r.pairs.size(), truth.size());
  double mean = 0.0;
  for (size_t p = 0; p < truth.size(); ++p) mean += r.pairs[p].offset_m - truth[p];
  mean /= static_cast<double>(truth.size());
  for (size_t p = 0; p < truth.size(); ++p) {
    const double d = r.pairs[p].offset_m - truth[p];
    e.max_abs_m = std::max(e.max_abs_m, std::fabs(d));
    e.max_abs_demeaned_m = std::max(e.max_abs_demeaned_m, std::fabs(d - mean));
    e.max_z = std::max(e.max_z, std::fabs(d) / r.pairs[p].sigma_m);
  }
  return e;
}

TEST(CalibrateTruth, RecoversSimulatedPairOffsetsOfA3TagTrolleyWithin2cm) {
  for (uint64_t seed : {11U, 12U}) {
    SCOPED_TRACE(seed);
    const TrolleyRecording t = make_trolley(seed);
    calib::Options opt;
    calib::Result r;
    std::string err;
    ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
    EXPECT_EQ(r.method, calib::Method::kTruth);
    EXPECT_TRUE(r.observable);
    EXPECT_TRUE(r.converged);
    ASSERT_EQ(r.pairs.size(), 24U);
    const Errors e = compare(r, t.offset_m);
    EXPECT_LT(e.max_abs_m, 0.02);
    EXPECT_LT(e.max_z, 4.5) << "claimed sigmas too small";
    for (const auto& p : r.pairs) {
      EXPECT_GT(p.used, 600U);
      EXPECT_LT(p.sigma_m, 0.01);
    }
    // 5 cm noise + 1 cm quantisation: the residual RMS is the noise.
    EXPECT_NEAR(r.resid_rms_m, 0.05, 0.01);
    // Anchor + tag delays explain the pairs up to the +-8 mm pair-specific part.
    ASSERT_TRUE(r.decomposition.testable);
    EXPECT_LT(r.decomposition.resid_rms_m, 0.01);
    for (size_t a = 0; a < 8; ++a) {
      // true d_anchor with the gauge sum(d_tag) = 0: 0.08 + 0.02 a + mean(d_tag) = 0.13 + 0.02 a
      EXPECT_NEAR(r.decomposition.anchor_m[a], 0.13 + 0.02 * static_cast<double>(a), 0.01);
    }
  }
}

TEST(CalibrateTruth, GrossOutliersAreRejectedCountedAndDoNotBiasTheOffsets) {
  const TrolleyRecording t = make_trolley(13, 60.0, true, 0.03);
  calib::Options opt;
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_GT(r.ranges_rejected, r.ranges_total / 100);  // ~3 % outliers of 0.5-5 m
  EXPECT_LT(r.ranges_rejected, r.ranges_total / 10);
  EXPECT_LT(compare(r, t.offset_m).max_abs_m, 0.02);
}

TEST(CalibrateSelf, RecoversOffsetsWithoutReferenceInsideTheAnchorHull) {
  TrolleyRecording t = make_trolley(14);
  t.rec.truth.clear();  // no reference at all
  calib::Options opt;   // trajectory knots every 0.1 s, one unknown body height
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_EQ(r.method, calib::Method::kSelf);
  EXPECT_TRUE(r.converged);
  // Inside the anchor hull a common lengthening of every range cannot be
  // explained by moving the trolley (nor by its unknown height: the ranges
  // differ in length), so even the common offset is observable.
  EXPECT_TRUE(r.observable);
  EXPECT_LT(r.common_sigma_m, 0.01);
  const Errors e = compare(r, t.offset_m);
  EXPECT_LT(e.max_abs_m, 0.02);
  EXPECT_LT(e.max_z, 4.5);
  ASSERT_EQ(r.body_z_m.size(), 1U);
  EXPECT_NEAR(r.body_z_m[0], 0.0, 0.05);
}

TEST(CalibrateTruth, SystematicSigmaMeasuresTheSurveyErrorThatTheOffsetsCannotHold) {
  // An anchor surveyed d off moves its ranges by -u.d: a pair's offset holds
  // the mean over the drive's lines of sight u, the rest changes as u turns
  // and stays in the residuals against the reference, correlated from one
  // range to the next. The white ranging noise (5 cm) and the 1 cm
  // quantisation do not correlate.
  double measured[2] = {0.0, 0.0};
  const double survey_sigma_m[2] = {0.0, 0.05};
  for (int k = 0; k < 2; ++k) {
    const TrolleyRecording t = make_trolley(15, 60.0, true, 0.0, "1.5 1.2 0 0", survey_sigma_m[k]);
    calib::Result r;
    std::string err;
    ASSERT_EQ(calib::calibrate({t.rec}, calib::Options{}, r, &err), Status::kOk) << err;
    ASSERT_EQ(r.method, calib::Method::kTruth);
    measured[k] = r.systematic_sigma_m;
    const dataset::CalibrationFile f = calib::to_calibration_file(r, {"trolley_test"});
    EXPECT_FLOAT_EQ(f.systematic_sigma_m, static_cast<float>(r.systematic_sigma_m));
    // A self-calibration's trajectory bends to part of the survey error: it
    // measures the figure too, but its file does not carry it.
    TrolleyRecording self = t;
    self.rec.truth.clear();
    calib::Result rs;
    ASSERT_EQ(calib::calibrate({self.rec}, calib::Options{}, rs, &err), Status::kOk) << err;
    ASSERT_EQ(rs.method, calib::Method::kSelf);
    EXPECT_TRUE(std::isnan(calib::to_calibration_file(rs, {"trolley_test"}).systematic_sigma_m));
  }
  std::printf("systematic sigma: %.4f m surveyed exactly, %.4f m surveyed to 5 cm\n", measured[0], measured[1]);
  EXPECT_LT(measured[0], 0.01);  // parked quantisation and the reference's own interpolation remain
  EXPECT_GT(measured[1], 0.015);
  EXPECT_GT(measured[1], 2.5 * measured[0]);
  EXPECT_LT(measured[1], 0.05);  // what the offsets hold is gone: less than the survey error itself
}

TEST(CalibrateSelf, FarOutsideTheAnchorsTheCommonOffsetIsTheReportedGaugeAndCanBeFixed) {
  // The same loop 40 m north of the room: every anchor lies within +-6 deg of
  // south, so lengthening every range is nearly the same as moving north.
  TrolleyRecording t = make_trolley(22, 60.0, true, 0.0, "1.5 40 0 0");
  t.rec.truth.clear();
  calib::Options opt;
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_FALSE(r.observable);
  EXPECT_GT(r.common_sigma_m, 0.02);
  ASSERT_FALSE(r.weak.empty());
  EXPECT_NE(r.weak[0].what.find("common offset of all pairs"), std::string::npos) << r.weak[0].what;
  EXPECT_LT(compare(r, t.offset_m).max_abs_demeaned_m, 0.02);  // differences between pairs are still there

  // Fixing the gauge (the mean offset known, e.g. from one reference point)
  // makes every offset observable and right within 2 cm.
  double mean = 0.0;
  for (double v : t.offset_m) mean += v;
  opt.fix_common = true;
  opt.common_offset_m = mean / static_cast<double>(t.offset_m.size());
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_TRUE(r.observable);
  EXPECT_LT(compare(r, t.offset_m).max_abs_m, 0.02);
}

TEST(CalibrateSelf, KnownBodyHeightMakesTheCommonOffsetObservable) {
  TrolleyRecording t = make_trolley(15);
  t.rec.truth.clear();
  calib::Options opt;
  opt.z = calib::ZMode::kFixed;
  opt.body_z_m = 0.0;  // the trolley's body origin is on the floor (tags.csv lever arms from there)
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_TRUE(r.observable);
  EXPECT_LT(compare(r, t.offset_m).max_abs_m, 0.02);
}

TEST(CalibrateSelf, ParkedVehicleIsReportedNotObservableInsteadOfNumbers) {
  TrolleyRecording t = make_trolley(16, 30.0, false);
  t.rec.truth.clear();
  calib::Options opt;
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_FALSE(r.observable);
  EXPECT_FALSE(r.weak.empty());
}

calib::StaticPoint start_point(const dataset::Recording& rec, bool with_yaw) {
  calib::StaticPoint sp;
  sp.id = "P1";
  sp.t_start_us = 500000;
  sp.t_end_us = 9500000;  // parked for the first 10 s
  const dataset::TruthRow& tr = rec.truth.front();
  for (int i = 0; i < 3; ++i) sp.pos_nav_m[i] = tr.pos_nav_m[i];
  sp.has_yaw = with_yaw;
  sp.yaw_rad = 0.0;  // the route starts heading along nav x
  return sp;
}

TEST(CalibrateStatic, OneSurveyedStopWithHeadingGivesEveryOffsetWithin2cm) {
  TrolleyRecording t = make_trolley(17);
  const calib::StaticPoint sp = start_point(t.rec, true);
  t.rec.truth.clear();
  calib::Options opt;
  opt.method = calib::Method::kStatic;
  opt.static_points = {{sp}};
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_EQ(r.method, calib::Method::kStatic);
  EXPECT_TRUE(r.observable);
  EXPECT_GT(r.ranges_no_reference, r.ranges_total / 2);  // the drive after the stop has no reference
  const Errors e = compare(r, t.offset_m);
  EXPECT_LT(e.max_abs_m, 0.02);
  EXPECT_LT(e.max_z, 4.5);
}

TEST(CalibrateStatic, OneStopWithoutHeadingIsNotObservableButTwoStopsAre) {
  TrolleyRecording t = make_trolley(18);
  calib::StaticPoint sp = start_point(t.rec, false);
  calib::Options opt;
  opt.method = calib::Method::kStatic;
  opt.static_points = {{sp}};
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_FALSE(r.observable);  // one heading unknown: 24 ranges, 24 offsets + 1 yaw

  // A second stop elsewhere, turned by 135 deg, heading unknown too (a
  // second short recording of the same site): 48 ranges for 24 offsets + 2 yaws.
  const TrolleyRecording t2 = make_trolley(19, 12.0, false, 0.0, "5.5 4.0 0 135");
  calib::StaticPoint sp2 = start_point(t2.rec, false);
  sp2.id = "P2";
  opt.static_points = {{sp}, {sp2}};
  ASSERT_EQ(calib::calibrate({t.rec, t2.rec}, opt, r, &err), Status::kOk) << err;
  EXPECT_TRUE(r.observable);
  EXPECT_LT(compare(r, t.offset_m).max_abs_m, 0.02);
}

// Reporting seeds (101-105; the solver settings were chosen while developing
// on seeds 11-22 and the hanyang recordings): the figures docs/commissioning.md
// quotes, printed, and the 2 cm target checked for every method.
TEST(CalibrateReport, ReportingSeedsRecoverEveryOffsetWithin2cmByTruthStaticAndSelf) {
  std::printf("calibrate trolley (24 pairs, 0.09-0.31 m offsets, 5 cm noise, 1 cm quantisation, 60 s)\n");
  std::printf("  seed method  max|err|_m  rms_err_m  median_sigma_m  max|err|/sigma  common_sigma_m\n");
  for (uint64_t seed = 101; seed <= 105; ++seed) {
    const TrolleyRecording t = make_trolley(seed);
    for (int m = 0; m < 3; ++m) {
      TrolleyRecording run = t;
      calib::Options opt;
      const char* name = "truth";
      if (m == 1) {
        name = "static";
        opt.method = calib::Method::kStatic;
        opt.static_points = {{start_point(run.rec, true)}};
      } else if (m == 2) {
        name = "self";
        run.rec.truth.clear();
      }
      calib::Result r;
      std::string err;
      ASSERT_EQ(calib::calibrate({run.rec}, opt, r, &err), Status::kOk) << err;
      const Errors e = compare(r, t.offset_m);
      double rms = 0.0;
      std::vector<double> sig;
      for (size_t p = 0; p < t.offset_m.size(); ++p) {
        rms += (r.pairs[p].offset_m - t.offset_m[p]) * (r.pairs[p].offset_m - t.offset_m[p]);
        sig.push_back(r.pairs[p].sigma_m);
      }
      std::sort(sig.begin(), sig.end());
      std::printf("  %4llu %-6s %11.4f %10.4f %15.4f %14.2f %15.4f\n", static_cast<unsigned long long>(seed), name,
                  e.max_abs_m, std::sqrt(rms / static_cast<double>(t.offset_m.size())), sig[sig.size() / 2], e.max_z,
                  r.common_sigma_m);
      EXPECT_TRUE(r.observable) << seed << " " << name;
      EXPECT_LT(e.max_abs_m, 0.02) << seed << " " << name;
    }
  }
}

TEST(CalibrateFile, ResultWritesAFileThatLoadsIntoTheSiteAsEstimated) {
  const TrolleyRecording t = make_trolley(20);
  calib::Options opt;
  calib::Result r;
  std::string err;
  ASSERT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kOk) << err;
  ASSERT_TRUE(r.observable);
  const dataset::CalibrationFile f = calib::to_calibration_file(r, {"trolley_test"});
  dataset::CalibrationFile back;
  std::vector<std::string> errors;
  ASSERT_EQ(dataset::parse_calibration(dataset::format_calibration(f), "t.cal", back, errors), Status::kOk);
  SiteConfig site = t.rec.site;
  ASSERT_EQ(dataset::check_calibration(back, site, "t.cal", errors), Status::kOk) << errors.at(0);
  dataset::apply_calibration(back, site);
  double max_sigma = 0.0;
  for (size_t a = 0; a < site.num_anchors; ++a) {
    for (size_t g = 0; g < site.num_tags; ++g) {
      const calib::PairResult& p = r.pairs[a * site.num_tags + g];
      EXPECT_EQ(p.anchor_id, site.anchors[a].id);
      EXPECT_EQ(p.tag_id, site.tags[g].id);
      EXPECT_NEAR(site.range_offset_m[a][g], p.offset_m, 0.5e-4);
      max_sigma = std::max(max_sigma, p.sigma_m);
    }
  }
  EXPECT_GE(static_cast<double>(site.range_offset_sigma_m), max_sigma);
  EXPECT_LT(static_cast<double>(site.range_offset_sigma_m), max_sigma + 1e-4 + 1e-7);
}

TEST(CalibrateInputs, DifferentSitesAndMissingReferencesAreRefusedWithAReason) {
  const TrolleyRecording t = make_trolley(21, 20.0);
  dataset::Recording other = t.rec;
  other.site.anchors[0].pos_nav_m.x += 0.5F;
  calib::Options opt;
  calib::Result r;
  std::string err;
  EXPECT_EQ(calib::calibrate({t.rec, other}, opt, r, &err), Status::kInvalidArgument);
  EXPECT_NE(err.find("one site per calibration"), std::string::npos) << err;
  dataset::Recording no_truth = t.rec;
  no_truth.truth.clear();
  opt.method = calib::Method::kTruth;
  EXPECT_EQ(calib::calibrate({no_truth}, opt, r, &err), Status::kInvalidArgument);
  EXPECT_NE(err.find("no truth.csv"), std::string::npos) << err;
  dataset::Recording no_attitude = t.rec;
  for (auto& row : no_attitude.truth) row.has_attitude = false;
  EXPECT_EQ(calib::calibrate({no_attitude}, opt, r, &err), Status::kInvalidArgument);
  EXPECT_NE(err.find("has no attitude"), std::string::npos) << err;
  opt.method = calib::Method::kStatic;
  EXPECT_EQ(calib::calibrate({t.rec}, opt, r, &err), Status::kInvalidArgument);
  EXPECT_NE(err.find("static points"), std::string::npos) << err;
}

}  // namespace
}  // namespace uwbnav::testing
