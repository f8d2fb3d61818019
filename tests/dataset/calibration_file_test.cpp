// Site range calibration file (tools/dataset/calibration.hpp): round trip,
// the strict reader's file:line: reason for every malformed input, the site
// check (unknown, missing, duplicate pairs; another survey) and what gets
// applied to SiteConfig.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "dataset_test_util.hpp"
#include "tools/dataset/calibration.hpp"

namespace uwbnav::dataset {
namespace {

// Two anchors (7, 9) and two tags (0, 1).
SiteConfig two_by_two() {
  SiteConfig s;
  EXPECT_TRUE(ok(s.add_anchor(7, {0.0F, 0.0F, 1.0F})));
  EXPECT_TRUE(ok(s.add_anchor(9, {5.0F, 0.0F, 1.0F})));
  EXPECT_TRUE(ok(s.add_tag(0, {0.2F, 0.0F, 0.5F})));
  EXPECT_TRUE(ok(s.add_tag(1, {-0.2F, 0.0F, 0.5F})));
  return s;
}

const std::string kHead = std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nanchor_id,tag_id,offset_m,sigma_m\n";
const std::string kRows = "7,0,0.1500,0.0020\n7,1,0.1800,0.0030\n9,0,0.2100,0.0020\n9,1,0.2400,0.0040\n";

// Parse + check; returns the messages (empty when the file is accepted).
std::vector<std::string> problems(const std::string& text, const SiteConfig& site) {
  CalibrationFile cal;
  std::vector<std::string> errors;
  if (ok(parse_calibration(text, "site.cal", cal, errors))) {
    if (ok(check_calibration(cal, site, "site.cal", errors))) EXPECT_TRUE(errors.empty());
    else EXPECT_FALSE(errors.empty());
  } else {
    EXPECT_FALSE(errors.empty());
  }
  return errors;
}

bool has(const std::vector<std::string>& errors, const std::string& needle) {
  for (const auto& e : errors) {
    if (e.find(needle) != std::string::npos) return true;
  }
  return false;
}

std::string dump(const std::vector<std::string>& errors) {
  std::string s;
  for (const auto& e : errors) s += e + "\n";
  return s;
}

TEST(CalibrationFile, WrittenFileReadsBackAndFillsSiteOffsetsByPairIndex) {
  const SiteConfig site = two_by_two();
  CalibrationFile cal;
  cal.site_sigma_m = 0.0041F;
  cal.has_site_crc = true;
  cal.site_crc32 = site_crc32(site);
  cal.info.push_back("method = truth");
  cal.pairs = {{9, 1, 0.2412F, 0.0041F}, {7, 0, -0.0153F, 0.0012F}, {7, 1, 0.1801F, 0.003F}, {9, 0, 0.21F, 0.002F}};
  const std::string path = testutil::scratch_dir() + "/site.cal";
  ASSERT_EQ(write_calibration(path, cal), Status::kOk);
  EXPECT_EQ(testutil::read_text(path).rfind(std::string(kCalibrationMagic) + "\n", 0), 0U);

  SiteConfig loaded = two_by_two();
  std::vector<std::string> errors;
  ASSERT_EQ(load_calibration(path, loaded, errors), Status::kOk) << dump(errors);
  EXPECT_FLOAT_EQ(loaded.range_offset_sigma_m, 0.0041F);
  EXPECT_FLOAT_EQ(loaded.range_offset_m[0][0], -0.0153F);  // anchor 7 (index 0), tag 0
  EXPECT_FLOAT_EQ(loaded.range_offset_m[0][1], 0.1801F);
  EXPECT_FLOAT_EQ(loaded.range_offset_m[1][0], 0.21F);
  EXPECT_FLOAT_EQ(loaded.range_offset_m[1][1], 0.2412F);   // anchor 9 (index 1), tag 1
  EXPECT_EQ(loaded.range_offset_m[2][0], 0.0F);            // no such anchor: stays zero

  CalibrationFile back;
  ASSERT_EQ(parse_calibration(testutil::read_text(path), path, back, errors), Status::kOk) << dump(errors);
  ASSERT_EQ(back.info.size(), 1U);
  EXPECT_EQ(back.info[0], "method = truth");
  EXPECT_TRUE(back.has_site_crc);
  EXPECT_EQ(back.site_crc32, site_crc32(site));
}

TEST(CalibrationFile, SystematicSigmaIsOptionalRoundsUpAndReachesTheSiteOnlyWhenGiven) {
  CalibrationFile cal;
  cal.site_sigma_m = 0.004F;
  cal.pairs = {{7, 0, 0.15F, 0.002F}, {7, 1, 0.18F, 0.003F}, {9, 0, 0.21F, 0.002F}, {9, 1, 0.24F, 0.004F}};
  // Not measured (a file of an older tool, or written by hand): no line, and
  // the site keeps NaN, so the filter keeps uwb.survey_sigma.
  EXPECT_EQ(format_calibration(cal).find("systematic_sigma_m"), std::string::npos);
  const std::string path = testutil::scratch_dir() + "/systematic.cal";
  ASSERT_EQ(write_calibration(path, cal), Status::kOk);
  SiteConfig loaded = two_by_two();
  std::vector<std::string> errors;
  ASSERT_EQ(load_calibration(path, loaded, errors), Status::kOk) << dump(errors);
  EXPECT_TRUE(std::isnan(loaded.range_systematic_sigma_m));
  // Measured: written rounded up, read back into the site.
  cal.systematic_sigma_m = 0.00312F;
  EXPECT_NE(format_calibration(cal).find("systematic_sigma_m = 0.0032\n"), std::string::npos) << format_calibration(cal);
  ASSERT_EQ(write_calibration(path, cal), Status::kOk);
  ASSERT_EQ(load_calibration(path, loaded, errors), Status::kOk) << dump(errors);
  EXPECT_FLOAT_EQ(loaded.range_systematic_sigma_m, 0.0032F);
  EXPECT_FLOAT_EQ(loaded.range_offset_sigma_m, 0.004F);
  // Zero is a measurement too (noise-free simulation): written as the 0.1 mm floor.
  cal.systematic_sigma_m = 0.0F;
  EXPECT_NE(format_calibration(cal).find("systematic_sigma_m = 0.0001\n"), std::string::npos) << format_calibration(cal);
}

TEST(CalibrationFile, SigmasAreRoundedUpNeverDownWhenWritten) {
  CalibrationFile cal;
  cal.site_sigma_m = 0.00411F;
  cal.pairs = {{7, 0, 0.1F, 0.00411F}, {7, 1, 0.1F, 0.00001F}};
  const std::string text = format_calibration(cal);
  EXPECT_NE(text.find("site_sigma_m = 0.0042\n"), std::string::npos) << text;
  EXPECT_NE(text.find("7,0,0.1000,0.0042\n"), std::string::npos) << text;
  EXPECT_NE(text.find("7,1,0.1000,0.0001\n"), std::string::npos) << text;  // never 0
}

TEST(CalibrationFile, AFailedLoadLeavesTheSiteUncalibrated) {
  SiteConfig site = two_by_two();
  const std::string path = testutil::scratch_dir() + "/bad.cal";
  testutil::write_file(path, kHead + "7,0,0.15,0.002\n7,1,nan,0.002\n9,0,0.2,0.002\n9,1,0.2,0.002\n");
  std::vector<std::string> errors;
  EXPECT_EQ(load_calibration(path, site, errors), Status::kInvalidArgument);
  EXPECT_TRUE(std::isnan(site.range_offset_sigma_m));
  EXPECT_EQ(site.range_offset_m[0][0], 0.0F);
  errors.clear();
  EXPECT_EQ(load_calibration(testutil::scratch_dir() + "/absent.cal", site, errors), Status::kNotFound);
  EXPECT_TRUE(has(errors, "absent.cal: no such file")) << dump(errors);
}

TEST(CalibrationFile, MalformedInputIsRefusedWithFileLineAndReason) {
  const SiteConfig site = two_by_two();
  EXPECT_TRUE(problems(kHead + kRows, site).empty());
  struct Case {
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"", "site.cal: empty file"},
      {"anchor_id,tag_id,offset_m,sigma_m\n7,0,0.1,0.01\n", "site.cal:1: first line must be '# uwbnav range calibration v1'"},
      {"# uwbnav range calibration v2\n", "site.cal:1: first line must be"},
      {std::string(kCalibrationMagic) + "\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows, "no 'site_sigma_m = <metres>' line"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\n" + kRows, "site.cal:3: expected 'key = value' or the column line"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\n", "no column line"},
      {kHead, "site.cal: no pair rows"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = abc\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:2: site_sigma_m 'abc' is not a number"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:2: site_sigma_m 0 is not in (0, 1] m"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = nan\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:2: site_sigma_m is NaN"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsite_sigma_m = 0.02\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: key 'site_sigma_m' given twice"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nSite Sigma = 1\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: key 'Site Sigma' is not [a-z0-9_]+"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsite_crc32 = 1234\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: site_crc32 '1234' is not 0x followed by hex digits"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsystematic_sigma_m = -0.01\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: systematic_sigma_m -0.01 is not in [0, 1] m"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsystematic_sigma_m = 1.5\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: systematic_sigma_m 1.5 is not in [0, 1] m"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsystematic_sigma_m = nan\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: systematic_sigma_m is NaN"},
      {kHead + "7,0,0.15\n", "site.cal:4: 3 cells, expected 4"},
      {kHead + "7,0,0.15,0.002,9\n", "site.cal:4: 5 cells, expected 4"},
      {kHead + "x,0,0.15,0.002\n", "site.cal:4: anchor_id 'x' is not an integer in 0..65535"},
      {kHead + "70000,0,0.15,0.002\n", "site.cal:4: anchor_id '70000' is not an integer in 0..65535"},
      {kHead + "7,-1,0.15,0.002\n", "site.cal:4: tag_id '-1' is not an integer in 0..255"},
      {kHead + "7,0,nan,0.002\n", "site.cal:4: offset_m is NaN"},
      {kHead + "7,0,inf,0.002\n", "site.cal:4: offset_m 'inf' is not finite"},
      {kHead + "7,0,0.15m,0.002\n", "site.cal:4: offset_m '0.15m' is not a number"},
      {kHead + "7,0,,0.002\n", "site.cal:4: offset_m '' is not a number"},
      {kHead + "7,0,12.5,0.002\n", "site.cal:4: offset_m 12.5 is beyond +-10 m"},
      {kHead + "7,0,0.15,0\n", "site.cal:4: sigma_m 0 is not in (0, 1] m"},
      {kHead + "7,0,0.15,NaN\n", "site.cal:4: sigma_m is NaN"},
      {kHead + "7,0,0.15,0.02\n" + "7,1,0.1,0.002\n9,0,0.1,0.002\n9,1,0.1,0.002\n",
       "site.cal:4: sigma_m of anchor 7 / tag 0 exceeds site_sigma_m (line 2)"},
      {kHead + kRows + "9,0,0.3,0.002\n", "site.cal:8: duplicate pair anchor 9 / tag 0 (first on line 6)"},
      {kHead + kRows + "3,0,0.3,0.002\n", "site.cal:8: anchor 3 is not an anchor of the site"},
      {kHead + kRows + "7,4,0.3,0.002\n", "site.cal:8: tag 4 is not a tag of the site"},
      {kHead + "7,0,0.15,0.002\n7,1,0.15,0.002\n9,0,0.15,0.002\n",
       "site.cal: no row for anchor 9 / tag 1 of the site (every pair must be calibrated)"},
      {std::string(kCalibrationMagic) + "\nsite_sigma_m = 0.01\nsite_crc32 = 0x12345678\nanchor_id,tag_id,offset_m,sigma_m\n" + kRows,
       "site.cal:3: site_crc32 0x12345678 does not match this site"},
  };
  for (const Case& c : cases) {
    const auto errors = problems(c.text, site);
    EXPECT_TRUE(has(errors, c.message)) << "input:\n" << c.text << "\ngot:\n" << dump(errors);
  }
}

TEST(CalibrationFile, CommentsBlankLinesCrLfAndExtraKeysAreAccepted) {
  const SiteConfig site = two_by_two();
  std::string text = std::string(kCalibrationMagic) + "\r\n# made on site\r\n\r\nsite_sigma_m = 0.01\r\nmethod = self\r\n" +
                     "site_crc32 = 0x" + [&] {
                       char b[16];
                       std::snprintf(b, sizeof b, "%08x", static_cast<unsigned>(site_crc32(site)));
                       return std::string(b);
                     }() + "\r\nanchor_id,tag_id,offset_m,sigma_m\r\n# pairs\r\n" + "7,0, 0.15 ,0.002\r\n7,1,+0.18,2e-3\r\n9,0,0.21,0.002\r\n9,1,-0.24,0.004\r\n";
  CalibrationFile cal;
  std::vector<std::string> errors;
  ASSERT_EQ(parse_calibration(text, "site.cal", cal, errors), Status::kOk) << dump(errors);
  ASSERT_EQ(check_calibration(cal, site, "site.cal", errors), Status::kOk) << dump(errors);
  ASSERT_EQ(cal.pairs.size(), 4U);
  EXPECT_FLOAT_EQ(cal.pairs[1].offset_m, 0.18F);
  EXPECT_FLOAT_EQ(cal.pairs[3].offset_m, -0.24F);
  EXPECT_EQ(cal.info, std::vector<std::string>{"method = self"});
}

TEST(CalibrationFile, SiteCrcChangesWhenAnAnchorMovesOrATagLeverArmChanges) {
  const SiteConfig a = two_by_two();
  SiteConfig b = two_by_two();
  b.anchors[1].pos_nav_m.x = 5.01F;
  SiteConfig c = two_by_two();
  c.tags[0].lever_body_m.z = 0.51F;
  EXPECT_EQ(site_crc32(a), site_crc32(two_by_two()));
  EXPECT_NE(site_crc32(a), site_crc32(b));
  EXPECT_NE(site_crc32(a), site_crc32(c));
}

}  // namespace
}  // namespace uwbnav::dataset
