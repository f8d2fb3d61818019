// Streaming replay keeps its memory independent of the recording's length
// (issue 17 target: the same peak for a 1 h and a 10 h drive). This binary
// replaces the global operator new/delete to track the bytes live on the heap,
// and replays a short and a four times longer drive the way `uwbnav replay`
// does (streamed input, outputs written, result table on the fly): the peak
// heap use of both must be the same within a small slack, and small in absolute terms.
#include <gtest/gtest.h>
#include <malloc.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"
#include "tools/dataset/tables.hpp"
#include "tools/eval/replay.hpp"
#include "tools/eval/summary.hpp"
#include "tools/sim/simulator.hpp"

namespace {

std::atomic<long long> g_live_bytes{0};
std::atomic<long long> g_peak_bytes{0};

void* counted_alloc(std::size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  const long long now = g_live_bytes += static_cast<long long>(malloc_usable_size(p));
  long long peak = g_peak_bytes.load();
  while (now > peak && !g_peak_bytes.compare_exchange_weak(peak, now)) {
  }
  return p;
}

void counted_free(void* p) {
  if (p == nullptr) return;
  g_live_bytes -= static_cast<long long>(malloc_usable_size(p));
  std::free(p);
}

}  // namespace

void* operator new(std::size_t n) { return counted_alloc(n); }
void* operator new[](std::size_t n) { return counted_alloc(n); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p); }

namespace uwbnav::eval {
namespace {

std::string make_drive(const std::string& name, double duration_s) {
  const auto root = std::filesystem::path(::testing::TempDir()) / "uwbnav_stream_memory";
  std::filesystem::create_directories(root);
  const std::string dir = (root / name).string();
  std::filesystem::remove_all(dir);
  {
    std::ofstream scn(dir + ".scn");
    scn << "base = drive_1h\n[scenario]\nduration_s = " << duration_s << "\n";
  }
  dataset::Recording rec;
  std::string err;
  EXPECT_EQ(sim::simulate(dir + ".scn", 5, rec, &err), Status::kOk) << err;
  EXPECT_EQ(dataset::write_recording(dir, rec), Status::kOk);
  return dir;
}

struct Peak {
  long long heap_bytes = 0;  // peak live heap during the replay, above what was live before it
  uint64_t cycles = 0;
};

// What `uwbnav replay DIR --out OUT` does, measured.
Peak streamed_replay(const std::string& dir) {
  const std::string out = dir + "_out";
  std::filesystem::create_directories(out);
  Peak peak;
  const long long before = g_live_bytes.load();
  g_peak_bytes = before;
  {
    dataset::RecordingStream rec;
    dataset::ReadReport report;
    EXPECT_EQ(rec.open(dir, report, false), Status::kOk) << report.error;
    dataset::RowStream<dataset::UwbRow> summary_uwb;
    dataset::RowStream<dataset::TruthRow> truth;
    dataset::ReadReport summary_report, truth_report;
    EXPECT_EQ(summary_uwb.open(dir, "uwb.csv", dataset::tables::kUwb, true, summary_report), Status::kOk);
    EXPECT_EQ(truth.open(dir, "truth.csv", dataset::tables::kTruth, true, truth_report), Status::kOk);
    SummaryBuilder summary(rec.site, rec.name(), summary_uwb, &truth);
    ReplayOptions opt;
    opt.out_dir = out;
    opt.keep_in_memory = false;
    opt.sink = &summary;
    ReplayResult result;
    std::string err;
    EXPECT_EQ(run_replay(rec, opt, result, &err), Status::kOk) << err;
    const RunSummary s = summary.finish(result);
    EXPECT_GT(s.filter.epochs, 0U);
    EXPECT_GT(s.ls_uwb.epochs, 0U);
    peak.cycles = result.cycles;
  }
  peak.heap_bytes = g_peak_bytes.load() - before;
  return peak;
}

TEST(StreamingReplayMemory, PeakHeapOfTheReplayDoesNotGrowWithTheDrivesLength) {
  const std::string short_dir = make_drive("drive_60s", 60.0);
  const std::string long_dir = make_drive("drive_240s", 240.0);
  const Peak a = streamed_replay(short_dir);
  const Peak b = streamed_replay(long_dir);
  ASSERT_GT(b.cycles, 3 * a.cycles);
  std::printf("peak heap of the replay: %lld B (%llu cycles), %lld B (%llu cycles)\n", a.heap_bytes,
              static_cast<unsigned long long>(a.cycles), b.heap_bytes, static_cast<unsigned long long>(b.cycles));
  // Rows held in memory would add ~100 bytes per row: 18,000 more IMU rows alone
  // would be ~2 MB. Allow 16 KiB of slack for string lengths that vary.
  EXPECT_LE(b.heap_bytes, a.heap_bytes + 16 * 1024) << "short " << a.heap_bytes << " B, long " << b.heap_bytes << " B";
  EXPECT_LT(b.heap_bytes, 2 * 1024 * 1024) << "streaming replay should hold about 1 MB at most";
}

TEST(StreamingReplayMemory, RowStreamHoldsOneRowAndOneBufferWhateverTheFileLength) {
  const std::string dir = make_drive("drive_reader", 120.0);
  dataset::ReadReport report;
  dataset::RowStream<ImuSample> imu;
  ASSERT_EQ(imu.open(dir, "imu.csv", dataset::tables::kImu, true, report), Status::kOk);
  const long long before = g_live_bytes.load();
  g_peak_bytes = before;
  ImuSample s;
  size_t n = 0;
  while (imu.next(s)) ++n;
  EXPECT_GT(n, 10000U);
  EXPECT_LE(g_peak_bytes.load() - before, 1024) << "reading rows allocated";
  EXPECT_LE(imu.buffer_bytes(), 2 * dataset::csv::LineReader::kChunk);
}

}  // namespace
}  // namespace uwbnav::eval
