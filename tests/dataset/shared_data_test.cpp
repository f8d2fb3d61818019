// Reads every real recording shipped under data/ (UWBNAV_DATA_DIR, tables
// gzip-compressed) and checks that each data line of each file became one row
// (none skipped) and the site is parsed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "tests/dataset/dataset_test_util.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/text_source.hpp"

namespace uwbnav::dataset {
namespace {

namespace fs = std::filesystem;

// Lines that are neither blank nor comments, minus the header; 0 when absent.
size_t data_lines(const std::string& path) {
  std::string text;
  if (!ok(read_text_file(path, text))) return 0;
  size_t n = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    const std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (!line.empty() && line != "\r" && line[0] != '#') ++n;
  }
  return n > 0 ? n - 1 : 0;
}

std::vector<std::string> recordings() {
  std::vector<std::string> dirs;
  const fs::path data = fs::path(UWBNAV_DATA_DIR);
  std::error_code ec;
  if (!fs::is_directory(data, ec)) return dirs;
  for (const auto& e : fs::recursive_directory_iterator(data, ec)) {
    if (e.is_regular_file() && e.path().filename() == "uwb.csv.gz") dirs.push_back(e.path().parent_path().string());
  }
  std::sort(dirs.begin(), dirs.end());
  return dirs;
}

TEST(DatasetSharedData, EveryRecordingLoadsWithOneRowPerDataLine) {
  const auto dirs = recordings();
  ASSERT_EQ(dirs.size(), 5U) << "recordings shipped under " << UWBNAV_DATA_DIR;
  for (const auto& dir : dirs) {
    SCOPED_TRACE(dir);
    Recording rec;
    ReadReport rep;
    ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << testutil::dump(rep);
    EXPECT_EQ(rep.rows_skipped, 0U) << testutil::dump(rep);
    EXPECT_EQ(rec.uwb.size(), data_lines(dir + "/uwb.csv"));
    EXPECT_EQ(rec.imu.size(), data_lines(dir + "/imu.csv"));
    EXPECT_EQ(rec.truth.size(), data_lines(dir + "/truth.csv"));
    EXPECT_EQ(rec.site.num_anchors, data_lines(dir + "/anchors.csv"));
    EXPECT_EQ(rec.site.has_imu, !rec.imu.empty());
    EXPECT_FALSE(rec.uwb.empty());
    EXPECT_FALSE(rec.name().empty());
    std::printf("%s: %zu uwb, %zu imu, %zu truth, %zu anchors\n", rec.name().c_str(), rec.uwb.size(),
                rec.imu.size(), rec.truth.size(), rec.site.num_anchors);
    for (const auto& r : rec.uwb) {
      EXPECT_GE(rec.site.find_anchor(r.range.anchor_id), 0) << "range to unknown anchor " << r.range.anchor_id;
    }
  }
}

TEST(DatasetSharedData, HanyangRecordingsHaveAnchors3_5_9_12AndNoImu) {
  size_t seen = 0;
  for (const auto& dir : recordings()) {
    if (dir.find("hanyang") == std::string::npos) continue;
    SCOPED_TRACE(dir);
    ++seen;
    Recording rec;
    ReadReport rep;
    ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << testutil::dump(rep);
    std::set<uint16_t> ids;
    for (size_t i = 0; i < rec.site.num_anchors; ++i) ids.insert(rec.site.anchors[i].id);
    EXPECT_EQ(ids, (std::set<uint16_t>{3, 5, 9, 12}));
    EXPECT_FALSE(rec.site.has_imu);
    EXPECT_EQ(rec.site.platform, Platform::kGround);
    ASSERT_EQ(rec.site.num_tags, 1U);
    EXPECT_EQ(rec.site.tags[0].lever_body_m.z, 1.02F);
    // Repeated values (same anchor and value again at a new timestamp) are valid rows and are kept.
    size_t repeats = 0;
    for (size_t i = 1; i < rec.uwb.size(); ++i) {
      for (size_t j = i; j-- > 0 && j + 8 > i;) {
        if (rec.uwb[j].range.anchor_id == rec.uwb[i].range.anchor_id) {
          repeats += rec.uwb[j].range.range_m == rec.uwb[i].range.range_m ? 1U : 0U;
          break;
        }
      }
    }
    EXPECT_GT(repeats, 0U);
    for (const auto& r : rec.uwb) EXPECT_TRUE(std::isfinite(r.range.fp_power_dbm));
  }
  EXPECT_EQ(seen, 4U) << "hanyang recordings shipped under " << UWBNAV_DATA_DIR;
}

TEST(DatasetSharedData, MiluvRecordingHasImuTwoTagsAndAttitudeTruth) {
  const std::string dir = std::string(UWBNAV_DATA_DIR) + "/miluv/miluv_3drone_ifo001";
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << testutil::dump(rep);
  EXPECT_TRUE(rec.site.has_imu);
  EXPECT_EQ(rec.site.platform, Platform::kAir);
  EXPECT_EQ(rec.site.num_anchors, 6U);
  ASSERT_EQ(rec.site.num_tags, 2U);
  EXPECT_EQ(rec.site.tags[0].id, 10);
  EXPECT_EQ(rec.site.tags[1].id, 11);
  ASSERT_FALSE(rec.truth.empty());
  EXPECT_TRUE(rec.truth.front().has_attitude);
  ASSERT_FALSE(rec.uwb.empty());
  EXPECT_TRUE(std::isnan(rec.uwb.front().range.rx_power_dbm)) << "rx power not recorded: empty cell";
  EXPECT_NEAR(rec.imu.front().accel_body_mps2.z, 9.8F, 0.2F);
}

}  // namespace
}  // namespace uwbnav::dataset
