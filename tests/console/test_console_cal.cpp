// Console `cal`: the site range calibration the board loaded at start-up, per
// anchor/tag pair, or "uncalibrated".
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "console_rig.hpp"
#include "tools/dataset/calibration.hpp"

namespace uwbnav::testing {
namespace {

TEST(ConsoleCal, UncalibratedSiteSaysSoInOneLine) {
  const dataset::Recording rec = truncated(sim_recording(), 1.0);
  ConsoleRig rig(rec);
  const auto lines = reply_lines(rig.command("cal"));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "cal status=uncalibrated pairs=0");
}

// Loads a calibration file into rec.site: `keys` are the lines after
// site_sigma_m = 0.0125; one row per pair, offset 0.1 m + 0.01 m per anchor
// index + 0.001 m per tag index, sigma 0.01 m.
void load_calibration_text(dataset::Recording& rec, const std::string& keys) {
  const SiteConfig& s = rec.site;
  std::string text = std::string(dataset::kCalibrationMagic) + "\nsite_sigma_m = 0.0125\n" + keys +
                     "anchor_id,tag_id,offset_m,sigma_m\n";
  for (size_t a = 0; a < s.num_anchors; ++a) {
    for (size_t t = 0; t < s.num_tags; ++t) {
      char row[96];
      std::snprintf(row, sizeof row, "%u,%u,%.4f,0.0100\n", static_cast<unsigned>(s.anchors[a].id),
                    static_cast<unsigned>(s.tags[t].id), 0.1 + 0.01 * static_cast<double>(a) + 0.001 * static_cast<double>(t));
      text += row;
    }
  }
  dataset::CalibrationFile cal;
  std::vector<std::string> errors;
  ASSERT_EQ(dataset::parse_calibration(text, "site.cal", cal, errors), Status::kOk) << errors.at(0);
  ASSERT_EQ(dataset::check_calibration(cal, rec.site, "site.cal", errors), Status::kOk) << errors.at(0);
  dataset::apply_calibration(cal, rec.site);
}

TEST(ConsoleCal, LoadedCalibrationFileIsShownPerPairWithTheSiteSigma) {
  dataset::Recording rec = truncated(sim_recording(), 1.0);
  const SiteConfig& s = rec.site;
  load_calibration_text(rec, "");
  ASSERT_FALSE(HasFatalFailure());

  ConsoleRig rig(rec);
  const auto lines = reply_lines(rig.command("cal"));
  const size_t pairs = s.num_anchors * s.num_tags;
  ASSERT_EQ(lines.size(), 1 + pairs);
  EXPECT_EQ(lines[0], "cal status=calibrated pairs=" + std::to_string(pairs) + " sigma_m=0.0125");
  for (size_t a = 0; a < s.num_anchors; ++a) {
    char expect[128];
    std::snprintf(expect, sizeof expect, "cal anchor=%u tag=%u offset_m=%.4f sigma_m=0.0125",
                  static_cast<unsigned>(s.anchors[a].id), static_cast<unsigned>(s.tags[0].id),
                  0.1 + 0.01 * static_cast<double>(a));
    EXPECT_EQ(lines.at(1 + a * s.num_tags), expect);
  }
  EXPECT_EQ(reply_lines(rig.command("cal x")).at(0), "error: cal: takes no arguments");
}

TEST(ConsoleCal, ReferenceCommissionedFileAlsoShowsItsMeasuredSystematicSigma) {
  dataset::Recording rec = truncated(sim_recording(), 1.0);
  const SiteConfig& s = rec.site;
  load_calibration_text(rec, "systematic_sigma_m = 0.0061\n");
  ASSERT_FALSE(HasFatalFailure());
  ConsoleRig rig(rec);
  const auto lines = reply_lines(rig.command("cal"));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "cal status=calibrated pairs=" + std::to_string(s.num_anchors * s.num_tags) +
                          " sigma_m=0.0125 systematic_sigma_m=0.0061");
}

}  // namespace
}  // namespace uwbnav::testing
