// Format v1 reader on malformed input: every bad-row kind skipped, counted and
// warned with its line (gnss.csv and neighbours.csv included), and no input (garbage, CRLF, empty,
// huge) crashes it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "tests/dataset/dataset_test_util.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"

namespace uwbnav::dataset {
namespace {

using testutil::dump;
using testutil::has_warning;
using testutil::kAnchorsOk;
using testutil::scratch_dir;
using testutil::write_file;

TEST(DatasetReader, SkipsEachBadRowKindWithItsLineNumber) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv",
             "t_s,anchor_id,range_m,tag_id,nlos,fp_power_dbm,rx_power_dbm\n"  // 1
             "0.1,1,5.0,0,0,-80,-79\n"                                        // 2 ok
             "# a comment\n"                                                  // 3
             "0.2,1,abc,0,0,,\n"                                              // 4 unparsable
             "0.3,1,nan,0,0,,\n"                                              // 5 NaN
             "0.3,1,inf,,,,\n"                                                // 6 Inf
             "0.4,1,5.0\n"                                                    // 7 column count
             "0.05,1,5.0,0,,,\n"                                              // 8 backwards
             "0.5,-1,5.0,0,,,\n"                                              // 9 negative id
             "0.5,70000,5.0,0,,,\n"                                           // 10 id overflow
             "-0.1,1,5.0,0,,,\n"                                              // 11 t_s < 0
             "0.5,1,5.0,0,2,,\n"                                              // 12 nlos not 0/1
             "0.5,1,5.0,256,,,\n"                                             // 13 tag id overflow
             "0.5,1,1e39,0,,,\n"                                              // 14 float overflow
             "0.5,99999999999999999999999,5.0,0,,,\n"                         // 15 uint64 overflow
             "0.5,2,6.5,1,,-81.5,\n"                                          // 16 ok
             "0.5,3,7.0,,,,\n");                                              // 17 ok, tie in time
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.uwb.size(), 3U) << dump(rep);
  EXPECT_EQ(rep.rows_skipped, 12U) << dump(rep);
  EXPECT_EQ(rep.rows_read, 3U + 3U);  // anchors + ranges
  EXPECT_TRUE(has_warning(rep, "uwb.csv:4:", "unparsable")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:5:", "not finite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:6:", "not finite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:7:", "expected 7 columns, got 3")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:8:", "backwards")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:9:", "negative")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:10:", "out of range")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:11:", "negative time")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:12:", "nlos")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:13:", "tag_id")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:14:", "float range")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:15:", "out of range")) << dump(rep);

  EXPECT_EQ(rec.uwb[0].range.t_us, 100000U);
  EXPECT_EQ(rec.uwb[0].nlos_label, 0);
  EXPECT_FLOAT_EQ(rec.uwb[0].range.rx_power_dbm, -79.0F);
  EXPECT_EQ(rec.uwb[1].range.tag_id, 1);
  EXPECT_EQ(rec.uwb[1].nlos_label, -1);
  EXPECT_FLOAT_EQ(rec.uwb[1].range.fp_power_dbm, -81.5F);
  EXPECT_TRUE(std::isnan(rec.uwb[1].range.rx_power_dbm));
  EXPECT_EQ(rec.uwb[2].range.t_us, rec.uwb[1].range.t_us);
  EXPECT_EQ(rec.uwb[2].range.tag_id, 0);  // empty tag_id means 0
}

TEST(DatasetReader, SkipsBadImuAndTruthRows) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/imu.csv",
             "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps\n"
             "0.00,0,0,9.81,0,0,0\n"
             "0.01,0,0,,0,0,0\n"  // 3 empty required cell
             "0.02,0,0,9.81,0,0,0,7\n"  // 4 column count
             "0.03,0,0,9.81,0,0,0\n");
  write_file(dir + "/truth.csv",
             "t_s,x_m,y_m,z_m,qw,qx,qy,qz\n"
             "0.0,1,2,3,1,0,0,0\n"
             "0.1,1,2,3,,,,\n"     // no attitude: fine
             "0.2,1,2,3,1,0,,\n"   // 4 partial quaternion
             "0.3,1,2,INF,1,0,0,0\n");  // 5 Inf
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_EQ(rec.imu.size(), 2U);
  EXPECT_TRUE(rec.site.has_imu);
  EXPECT_EQ(rec.truth.size(), 2U);
  EXPECT_TRUE(rec.truth[0].has_attitude);
  EXPECT_FALSE(rec.truth[1].has_attitude);
  EXPECT_EQ(rep.rows_skipped, 4U);
  EXPECT_TRUE(has_warning(rep, "imu.csv:3:", "az_mps2: empty")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "imu.csv:4:", "columns")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "truth.csv:4:", "quaternion")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "truth.csv:5:", "not finite")) << dump(rep);
}

TEST(DatasetReader, CrlfAndMissingFinalNewlineReadLikeLf) {
  const std::string uwb_lf =
      "t_s,anchor_id,range_m,tag_id,nlos\n# comment\n0.1,1,5.0,0,1\n0.2,2,6.0,0,0\n0.3,3,7.0,0,\n";
  std::string uwb_crlf;
  for (char c : uwb_lf) {
    if (c == '\n') uwb_crlf += '\r';
    uwb_crlf += c;
  }
  uwb_crlf.erase(uwb_crlf.size() - 2);  // no final line break

  const std::string root = scratch_dir();
  const std::string dir_lf = root + "/lf";
  const std::string dir_crlf = root + "/crlf";
  for (const auto& [dir, uwb] : {std::pair{dir_lf, uwb_lf}, std::pair{dir_crlf, uwb_crlf}}) {
    std::filesystem::create_directories(dir);
    write_file(dir + "/anchors.csv", dir == dir_lf ? std::string(kAnchorsOk)
                                                   : std::string("anchor_id,x_m,y_m,z_m\r\n1,0,0,2\r\n"
                                                                 "2,10,0,2\r\n3,10,10,2"));
    write_file(dir + "/uwb.csv", uwb);
  }
  Recording a;
  Recording b;
  ReadReport ra;
  ReadReport rb;
  ASSERT_EQ(read_recording(dir_lf, a, ra), Status::kOk) << dump(ra);
  ASSERT_EQ(read_recording(dir_crlf, b, rb), Status::kOk) << dump(rb);
  EXPECT_EQ(rb.rows_skipped, 0U) << dump(rb);
  ASSERT_EQ(a.uwb.size(), 3U);
  ASSERT_EQ(b.uwb.size(), a.uwb.size());
  ASSERT_EQ(b.site.num_anchors, 3U);
  for (size_t i = 0; i < a.uwb.size(); ++i) {
    EXPECT_EQ(a.uwb[i].range.t_us, b.uwb[i].range.t_us);
    EXPECT_EQ(a.uwb[i].range.range_m, b.uwb[i].range.range_m);
    EXPECT_EQ(a.uwb[i].nlos_label, b.uwb[i].nlos_label);
  }
  EXPECT_EQ(b.uwb[2].nlos_label, -1);
}

TEST(DatasetReader, GarbageBytesNeverCrashAndWarningsAreCapped) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  std::string garbage = "t_s,anchor_id,range_m\n";
  uint32_t x = 12345U;  // xorshift32: deterministic bytes incl. NUL, '\n', ',', '\r', 0xFF
  for (size_t i = 0; i < 200000; ++i) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    garbage.push_back(static_cast<char>(x & 0xFFU));
  }
  write_file(dir + "/uwb.csv", garbage);
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_GT(rep.rows_skipped, ReadReport::kMaxWarnings);
  EXPECT_EQ(rep.warnings.size(), ReadReport::kMaxWarnings);
  EXPECT_EQ(rep.warnings.size() + rep.warnings_dropped, rep.rows_skipped);
  for (const auto& r : rec.uwb) EXPECT_TRUE(std::isfinite(r.range.range_m));

  // Garbage in every file, header included: an error or a load, never a crash.
  for (uint32_t seed = 1; seed <= 40; ++seed) {
    for (const char* f : {"anchors.csv", "uwb.csv", "imu.csv", "truth.csv", "tags.csv", "meta.ini", "gnss.csv",
                          "neighbours.csv"}) {
      std::string bytes = seed % 2 == 0 ? std::string(kAnchorsOk).substr(0, 22) : std::string();
      x = seed * 7919U + static_cast<uint32_t>(bytes.size());
      for (size_t i = 0; i < 3000; ++i) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        bytes.push_back(static_cast<char>(x % 7 == 0 ? '\n' : x % 5 == 0 ? ',' : (x >> 8) & 0xFFU));
      }
      write_file(dir + "/" + f, bytes);
    }
    Recording r2;
    ReadReport rep2;
    const Status st = read_recording(dir, r2, rep2);
    if (st != Status::kOk) {
      EXPECT_FALSE(rep2.error.empty());
    }
  }
}

TEST(DatasetReader, HugeLineIsSkippedNotFatal) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  std::string uwb = "t_s,anchor_id,range_m\n0.1,1,";
  uwb.append(8U << 20, '7');  // an 8 MB number
  uwb += "\n0.2,1,5.5\n";
  write_file(dir + "/uwb.csv", uwb);
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_EQ(rep.rows_skipped, 1U);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:2:", "range_m")) << dump(rep);
  ASSERT_EQ(rec.uwb.size(), 1U);
  EXPECT_EQ(rec.uwb[0].range.range_m, 5.5F);
}

TEST(DatasetReader, EmptyFilesFailWhenRequiredAndAreIgnoredWhenOptional) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "");
  Recording rec;
  ReadReport rep;
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);
  EXPECT_NE(rep.error.find("uwb.csv"), std::string::npos) << rep.error;
  EXPECT_NE(rep.error.find("no header"), std::string::npos) << rep.error;

  write_file(dir + "/uwb.csv", "# only a comment\n\n");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);

  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/imu.csv", "");
  write_file(dir + "/truth.csv", "");
  rep = ReadReport{};
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_TRUE(rec.uwb.empty());
  EXPECT_FALSE(rec.site.has_imu);
  EXPECT_TRUE(has_warning(rep, "imu.csv:", "no header")) << dump(rep);

  write_file(dir + "/imu.csv", "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps\n");
  rep = ReadReport{};
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_FALSE(rec.site.has_imu) << "imu.csv without rows is a UWB-only recording";

  write_file(dir + "/anchors.csv", "");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);
  EXPECT_NE(rep.error.find("anchors.csv"), std::string::npos) << rep.error;

  write_file(dir + "/anchors.csv", "anchor_id,x_m,y_m,z_m\n1,nan,0,0\n");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);
  EXPECT_NE(rep.error.find("no usable anchor"), std::string::npos) << rep.error;
}

TEST(DatasetReader, MissingRequiredFilesFailWithTheirName) {
  const std::string dir = scratch_dir();
  Recording rec;
  ReadReport rep;
  EXPECT_EQ(read_recording(dir + "/does_not_exist", rec, rep), Status::kNotFound);
  EXPECT_NE(rep.error.find("does_not_exist: no such directory"), std::string::npos) << rep.error;

  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kNotFound);  // empty directory
  EXPECT_NE(rep.error.find("anchors.csv: required file missing"), std::string::npos) << rep.error;

  write_file(dir + "/anchors.csv", kAnchorsOk);
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kNotFound);
  EXPECT_NE(rep.error.find("uwb.csv"), std::string::npos) << rep.error;

  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n1.0,1,3.0\n");
  std::filesystem::remove(dir + "/anchors.csv");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kNotFound);
  EXPECT_NE(rep.error.find("anchors.csv"), std::string::npos) << rep.error;
}

TEST(DatasetReader, WrongHeadersAreRejectedWithAClearError) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  struct Case {
    const char* file;
    const char* header;
  };
  const Case bad[] = {
      {"uwb.csv", "t_s,range_m,anchor_id\n"},                 // order
      {"uwb.csv", "t_s,anchor_id,range_m,nlos\n"},            // optional column skipped
      {"uwb.csv", "time,anchor_id,range_m\n"},                // name
      {"uwb.csv", "t_s,anchor_id,range_m,tag_id,nlos,fp_power_dbm,rx_power_dbm,extra\n"},
      {"imu.csv", "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps\n"},
      {"truth.csv", "t_s,x_m,y_m,z_m,qw,qx\n"},               // partial quaternion group
      {"tags.csv", "tag_id,x,y,z\n"},
  };
  for (const Case& c : bad) {
    write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
    for (const char* f : {"imu.csv", "truth.csv", "tags.csv"}) std::filesystem::remove(dir + "/" + f);
    write_file(dir + "/" + c.file, c.header);
    Recording rec;
    ReadReport rep;
    EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument) << c.file << " " << c.header;
    EXPECT_EQ(rep.error.rfind(std::string(c.file) + ":1: wrong header", 0), 0U) << rep.error;
    EXPECT_NE(rep.error.find("expected"), std::string::npos) << rep.error;
  }

  // Accepted: comments before the header, a BOM, and any leading part of the optional columns.
  std::filesystem::remove(dir + "/tags.csv");
  write_file(dir + "/uwb.csv", "\xEF\xBB\xBF# made by hand\nt_s,anchor_id,range_m,tag_id\n0.5,1,2.5,3\n");
  write_file(dir + "/truth.csv", "t_s,x_m,y_m,z_m\n0.5,1,2,3\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  ASSERT_EQ(rec.uwb.size(), 1U);
  EXPECT_EQ(rec.uwb[0].range.tag_id, 3);
  EXPECT_TRUE(std::isnan(rec.uwb[0].range.fp_power_dbm));
  EXPECT_EQ(rec.truth.size(), 1U);
}

TEST(DatasetReader, AnchorAndTagCapacityOverflowIsWarnedNotOverrun) {
  const std::string dir = scratch_dir();
  std::string anchors = "anchor_id,x_m,y_m,z_m\n";
  for (int i = 0; i < 20; ++i) anchors += std::to_string(100 + i) + ",1,2,3\n";
  anchors += "100,5,5,5\n";  // duplicate id
  write_file(dir + "/anchors.csv", anchors);
  std::string tags = "tag_id,x_m,y_m,z_m\n";
  for (int i = 0; i < 6; ++i) tags += std::to_string(i) + ",0.1,0,1\n";
  write_file(dir + "/tags.csv", tags);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_EQ(rec.site.num_anchors, kMaxAnchors);
  EXPECT_EQ(static_cast<size_t>(rec.site.anchors[kMaxAnchors - 1].id), 100 + kMaxAnchors - 1);
  EXPECT_EQ(rec.site.num_tags, kMaxTags);
  EXPECT_EQ(rep.rows_skipped, (20 - kMaxAnchors) + 1 + (6 - kMaxTags));
  EXPECT_TRUE(has_warning(rep, "anchors.csv:18:", "more than 16 anchors")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "anchors.csv:22:", "duplicate anchor_id 100")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "tags.csv:6:", "more than 4 tags")) << dump(rep);
}

TEST(DatasetReader, AbsentTagsFileMeansTagZeroAtBodyOrigin) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  ASSERT_EQ(rec.site.num_tags, 1U);
  EXPECT_EQ(rec.site.tags[0].id, 0);
  EXPECT_EQ(rec.site.tags[0].lever_body_m.x, 0.0F);
  EXPECT_EQ(rec.site.tags[0].lever_body_m.z, 0.0F);
  EXPECT_EQ(rec.name(), "DatasetReader.AbsentTagsFileMeansTagZeroAtBodyOrigin") << "name falls back to the folder";

  write_file(dir + "/tags.csv", "tag_id,x_m,y_m,z_m\n7,0.5,-0.25,1.5\n");
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  ASSERT_EQ(rec.site.num_tags, 1U);
  EXPECT_EQ(rec.site.tags[0].id, 7);
  EXPECT_EQ(rec.site.tags[0].lever_body_m.y, -0.25F);
}

TEST(DatasetReader, MetaIniFillsSiteAndWarnsAboutBadLines) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/meta.ini",
             "# comment\r\n"
             "; another comment\r\n"
             "name = drive 7\r\n"
             "platform = air\r\n"
             "gravity_mps2 = 9.79\r\n"
             "uwb_sigma_m=0.25\r\n"
             "this line has no equals sign\r\n"
             "description = a = b\r\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_EQ(rec.name(), "drive 7");
  EXPECT_EQ(rec.site.platform, Platform::kAir);
  EXPECT_EQ(rec.site.gravity_mps2, 9.79F);
  EXPECT_EQ(rec.meta["uwb_sigma_m"], "0.25") << "a simulator fact: kept in meta, never in the site config";
  EXPECT_EQ(rec.meta["description"], "a = b");
  EXPECT_TRUE(has_warning(rep, "meta.ini:7:", "key = value")) << dump(rep);
  EXPECT_EQ(rep.rows_skipped, 0U) << "meta.ini lines are not data rows";

  write_file(dir + "/meta.ini", "platform = boat\ngravity_mps2 = -3\nuwb_sigma_m = x\n");
  rep = ReadReport{};
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << rep.error;
  EXPECT_EQ(rec.site.platform, Platform::kGround);
  EXPECT_EQ(rec.site.gravity_mps2, SiteConfig{}.gravity_mps2);
  EXPECT_EQ(rec.meta.count("uwb_sigma_m"), 0U);
  EXPECT_TRUE(has_warning(rep, "meta.ini:1:", "platform")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "meta.ini:2:", "gravity_mps2")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "meta.ini:3:", "uwb_sigma_m")) << dump(rep);
}

TEST(DatasetReader, SecondsToMicrosecondsRoundsToNearest) {
  EXPECT_EQ(seconds_to_us(0.0), 0U);
  EXPECT_EQ(seconds_to_us(1e-6), 1U);
  EXPECT_EQ(seconds_to_us(0.0000014), 1U);
  EXPECT_EQ(seconds_to_us(0.0000016), 2U);
  EXPECT_EQ(seconds_to_us(1.5), 1500000U);
  EXPECT_EQ(seconds_to_us(1723710007.350701), 1723710007350701U);
  EXPECT_EQ(seconds_to_us(-1.0), 0U);
  EXPECT_EQ(seconds_to_us(std::nan("")), 0U);
  EXPECT_DOUBLE_EQ(us_to_seconds(1500000U), 1.5);
}

TEST(DatasetReader, AStreamEndingMoreThanASecondBeforeTheOtherIsReported) {
  Recording rec;
  for (uint64_t t_us = 0; t_us <= 10000000; t_us += 100000) {
    UwbRow row;
    row.range.t_us = t_us;
    rec.uwb.push_back(row);
  }
  for (uint64_t t_us = 0; t_us <= 10000000; t_us += 10000) {
    ImuSample s;
    s.t_us = t_us;
    rec.imu.push_back(s);
  }
  EXPECT_TRUE(streams_ended_early(rec).empty());
  rec.imu.resize(rec.imu.size() / 2 + 1);  // IMU stops at 5 s
  const auto lines = streams_ended_early(rec);
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "imu.csv: ends at t=5.000 s, 5.000 s before uwb.csv (last 10.000 s): input stream ended early");
  rec.imu.clear();  // a UWB-only recording has no IMU stream to end early
  EXPECT_TRUE(streams_ended_early(rec).empty());
}

// gnss.csv (extension of format v1): every malformed row kind is skipped,
// counted and warned with its line like the other tables; a fix-0 row is
// receiver output ("no fix"), counted as read without a warning.
TEST(DatasetReaderGnss, BadGnssRowsAreSkippedWithTheirLineAndFixZeroRowsAreReadSilently) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/gnss.csv",
             "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s,vx_mps,vy_mps,vz_mps,sv_mps\n"  // 1
             "1.0,10,20,1.5,0.8,0.8,1.6,2,12,0.08,1,0,0,0.05\n"  // 2 ok
             "1.2,,,,,,,0,0,,,,,\n"                              // 3 fix 0: read, not kept, no warning
             "1.4,abc,20,1.5,0.8,0.8,1.6,2,12,0.08,,,,\n"        // 4 non-numeric
             "1.6,10,nan,1.5,0.8,0.8,1.6,2,12,0.08,,,,\n"        // 5 NaN
             "1.8,10,20,1.5,-0.8,0.8,1.6,2,12,0.08,,,,\n"        // 6 negative sigma
             "2.0,10,20,1.5,0.8,0,1.6,2,12,0.08,,,,\n"           // 7 zero sigma
             "2.2,10,20,1.5,0.8,0.8,1.6,2,12,-0.01,,,,\n"        // 8 latency < 0
             "2.4,10,20,1.5,0.8,0.8,1.6,3,12,0.08,,,,\n"         // 9 unknown fix code (3: PPS)
             "0.5,10,20,1.5,0.8,0.8,1.6,2,12,0.08,,,,\n"         // 10 t_s backwards
             "2.6,10,20,1.5,0.8,0.8,1.6,2,12,0.08,1,,0,\n"       // 11 partial velocity
             "2.8,10,20,1.5,0.8,0.8,1.6,2,12,0.08,1,0,0,0\n"     // 12 sv_mps not > 0
             "3.0,10,20,1.5,0.8,0.8,1.6,2,-4,0.08,,,,\n"         // 13 negative num_sv
             "3.2,10,20,1.5,0.8,0.8\n"                           // 14 column count
             "3.4,10,20,1.5,0.8,0.8,1.6,2,12,61,,,,\n"           // 15 latency above 60 s
             "3.6,11,21,1.5,0.8,0.8,1.6,1,,,,,,\n");             // 16 ok, empty optional cells
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.gnss.size(), 2U) << dump(rep);
  EXPECT_EQ(rep.rows_read, 3U + 3U) << dump(rep);  // anchors + two fixes + the fix-0 row
  EXPECT_EQ(rep.rows_skipped, 12U) << dump(rep);
  EXPECT_EQ(rep.warnings.size(), 12U) << dump(rep);
  EXPECT_FALSE(has_warning(rep, "gnss.csv:3:", "")) << "a fix-0 row is not malformed: " << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:4:", "x_m: unparsable")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:5:", "y_m: not finite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:6:", "sx_m: must be > 0")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:7:", "sy_m: must be > 0")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:8:", "latency_s: negative")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:9:", "unknown GGA quality code 3")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:10:", "backwards")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:11:", "velocity partly empty")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:12:", "sv_mps: must be > 0")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:13:", "num_sv: negative")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:14:", "expected 14 columns, got 6")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "gnss.csv:15:", "latency_s: above 60 s")) << dump(rep);

  const GnssFix& a = rec.gnss[0];
  EXPECT_EQ(a.t_us, 1000000U);
  EXPECT_EQ(a.rx_t_us, 1080000U);
  EXPECT_EQ(a.fix, GnssFixType::kDgnss);
  EXPECT_EQ(a.num_sv, 12);
  EXPECT_EQ(a.pos_nav_m.y, 20.0F);
  EXPECT_EQ(a.pos_sigma_m.z, 1.6F);
  EXPECT_EQ(a.vel_nav_mps.x, 1.0F);
  EXPECT_EQ(a.vel_sigma_mps, 0.05F);
  const GnssFix& b = rec.gnss[1];
  EXPECT_EQ(b.t_us, 3600000U);
  EXPECT_EQ(b.rx_t_us, b.t_us) << "empty latency_s means 0";
  EXPECT_EQ(b.fix, GnssFixType::kSingle);
  EXPECT_EQ(b.num_sv, 0) << "empty num_sv means unknown (0)";
  EXPECT_TRUE(std::isnan(b.vel_nav_mps.x));
  EXPECT_TRUE(std::isnan(b.vel_sigma_mps));
}

TEST(DatasetReaderGnss, LatencyGivesTheArrivalTimeAndFixesAreDeliveredInArrivalOrder) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  // Validity order 1.0, 1.2, 1.2, 1.4; a slow fix (0.35 s) arrives after the next two.
  write_file(dir + "/gnss.csv",
             "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s\n"
             "1.0,1,0,0,1,1,1,1,8,0.35\n"
             "1.2,2,0,0,1,1,1,1,8,0.05\n"
             "1.2,3,0,0,1,1,1,1,8,0.15\n"
             "1.4,4,0,0,1,1,1,1,8,0\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  ASSERT_EQ(rec.gnss.size(), 4U);
  const uint64_t want_rx[4] = {1250000, 1350000, 1350000, 1400000};
  const float want_x[4] = {2, 1, 3, 4};  // tie at 1.35 s: the file's order (stable)
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(rec.gnss[i].rx_t_us, want_rx[i]) << i;
    EXPECT_EQ(rec.gnss[i].pos_nav_m.x, want_x[i]) << i;
    EXPECT_GE(rec.gnss[i].rx_t_us, rec.gnss[i].t_us) << i;
  }

  // The streaming reader holds the same fixes once the recording is opened.
  ReadReport rep2;
  RecordingStream stream;
  ASSERT_EQ(stream.open(dir, rep2), Status::kOk) << dump(rep2);
  ASSERT_EQ(stream.gnss.size(), 4U);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(stream.gnss[i].rx_t_us, want_rx[i]) << i;
}

TEST(DatasetReaderGnss, RequiredColumnsAloneMeanSingleFixNoLatencyNoVelocity) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/gnss.csv", "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m\n# comment\n5.0,-3.5,7.25,0.5,1.5,1.5,3\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.gnss.size(), 1U);
  const GnssFix& f = rec.gnss[0];
  EXPECT_EQ(f.t_us, 5000000U);
  EXPECT_EQ(f.rx_t_us, f.t_us);
  EXPECT_EQ(f.fix, GnssFixType::kSingle);
  EXPECT_EQ(f.num_sv, 0);
  EXPECT_EQ(f.pos_nav_m.x, -3.5F);
  EXPECT_EQ(f.pos_sigma_m.z, 3.0F);
  EXPECT_TRUE(std::isnan(f.vel_nav_mps.x) && std::isnan(f.vel_nav_mps.y) && std::isnan(f.vel_nav_mps.z));
  EXPECT_TRUE(std::isnan(f.vel_sigma_mps));

  // A leading part of the optional columns is a valid header too; a skipped one is not.
  write_file(dir + "/gnss.csv", "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv\n5.0,1,2,3,1,1,2,4,20\n");
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.gnss.size(), 1U);
  EXPECT_EQ(rec.gnss[0].fix, GnssFixType::kRtkFixed);
  EXPECT_EQ(rec.gnss[0].num_sv, 20);
  write_file(dir + "/gnss.csv", "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,latency_s\n5.0,1,2,3,1,1,2,0.1\n");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);
  EXPECT_EQ(rep.error.rfind("gnss.csv:1: wrong header", 0), 0U) << rep.error;
}

TEST(DatasetReaderGnss, RecordingWithoutGnssCsvReadsAsBeforeWithNoFixesAndNoLever) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n0.1,1,5.0\n");
  write_file(dir + "/imu.csv", "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps\n0.0,0,0,9.81,0,0,0\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rec.gnss.empty());
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  EXPECT_EQ(rep.rows_read, 3U + 1U + 1U);
  EXPECT_EQ(rec.uwb.size(), 1U);
  EXPECT_EQ(rec.imu.size(), 1U);
  EXPECT_EQ(rec.site.gnss_lever_body_m.x, 0.0F);
  EXPECT_EQ(rec.site.gnss_lever_body_m.y, 0.0F);
  EXPECT_EQ(rec.site.gnss_lever_body_m.z, 0.0F);
}

TEST(DatasetReaderGnss, MetaGnssLeverTakesCommasOrBlanksAndRejectsAnythingElse) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  for (const char* good : {"0.5,-0.25,1.5", "0.5 -0.25 1.5", "0.5, -0.25,\t1.5"}) {
    write_file(dir + "/meta.ini", std::string("gnss_lever_m = ") + good + "\n");
    Recording rec;
    ReadReport rep;
    ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
    EXPECT_TRUE(rep.warnings.empty()) << good << "\n" << dump(rep);
    EXPECT_EQ(rec.site.gnss_lever_body_m.x, 0.5F) << good;
    EXPECT_EQ(rec.site.gnss_lever_body_m.y, -0.25F) << good;
    EXPECT_EQ(rec.site.gnss_lever_body_m.z, 1.5F) << good;
  }
  for (const char* bad : {"0.5,1.5", "0.5,1.5,2,3", "0.5,x,1", "0.5,nan,1", "0.5,0,101", ""}) {
    write_file(dir + "/meta.ini", std::string("gnss_lever_m = ") + bad + "\n");
    Recording rec;
    ReadReport rep;
    ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
    EXPECT_TRUE(has_warning(rep, "meta.ini:1:", "gnss_lever_m")) << bad << "\n" << dump(rep);
    EXPECT_EQ(rec.site.gnss_lever_body_m.x, 0.0F) << bad;
    EXPECT_EQ(rec.site.gnss_lever_body_m.z, 0.0F) << bad;
    EXPECT_EQ(rec.meta.count("gnss_lever_m"), 0U) << bad;
  }
}

// neighbours.csv (extension of format v1): every malformed row kind is
// skipped, counted and warned with its line; time order is per vehicle.
TEST(DatasetReaderNeighbours, BadNeighbourRowsAreSkippedWithTheirLine) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/neighbours.csv",
             "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps,coop\n"  // 1
             "1.0,32769,10,20,1.2,0.01,0.002,0,0.02,0,0.04,0.05,1,0,0,0\n"   // 2 ok
             "1.1,32767,10,20,1.2,0.01,0,0,0.01,0,0.04,,,,,\n"               // 3 an anchor id, not a vehicle
             "1.1,65535,10,20,1.2,0.01,0,0,0.01,0,0.04,,,,,\n"               // 4 0xFFFF: "no vehicle"
             "1.1,32769,abc,20,1.2,0.01,0,0,0.01,0,0.04,,,,,\n"              // 5 non-numeric
             "1.1,32769,10,20,1.2,0.01,nan,0,0.01,0,0.04,,,,,\n"             // 6 NaN
             "1.1,32769,10,20,1.2,0,0,0,0.01,0,0.04,,,,,\n"                  // 7 zero variance
             "1.1,32769,10,20,1.2,0.01,0,0,0.01,0,-0.04,,,,,\n"              // 8 negative variance
             "1.1,32769,10,20,1.2,0.01,0.02,0,0.01,0,0.04,,,,,\n"            // 9 2x2 minor < 0
             "1.1,32769,10,20,1.2,1,0.9,0.9,1,-0.9,1,,,,,\n"                 // 10 minors > 0, determinant < 0
             "1.1,32769,10,20,1.2,0.01,0,0,0.01,0,0.04,-0.01,,,,\n"          // 11 latency < 0
             "1.1,32769,10,20,1.2,0.01,0,0,0.01,0,0.04,61,,,,\n"             // 12 latency above 60 s
             "1.1,32769,10,20,1.2,0.01,0,0,0.01,0,0.04,0.05,1,,0,\n"         // 13 partial velocity
             "1.1,32769,10,20,1.2,0.01,0,0,0.01,0,0.04,0.05,,,,2\n"          // 14 coop not 0/1
             "0.5,32769,10,20,1.2,0.01,0,0,0.01,0,0.04,,,,,\n"               // 15 backwards for its vehicle
             "0.8,32770,-5,3,1.3,0.01,0,0,0.01,0,0.04,,,,,1\n"               // 16 ok: another vehicle may be earlier
             "1.2,32769,10,20,1.2,0.01,0,0,0.01\n"                           // 17 column count
             "2.0,32769,11,21,1.2,0.01,0,0,0.01,0,0.04,,,,,\n"               // 18 ok, empty optional cells
             "-1,32769,11,21,1.2,0.01,0,0,0.01,0,0.04,,,,,\n");              // 19 t_s < 0
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.neighbours.size(), 3U) << dump(rep);
  EXPECT_EQ(rep.rows_read, 3U + 3U) << dump(rep);  // anchors + three states
  EXPECT_EQ(rep.rows_skipped, 15U) << dump(rep);
  EXPECT_EQ(rep.warnings.size(), 15U) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:3:", "vehicle_id: 32767 is not a vehicle id (32768..65534)")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:4:", "vehicle_id: out of range")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:5:", "x_m: unparsable")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:6:", "pxy_m2: not finite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:7:", "pxx_m2: must be > 0")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:8:", "pzz_m2: must be > 0")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:9:", "not positive definite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:10:", "not positive definite")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:11:", "latency_s: negative")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:12:", "latency_s: above 60 s")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:13:", "velocity partly empty")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:14:", "coop: out of range")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:15:", "goes backwards for vehicle 32769")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:17:", "expected 16 columns, got 9")) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "neighbours.csv:19:", "negative time")) << dump(rep);

  // Arrival order: 0.8 s (vehicle 32770), 1.05 s, 2.0 s.
  const NeighbourState& b = rec.neighbours[0];
  EXPECT_EQ(b.vehicle_id, 32770);
  EXPECT_EQ(b.t_us, 800000U);
  EXPECT_EQ(b.rx_t_us, b.t_us) << "empty latency_s means 0";
  EXPECT_TRUE(b.cooperative);
  EXPECT_TRUE(std::isnan(b.vel_nav_mps.x));
  const NeighbourState& a = rec.neighbours[1];
  EXPECT_EQ(a.vehicle_id, 32769);
  EXPECT_EQ(a.t_us, 1000000U);
  EXPECT_EQ(a.rx_t_us, 1050000U);
  EXPECT_EQ(a.pos_nav_m.y, 20.0F);
  EXPECT_EQ(a.cov_pos_m2[0], 0.01F);
  EXPECT_EQ(a.cov_pos_m2[1], 0.002F);
  EXPECT_EQ(a.cov_pos_m2[3], 0.02F);
  EXPECT_EQ(a.cov_pos_m2[5], 0.04F);
  EXPECT_EQ(a.vel_nav_mps.x, 1.0F);
  EXPECT_FALSE(a.cooperative);
  const NeighbourState& c = rec.neighbours[2];
  EXPECT_EQ(c.t_us, 2000000U);
  EXPECT_FALSE(c.cooperative) << "empty coop means 0";
  EXPECT_TRUE(std::isnan(c.vel_nav_mps.z));
}

TEST(DatasetReaderNeighbours, LatencyGivesTheArrivalTimeAndStatesAreDeliveredInArrivalOrder) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  // Validity order 1.0, 1.0, 1.1, 1.2; the first state is slow (0.25 s) and arrives after the next two.
  write_file(dir + "/neighbours.csv",
             "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s\n"
             "1.0,32769,1,0,0,0.01,0,0,0.01,0,0.04,0.25\n"
             "1.0,32770,2,0,0,0.01,0,0,0.01,0,0.04,0.03\n"
             "1.1,32769,3,0,0,0.01,0,0,0.01,0,0.04,0.05\n"
             "1.2,32770,4,0,0,0.01,0,0,0.01,0,0.04,0.05\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  ASSERT_EQ(rec.neighbours.size(), 4U);
  const uint64_t want_rx[4] = {1030000, 1150000, 1250000, 1250000};
  const float want_x[4] = {2, 3, 1, 4};  // tie at 1.25 s: the file's order (stable)
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(rec.neighbours[i].rx_t_us, want_rx[i]) << i;
    EXPECT_EQ(rec.neighbours[i].pos_nav_m.x, want_x[i]) << i;
    EXPECT_GE(rec.neighbours[i].rx_t_us, rec.neighbours[i].t_us) << i;
  }

  // The streaming reader holds the same states once the recording is opened.
  ReadReport rep2;
  RecordingStream stream;
  ASSERT_EQ(stream.open(dir, rep2), Status::kOk) << dump(rep2);
  ASSERT_EQ(stream.neighbours.size(), 4U);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(stream.neighbours[i].rx_t_us, want_rx[i]) << i;
}

TEST(DatasetReaderNeighbours, RequiredColumnsAloneMeanNoLatencyNoVelocityIndependent) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n");
  write_file(dir + "/neighbours.csv",
             "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2\n# comment\n"
             "5.0,65534,-3.5,7.25,0.5,0.0225,-0.005,0.001,0.01,0.002,0.09\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  ASSERT_EQ(rec.neighbours.size(), 1U);
  const NeighbourState& n = rec.neighbours[0];
  EXPECT_EQ(n.t_us, 5000000U);
  EXPECT_EQ(n.rx_t_us, n.t_us);
  EXPECT_EQ(n.vehicle_id, 65534) << "the largest vehicle id";
  EXPECT_EQ(n.pos_nav_m.x, -3.5F);
  const float want_cov[6] = {0.0225F, -0.005F, 0.001F, 0.01F, 0.002F, 0.09F};
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(n.cov_pos_m2[i], want_cov[i]) << i;
  EXPECT_TRUE(std::isnan(n.vel_nav_mps.x) && std::isnan(n.vel_nav_mps.y) && std::isnan(n.vel_nav_mps.z));
  EXPECT_FALSE(n.cooperative);

  // A leading part of the optional columns is a valid header too; a skipped one is not.
  write_file(dir + "/neighbours.csv",
             "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps\n"
             "5.0,32768,1,2,3,1,0,0,1,0,1,0.02,1,2,0\n");
  rep = ReadReport{};
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.neighbours.size(), 1U);
  EXPECT_EQ(rec.neighbours[0].vehicle_id, kFirstVehicleId) << "the smallest vehicle id";
  EXPECT_EQ(rec.neighbours[0].rx_t_us, 5020000U);
  EXPECT_EQ(rec.neighbours[0].vel_nav_mps.y, 2.0F);
  write_file(dir + "/neighbours.csv",
             "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,coop\n"
             "5.0,32768,1,2,3,1,0,0,1,0,1,1\n");
  rep = ReadReport{};
  EXPECT_EQ(read_recording(dir, rec, rep), Status::kInvalidArgument);
  EXPECT_EQ(rep.error.rfind("neighbours.csv:1: wrong header", 0), 0U) << rep.error;
}

// Ranges to a vehicle's tag (anchor_id >= 32768) are uwb.csv rows like any
// other: the reader accepts ids 0..65535 and leaves their meaning to the
// firmware; a recording without neighbours.csv has no neighbour states.
TEST(DatasetReaderNeighbours, UwbRangesToVehicleIdsReadLikeAnyRangeAndNoFileMeansNoStates) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv",
             "t_s,anchor_id,range_m,tag_id,nlos\n"
             "0.1,1,5.0,0,0\n"
             "0.2,32768,12.5,0,0\n"
             "0.3,32769,20.25,1,1\n"
             "0.4,65534,7.5,0,\n"
             "0.5,65535,7.5,0,\n"
             "0.6,65536,7.5,0,\n");
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rec.uwb.size(), 5U) << dump(rep);
  EXPECT_EQ(rep.rows_skipped, 1U) << dump(rep);
  EXPECT_TRUE(has_warning(rep, "uwb.csv:7:", "anchor_id: out of range")) << dump(rep);
  EXPECT_EQ(rec.uwb[1].range.anchor_id, 32768);
  EXPECT_TRUE(is_vehicle_id(rec.uwb[1].range.anchor_id));
  EXPECT_EQ(rec.uwb[2].range.anchor_id, 32769);
  EXPECT_EQ(rec.uwb[2].range.tag_id, 1);
  EXPECT_EQ(rec.uwb[2].nlos_label, 1);
  EXPECT_EQ(rec.uwb[2].range.range_m, 20.25F);
  EXPECT_TRUE(is_vehicle_id(rec.uwb[3].range.anchor_id));
  EXPECT_EQ(rec.uwb[4].range.anchor_id, 65535);
  EXPECT_FALSE(is_vehicle_id(rec.uwb[4].range.anchor_id)) << "0xFFFF names no vehicle";
  EXPECT_TRUE(rec.neighbours.empty());
}

}  // namespace
}  // namespace uwbnav::dataset
