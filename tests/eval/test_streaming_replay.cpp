// Streaming replay (issue 17 item 3): a recording streamed from its directory
// gives the same firmware outputs as the same recording replayed from memory,
// the result table computed on the fly equals the whole-file metrics (computed
// here independently: truth interpolation, LS-UWB baseline, RMSE/MAX/STD,
// in-2-sigma, availability, split by mode), and damage met mid-stream is named
// with file and line (bad row) or ends the stream with the file's read error.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "estimator/ls_taylor.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"
#include "tools/dataset/tables.hpp"
#include "tools/eval/replay.hpp"
#include "tools/eval/summary.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::eval {
namespace {

std::string scratch(const std::string& leaf) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto p = std::filesystem::path(::testing::TempDir()) / "uwbnav_stream_tests" /
                 (std::string(info->test_suite_name()) + "." + info->name()) / leaf;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p.parent_path());
  return p.string();
}

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << bytes;
}

// A 40 s drive of the default parking scenario (NLOS, outliers, start-up
// fallback epochs and IMU-filter epochs both present) written to `dir`.
void simulate_to(const std::string& dir, double duration_s = 40.0) {
  const std::string scn = dir + ".scn";
  std::filesystem::create_directories(std::filesystem::path(dir).parent_path());
  spit(scn, "base = parking_nlos\n[scenario]\nduration_s = " + std::to_string(duration_s) + "\n");
  dataset::Recording rec;
  std::string err;
  ASSERT_EQ(sim::simulate(scn, 3, rec, &err), Status::kOk) << err;
  ASSERT_EQ(dataset::write_recording(dir, rec), Status::kOk);
}

// ---- whole-file reference, independent of the streaming code ----

bool ref_truth_at(const std::vector<dataset::TruthRow>& truth, uint64_t t_us, double p[3]) {
  if (truth.empty() || t_us < truth.front().t_us || t_us > truth.back().t_us) return false;
  size_t i = 0;
  while (truth[i].t_us < t_us) ++i;  // first row at or after t_us
  if (truth[i].t_us == t_us) {
    for (int k = 0; k < 3; ++k) p[k] = truth[i].pos_nav_m[k];
    return true;
  }
  const auto& a = truth[i - 1];
  const auto& b = truth[i];
  if (b.t_us - a.t_us > 200000) return false;
  const double w = static_cast<double>(t_us - a.t_us) / static_cast<double>(b.t_us - a.t_us);
  for (int k = 0; k < 3; ++k) p[k] = a.pos_nav_m[k] + w * (b.pos_nav_m[k] - a.pos_nav_m[k]);
  return true;
}

struct RefStats {
  size_t epochs = 0;
  double rmse = 0, max = 0, std = 0, in_x = 0, in_y = 0;
};

RefStats ref_stats(const std::vector<std::vector<double>>& err_sigma) {  // ex, ey, sx, sy per epoch
  RefStats r;
  r.epochs = err_sigma.size();
  if (r.epochs == 0) return r;
  std::vector<double> h;
  double sum2 = 0;
  size_t in_x = 0, in_y = 0;
  for (const auto& e : err_sigma) {
    h.push_back(std::sqrt(e[0] * e[0] + e[1] * e[1]));
    sum2 += h.back() * h.back();
    r.max = std::max(r.max, h.back());
    in_x += std::fabs(e[0]) <= 2 * e[2] ? 1 : 0;
    in_y += std::fabs(e[1]) <= 2 * e[3] ? 1 : 0;
  }
  const double n = static_cast<double>(h.size());
  double mean = 0;
  for (double v : h) mean += v / n;
  double var = 0;
  for (double v : h) var += (v - mean) * (v - mean) / n;
  r.rmse = std::sqrt(sum2 / n);
  r.std = std::sqrt(var);
  r.in_x = static_cast<double>(in_x) / n;
  r.in_y = static_cast<double>(in_y) / n;
  return r;
}

// Linear LS of the first tag at every 10 ms epoch from the latest range per anchor of the last 150 ms.
std::vector<dataset::EstimateRow> ref_ls(const dataset::Recording& rec) {
  std::vector<dataset::EstimateRow> out;
  const SiteConfig& site = rec.site;
  float zmin = 1e9F, zmax = -1e9F;
  for (size_t a = 0; a < site.num_anchors; ++a) {
    zmin = std::min(zmin, site.anchors[a].pos_nav_m.z);
    zmax = std::max(zmax, site.anchors[a].pos_nav_m.z);
  }
  std::vector<uint64_t> last_t(site.num_anchors, 0);
  std::vector<float> last_r(site.num_anchors, 0.0F);
  std::vector<bool> have(site.num_anchors, false);
  size_t next = 0;
  for (uint64_t t = (rec.uwb.front().range.t_us / 10000 + 1) * 10000; t <= rec.uwb.back().range.t_us + 10000;
       t += 10000) {
    for (; next < rec.uwb.size() && rec.uwb[next].range.t_us <= t; ++next) {
      const UwbRange& r = rec.uwb[next].range;
      const int a = site.find_anchor(r.anchor_id);
      if (r.tag_id != site.tags[0].id || a < 0) continue;
      last_t[static_cast<size_t>(a)] = r.t_us;
      last_r[static_cast<size_t>(a)] = r.range_m;
      have[static_cast<size_t>(a)] = true;
    }
    LsRange ranges[kMaxAnchors];
    size_t n = 0;
    for (size_t a = 0; a < site.num_anchors; ++a) {
      if (!have[a] || t - last_t[a] > 150000) continue;
      ranges[n++] = LsRange{site.anchors[a].pos_nav_m, last_r[a], 0.1F};
    }
    LsOptions opt;
    opt.two_d = zmax - zmin < 0.5F;
    opt.known_z_m = site.tags[0].lever_body_m.z;
    opt.max_iterations = 0;
    LsFix fix;
    if (!ok(ls_taylor_solve(ranges, n, opt, fix))) continue;
    dataset::EstimateRow row;
    row.t_us = t;
    row.pos_nav_m[0] = fix.pos_nav_m.x;
    row.pos_nav_m[1] = fix.pos_nav_m.y;
    out.push_back(row);
  }
  return out;
}

// Truth of the tag antenna: body origin + R(q) * lever (or + lever z without attitude).
std::vector<dataset::TruthRow> ref_tag_truth(const dataset::Recording& rec) {
  std::vector<dataset::TruthRow> out = rec.truth;
  const Vec3f l = rec.site.tags[0].lever_body_m;
  for (auto& t : out) {
    const double w = t.q_nav_body[0], x = t.q_nav_body[1], y = t.q_nav_body[2], z = t.q_nav_body[3];
    const double lx = l.x, ly = l.y, lz = l.z;
    if (!t.has_attitude) {
      t.pos_nav_m[2] += lz;
      continue;
    }
    t.pos_nav_m[0] += (1 - 2 * (y * y + z * z)) * lx + 2 * (x * y - w * z) * ly + 2 * (x * z + w * y) * lz;
    t.pos_nav_m[1] += 2 * (x * y + w * z) * lx + (1 - 2 * (x * x + z * z)) * ly + 2 * (y * z - w * x) * lz;
    t.pos_nav_m[2] += 2 * (x * z - w * y) * lx + 2 * (y * z + w * x) * ly + (1 - 2 * (x * x + y * y)) * lz;
  }
  return out;
}

void expect_same(const AccuracyStats& got, const RefStats& want, size_t total, const char* what, bool sigma = true) {
  SCOPED_TRACE(what);
  ASSERT_GT(want.epochs, 0U);
  EXPECT_EQ(got.epochs, want.epochs);
  EXPECT_EQ(got.epochs_total, total);
  EXPECT_NEAR(got.rmse_h_m, want.rmse, 1e-9 * (1 + want.rmse));
  EXPECT_DOUBLE_EQ(got.max_h_m, want.max);
  EXPECT_NEAR(got.std_h_m, want.std, 1e-9 * (1 + want.std));
  if (sigma) {
    EXPECT_DOUBLE_EQ(got.inside_2sigma_x, want.in_x);
    EXPECT_DOUBLE_EQ(got.inside_2sigma_y, want.in_y);
  }
}

TEST(StreamingReplay, StreamedTableEqualsTheWholeFileMetricsAndOutputsAreIdentical) {
  const std::string dir = scratch("rec");
  simulate_to(dir);
  // GIVEN the whole recording in memory and its replay kept in memory
  dataset::Recording rec;
  dataset::ReadReport rr;
  ASSERT_EQ(dataset::read_recording(dir, rec, rr), Status::kOk) << rr.error;
  ReplayOptions mem_opt;
  mem_opt.out_dir = scratch("out_memory");
  std::filesystem::create_directories(mem_opt.out_dir);
  ReplayResult mem;
  std::string err;
  ASSERT_EQ(run_replay(rec, mem_opt, mem, &err), Status::kOk) << err;

  // WHEN the same directory is streamed with the table built on the fly
  dataset::RecordingStream stream;
  dataset::ReadReport sr;
  ASSERT_EQ(stream.open(dir, sr, false), Status::kOk) << sr.error;
  // The builder runs on the output thread: readers (and reports) of its own.
  dataset::RowStream<dataset::UwbRow> summary_uwb;
  dataset::RowStream<dataset::TruthRow> truth;
  dataset::ReadReport ur, tr;
  ASSERT_EQ(summary_uwb.open(dir, "uwb.csv", dataset::tables::kUwb, true, ur), Status::kOk);
  ASSERT_EQ(truth.open(dir, "truth.csv", dataset::tables::kTruth, true, tr), Status::kOk);
  SummaryBuilder builder(stream.site, stream.name(), summary_uwb, &truth);
  ReplayOptions st_opt;
  st_opt.out_dir = scratch("out_stream");
  std::filesystem::create_directories(st_opt.out_dir);
  st_opt.keep_in_memory = false;
  st_opt.sink = &builder;
  ReplayResult st;
  ASSERT_EQ(run_replay(stream, st_opt, st, &err), Status::kOk) << err;
  const RunSummary s = builder.finish(st);
  EXPECT_TRUE(stream.read_error().empty());
  EXPECT_TRUE(st.estimates.empty());  // nothing kept

  // THEN the firmware saw the same input: identical outputs, counters and cycles
  for (const char* f : {"estimates.csv", "ranges.csv", "can.log"}) {
    EXPECT_EQ(slurp(mem_opt.out_dir + "/" + f), slurp(st_opt.out_dir + "/" + f)) << f;
  }
  EXPECT_EQ(st.cycles, mem.cycles);
  EXPECT_EQ(st.epochs, mem.estimates.size());
  EXPECT_EQ(st.ranges_used, mem.ranges_used);

  // AND the table equals the whole-file reference
  size_t total = 0;
  std::vector<std::vector<double>> all, inertial, fallback;
  for (const auto& e : mem.estimates) {
    double p[3];
    if (!ref_truth_at(rec.truth, e.t_us, p)) continue;
    ++total;
    if (e.status != 1 && e.status != 2) continue;
    const std::vector<double> v{e.pos_nav_m[0] - p[0], e.pos_nav_m[1] - p[1], e.pos_sigma_m[0], e.pos_sigma_m[1]};
    all.push_back(v);
    if (e.mode == static_cast<int>(NavMode::kInertial)) inertial.push_back(v);
    if (e.mode != static_cast<int>(NavMode::kInertial) && e.mode != static_cast<int>(NavMode::kNone)) {
      fallback.push_back(v);
    }
  }
  std::vector<std::vector<double>> ls;
  const auto tag_truth = ref_tag_truth(rec);
  for (const auto& f : ref_ls(rec)) {
    double p[3];
    if (ref_truth_at(tag_truth, f.t_us, p)) ls.push_back({f.pos_nav_m[0] - p[0], f.pos_nav_m[1] - p[1], 1e9, 1e9});
  }
  ASSERT_TRUE(s.has_truth);
  expect_same(s.filter, ref_stats(all), total, "filter");
  expect_same(s.inertial, ref_stats(inertial), total, "IMU filter epochs");
  expect_same(s.fallback, ref_stats(fallback), total, "fallback epochs");
  expect_same(s.ls_uwb, ref_stats(ls), total, "LS-UWB", false);  // the table shows no in-2-sigma for LS
  uint64_t labelled = 0;
  for (const auto& u : rec.uwb) labelled += u.nlos_label == 1 ? 1 : 0;
  EXPECT_EQ(s.ranges_nlos_labelled, labelled);
  EXPECT_GT(labelled, 0U);

  // AND the in-memory summary (same builder over vectors) agrees too
  const RunSummary m = summarise(rec, mem);
  EXPECT_EQ(m.filter.epochs, s.filter.epochs);
  EXPECT_DOUBLE_EQ(m.filter.rmse_h_m, s.filter.rmse_h_m);
  EXPECT_DOUBLE_EQ(m.ls_uwb.rmse_h_m, s.ls_uwb.rmse_h_m);
}

TEST(StreamingReplay, BadRowMidStreamIsWarnedWithFileAndLineAndSkipped) {
  const std::string dir = scratch("rec");
  simulate_to(dir, 10.0);
  std::string imu = slurp(dir + "/imu.csv");
  // Line 501 (the 500th data row) gets an unparsable accelerometer cell.
  size_t pos = 0;
  for (int i = 0; i < 500; ++i) pos = imu.find('\n', pos) + 1;
  const size_t comma = imu.find(',', pos);
  imu.replace(comma + 1, imu.find(',', comma + 1) - comma - 1, "1.2.3");
  spit(dir + "/imu.csv", imu);

  dataset::RecordingStream stream;
  dataset::ReadReport report;
  ASSERT_EQ(stream.open(dir, report), Status::kOk) << report.error;
  EXPECT_TRUE(report.warnings.empty());  // met only when the replay gets there
  ReplayOptions opt;
  opt.keep_in_memory = false;
  ReplayResult res;
  std::string err;
  ASSERT_EQ(run_replay(stream, opt, res, &err), Status::kOk) << err;
  ASSERT_EQ(report.warnings.size(), 1U);
  EXPECT_EQ(report.warnings[0], "imu.csv:501: ax_mps2: unparsable number '1.2.3'");
  EXPECT_EQ(report.rows_skipped, 1U);
  EXPECT_TRUE(stream.read_error().empty());
}

TEST(StreamingReplay, TruncatedGzipMidStreamEndsThatStreamWithItsReadError) {
  const std::string dir = scratch("rec");
  simulate_to(dir, 20.0);
  // imu.csv -> imu.csv.gz cut at two thirds (the header and first rows still inflate).
  const std::string text = slurp(dir + "/imu.csv");
  z_stream zs{};
  ASSERT_EQ(deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string gz(deflateBound(&zs, static_cast<uLong>(text.size())) + 64, '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = static_cast<uInt>(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(&gz[0]);
  zs.avail_out = static_cast<uInt>(gz.size());
  ASSERT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  gz.resize(zs.total_out * 2 / 3);
  deflateEnd(&zs);
  std::filesystem::remove(dir + "/imu.csv");
  spit(dir + "/imu.csv.gz", gz);

  dataset::RecordingStream stream;
  dataset::ReadReport report;
  ASSERT_EQ(stream.open(dir, report), Status::kOk) << report.error;
  ReplayOptions opt;
  opt.keep_in_memory = false;
  ReplayResult res;
  std::string err;
  ASSERT_EQ(run_replay(stream, opt, res, &err), Status::kOk) << err;
  EXPECT_EQ(stream.read_error().rfind("imu.csv: cannot be read (", 0), 0U) << stream.read_error();
  EXPECT_NE(stream.read_error().find("imu.csv.gz: truncated gzip stream"), std::string::npos) << stream.read_error();
  EXPECT_LT(stream.imu.last_t_us() + dataset::kStreamEndToleranceUs, stream.uwb.last_t_us());
  EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();  // the cut line is no row
  // The whole-file reader fails on the same file as before.
  dataset::Recording rec;
  dataset::ReadReport rr;
  EXPECT_EQ(dataset::read_recording(dir, rec, rr), Status::kIoError);
  EXPECT_NE(rr.error.find("imu.csv.gz: truncated gzip stream"), std::string::npos) << rr.error;
}

}  // namespace
}  // namespace uwbnav::eval
