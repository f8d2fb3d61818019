// Format v1 reader on gzip-compressed tables (X.csv.gz read when X.csv is
// absent): same rows as the plain file, multi-member files, and truncated or
// corrupt .gz input failing with a clear error instead of short or garbage rows.
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>
#include <vector>

#include "tests/dataset/dataset_test_util.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/text_source.hpp"
#include "tools/eval/svm_features.hpp"

namespace uwbnav::dataset {
namespace {

using testutil::dump;
using testutil::kAnchorsOk;
using testutil::scratch_dir;
using testutil::write_file;

// One gzip member holding `text` (deflate at level 9, gzip wrapper).
std::string gzip(const std::string& text) {
  z_stream zs{};
  EXPECT_EQ(deflateInit2(&zs, 9, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&zs, static_cast<uLong>(text.size())) + 64, '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(&out[0]);
  zs.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  return out;
}

// 2000 ranges: large enough that the compressed file spans several read chunks.
std::string uwb_table() {
  std::string s = "t_s,anchor_id,range_m\n";
  for (int i = 0; i < 2000; ++i) s += std::to_string(i) + ".5," + std::to_string(1 + i % 4) + ",12.25\n";
  return s;
}

TEST(DatasetReaderGzip, CompressedTablesReadLikeThePlainOnes) {
  const std::string plain = scratch_dir() + "_plain";
  const std::string packed = scratch_dir();
  std::filesystem::create_directories(plain);
  write_file(plain + "/anchors.csv", kAnchorsOk);
  write_file(plain + "/uwb.csv", uwb_table());
  write_file(packed + "/anchors.csv.gz", gzip(kAnchorsOk));
  write_file(packed + "/uwb.csv.gz", gzip(uwb_table()));
  Recording a;
  Recording b;
  ReadReport ra;
  ReadReport rb;
  ASSERT_EQ(read_recording(plain, a, ra), Status::kOk) << dump(ra);
  ASSERT_EQ(read_recording(packed, b, rb), Status::kOk) << dump(rb);
  ASSERT_EQ(b.uwb.size(), 2000U);
  ASSERT_EQ(a.uwb.size(), b.uwb.size());
  EXPECT_EQ(b.uwb.back().range.t_us, a.uwb.back().range.t_us);
  EXPECT_EQ(b.site.num_anchors, a.site.num_anchors);
  EXPECT_EQ(rb.rows_skipped, 0U);
}

TEST(DatasetReaderGzip, PlainFileWinsOverItsGzipTwin) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv", kAnchorsOk);
  write_file(dir + "/uwb.csv", "t_s,anchor_id,range_m\n1.0,1,3.0\n");
  write_file(dir + "/uwb.csv.gz", gzip(uwb_table()));
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_EQ(rec.uwb.size(), 1U);
}

TEST(DatasetReaderGzip, ConcatenatedMembersReadAsOneFile) {
  const std::string dir = scratch_dir();
  write_file(dir + "/anchors.csv.gz", gzip(kAnchorsOk));
  write_file(dir + "/uwb.csv.gz", gzip("t_s,anchor_id,range_m\n1.0,1,3.0\n") + gzip("2.0,1,4.0\n"));
  Recording rec;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, rec, rep), Status::kOk) << dump(rep);
  EXPECT_EQ(rec.uwb.size(), 2U);
}

TEST(DatasetReaderGzip, TruncatedGzipFailsTheReadNamingTheFile) {
  const std::string packed = gzip(uwb_table());
  // Cut inside the deflate data, just before the 8-byte trailer, and after the header only.
  for (const size_t keep : {packed.size() / 2, packed.size() - 4, static_cast<size_t>(12)}) {
    SCOPED_TRACE(keep);
    const std::string dir = scratch_dir();
    write_file(dir + "/anchors.csv", kAnchorsOk);
    write_file(dir + "/uwb.csv.gz", packed.substr(0, keep));
    Recording rec;
    ReadReport rep;
    EXPECT_EQ(read_recording(dir, rec, rep), Status::kIoError);
    EXPECT_NE(rep.error.find("uwb.csv"), std::string::npos) << rep.error;
    EXPECT_NE(rep.error.find("truncated"), std::string::npos) << rep.error;
    EXPECT_TRUE(rec.uwb.empty());
  }
}

TEST(DatasetReaderGzip, CorruptGzipFailsTheRead) {
  std::string packed = gzip(uwb_table());
  std::vector<std::string> bad;
  std::string flipped = packed;
  flipped[packed.size() / 2] = static_cast<char>(flipped[packed.size() / 2] ^ 0x5A);
  bad.push_back(flipped);                                  // damaged deflate data (or CRC mismatch)
  std::string crc = packed;
  crc[packed.size() - 6] = static_cast<char>(crc[packed.size() - 6] ^ 0x01);
  bad.push_back(crc);                                      // CRC-32 of the trailer wrong
  bad.push_back("t_s,anchor_id,range_m\n1.0,1,3.0\n");     // plain text named .gz
  bad.push_back(std::string());                            // empty file
  bad.push_back(packed + "garbage after the member");      // trailing bytes that are no member
  for (size_t i = 0; i < bad.size(); ++i) {
    SCOPED_TRACE(i);
    const std::string dir = scratch_dir();
    write_file(dir + "/anchors.csv", kAnchorsOk);
    write_file(dir + "/uwb.csv.gz", bad[i]);
    Recording rec;
    ReadReport rep;
    EXPECT_EQ(read_recording(dir, rec, rep), Status::kIoError) << dump(rep);
    EXPECT_NE(rep.error.find("uwb.csv"), std::string::npos) << rep.error;
  }
}

TEST(DatasetReaderGzip, LineSourceSplitsLinesAcrossChunksAndReportsTruncation) {
  const std::string dir = scratch_dir();
  write_file(dir + "/t.csv.gz", gzip(uwb_table()));
  TextSource src;
  ASSERT_EQ(src.open(dir + "/t.csv"), Status::kOk);
  EXPECT_TRUE(src.compressed());
  std::string line;
  size_t lines = 0;
  while (src.getline(line)) ++lines;
  EXPECT_EQ(src.status(), Status::kOk) << src.error();
  EXPECT_EQ(lines, 2001U);
  std::string table = "label,fp_power_dbm,rx_power_dbm\n";
  for (int i = 0; i < 3000; ++i) table += std::to_string(i % 2) + ",-8" + std::to_string(i % 10) + ".5,-79.25\n";
  const std::string packed = gzip(table);
  write_file(dir + "/whole.csv.gz", packed);
  std::vector<eval::SvmSample> samples;
  std::string err;
  ASSERT_EQ(eval::samples_from_table(dir + "/whole.csv", SvmFeatureSet::kChannel, samples, &err), Status::kOk) << err;
  EXPECT_EQ(samples.size(), 3000U);
  write_file(dir + "/cut.csv.gz", packed.substr(0, packed.size() / 2));
  samples.clear();
  EXPECT_NE(eval::samples_from_table(dir + "/cut.csv", SvmFeatureSet::kChannel, samples, &err), Status::kOk);
  EXPECT_NE(err.find("cut.csv.gz"), std::string::npos) << err;
}

}  // namespace
}  // namespace uwbnav::dataset
