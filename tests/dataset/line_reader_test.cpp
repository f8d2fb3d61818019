// The streaming line walker (csv::LineReader) yields exactly the lines of the
// in-memory walk, whatever the chunk boundaries, for plain and .gz files, with
// a buffer that does not grow with the number of lines.
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>
#include <vector>

#include "tests/dataset/dataset_test_util.hpp"
#include "tools/dataset/csv.hpp"

namespace uwbnav::dataset {
namespace {

using testutil::scratch_dir;
using testutil::write_file;

std::vector<std::string> walk(csv::LineReader& lines) {
  std::vector<std::string> out;
  const char* b = nullptr;
  const char* e = nullptr;
  while (lines.next(b, e)) out.emplace_back(b, e);
  return out;
}

// Lines of varied length (some longer than a chunk), CRLF on some, a BOM, no final newline.
std::string awkward_text() {
  std::string s = "\xEF\xBB\xBFt_s,x\r\n";
  for (int i = 0; i < 5000; ++i) {
    s += std::to_string(i) + "," + std::string(static_cast<size_t>(i % 97), 'x');
    s += (i % 3 == 0) ? "\r\n" : "\n";
    if (i == 2500) s += std::string(3 * csv::LineReader::kChunk, 'L') + "\n";
    if (i % 1000 == 0) s += "\n";  // blank lines stay lines
  }
  s += "last line without newline";
  return s;
}

TEST(LineReader, StreamedLinesEqualTheInMemoryWalkAcrossChunkBoundaries) {
  const std::string text = awkward_text();
  const std::string path = scratch_dir() + "/t.csv";
  write_file(path, text);
  csv::LineReader mem;
  mem.view(text);
  csv::LineReader file;
  ASSERT_EQ(file.open(path), Status::kOk);
  const auto a = walk(mem);
  const auto b = walk(file);
  EXPECT_EQ(file.status(), Status::kOk);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "line " << i + 1;
  EXPECT_EQ(a.front(), "t_s,x");  // BOM and CR removed
  EXPECT_EQ(a.back(), "last line without newline");
  EXPECT_EQ(file.line(), a.size());
}

TEST(LineReader, BufferStaysAtOneChunkForAnyNumberOfShortLines) {
  const std::string dir = scratch_dir();
  for (int rows : {1000, 100000}) {
    std::string text;
    for (int i = 0; i < rows; ++i) text += std::to_string(i) + ",1.25,2.5\n";
    write_file(dir + "/t.csv", text);
    csv::LineReader lines;
    ASSERT_EQ(lines.open(dir + "/t.csv"), Status::kOk);
    size_t n = 0;
    const char* b = nullptr;
    const char* e = nullptr;
    while (lines.next(b, e)) ++n;
    EXPECT_EQ(n, static_cast<size_t>(rows));
    EXPECT_LE(lines.buffer_bytes(), 2 * csv::LineReader::kChunk) << rows << " rows";
  }
}

TEST(LineReader, GzipFileStreamsTheSameLinesAndReportsTruncation) {
  std::string text;
  for (int i = 0; i < 20000; ++i) text += std::to_string(i) + ",0.125\n";
  z_stream zs{};
  ASSERT_EQ(deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string gz(deflateBound(&zs, static_cast<uLong>(text.size())) + 64, '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(&gz[0]);
  zs.avail_out = static_cast<uInt>(gz.size());
  ASSERT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  gz.resize(zs.total_out);
  deflateEnd(&zs);
  const std::string dir = scratch_dir();
  write_file(dir + "/t.csv.gz", gz);
  csv::LineReader whole;
  ASSERT_EQ(whole.open(dir + "/t.csv"), Status::kOk);  // falls back to t.csv.gz
  EXPECT_EQ(walk(whole).size(), 20000U);
  EXPECT_EQ(whole.status(), Status::kOk);

  write_file(dir + "/t.csv.gz", gz.substr(0, gz.size() / 2));
  csv::LineReader cut;
  ASSERT_EQ(cut.open(dir + "/t.csv"), Status::kOk);
  EXPECT_LT(walk(cut).size(), 20000U);
  EXPECT_EQ(cut.status(), Status::kIoError);
  EXPECT_NE(cut.error().find("t.csv.gz: truncated gzip stream"), std::string::npos) << cut.error();
}

}  // namespace
}  // namespace uwbnav::dataset
