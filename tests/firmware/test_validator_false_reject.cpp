// False-reject rate of every input validation rule on synthetic and real data
// (issue 19: validation never discards good data). The validator runs as the
// App runs it in lockstep (each frame checked at the first 10 ms cycle at or
// after its stamp); a range is "good" when it is a genuine measurement:
// simulated ranges that are not gross outliers; real ranges within 1 m of the
// truth range plus the pair's median offset. Every rule must reject no good
// frame. The duplicate rule is also checked to catch real duplicates (a frame
// re-reported with its pair and timestamp), and the old bit-identical-value
// rule is measured for comparison (it dropped 7-15 % of good ranges).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "calib/trolley_recording.hpp"
#include "estimator/params.hpp"
#include "firmware/app.hpp"
#include "firmware/input_validator.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

struct RuleStats {
  uint64_t frames = 0;
  uint64_t good = 0;
  uint64_t rejected[kNumRejectReasons] = {};
  uint64_t false_rejected[kNumRejectReasons] = {};
  uint64_t false_total() const {
    uint64_t n = 0;
    for (uint64_t v : false_rejected) n += v;
    return n;
  }
};

uint64_t cycle_of(uint64_t t_us) { return (t_us + kCyclePeriodUs - 1) / kCyclePeriodUs * kCyclePeriodUs; }

RuleStats validate_uwb(const SiteConfig& site, const std::vector<UwbRange>& ranges, const std::vector<bool>& good) {
  InputValidator v;
  const Params params;
  v.configure(site, params);
  RuleStats st;
  for (size_t i = 0; i < ranges.size(); ++i) {
    ++st.frames;
    st.good += good[i] ? 1U : 0U;
    const Verdict verdict = v.check_uwb(ranges[i], cycle_of(ranges[i].t_us));
    if (verdict.accepted) continue;
    ++st.rejected[static_cast<size_t>(verdict.reason)];
    if (good[i]) ++st.false_rejected[static_cast<size_t>(verdict.reason)];
  }
  return st;
}

RuleStats validate_imu(const SiteConfig& site, const std::vector<ImuSample>& imu) {
  InputValidator v;
  const Params params;
  v.configure(site, params);
  RuleStats st;
  for (const ImuSample& s : imu) {
    ++st.frames;
    ++st.good;  // no fault labels: every recorded sample counts as good
    const Verdict verdict = v.check_imu(s, cycle_of(s.t_us));
    if (verdict.accepted) continue;
    ++st.rejected[static_cast<size_t>(verdict.reason)];
    ++st.false_rejected[static_cast<size_t>(verdict.reason)];
  }
  return st;
}

// Good ranges the retired rule (bit-identical to the pair's previous value) would have dropped.
uint64_t old_repeat_rule_drops(const std::vector<UwbRange>& ranges, const std::vector<bool>& good) {
  std::map<std::pair<uint16_t, uint8_t>, float> last;
  uint64_t n = 0;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const auto key = std::make_pair(ranges[i].anchor_id, ranges[i].tag_id);
    const auto it = last.find(key);
    if (it != last.end() && std::memcmp(&it->second, &ranges[i].range_m, sizeof(float)) == 0 && good[i]) ++n;
    last[key] = ranges[i].range_m;
  }
  return n;
}

void print_row(const char* dataset, const char* stream, const RuleStats& st, uint64_t old_drops) {
  std::printf("false-reject %-28s %-3s frames %7llu good %7llu", dataset, stream,
              static_cast<unsigned long long>(st.frames), static_cast<unsigned long long>(st.good));
  for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
    std::printf(" %s=%llu/%llu", reject_reason_name(static_cast<RejectReason>(r)),
                static_cast<unsigned long long>(st.false_rejected[r]), static_cast<unsigned long long>(st.rejected[r]));
  }
  if (old_drops != UINT64_MAX) {
    std::printf(" | old repeat rule: %llu good dropped (%.2f %%)", static_cast<unsigned long long>(old_drops),
                st.good > 0 ? 100.0 * static_cast<double>(old_drops) / static_cast<double>(st.good) : 0.0);
  }
  std::printf("\n");
}

std::vector<UwbRange> ranges_of(const dataset::Recording& rec) {
  std::vector<UwbRange> out;
  for (const auto& row : rec.uwb) out.push_back(row.range);
  return out;
}

// Real recordings: good = within 1 m of the truth range plus the pair's median offset.
std::vector<bool> good_by_truth(const dataset::Recording& rec) {
  std::vector<double> resid(rec.uwb.size(), NAN);
  size_t j = 0;
  for (size_t i = 0; i < rec.uwb.size(); ++i) {
    const UwbRange& r = rec.uwb[i].range;
    while (j + 1 < rec.truth.size() && rec.truth[j + 1].t_us < r.t_us) ++j;
    if (j + 1 >= rec.truth.size() || rec.truth[j].t_us > r.t_us) continue;
    const auto& a = rec.truth[j];
    const auto& b = rec.truth[j + 1];
    const double w = static_cast<double>(r.t_us - a.t_us) / static_cast<double>(b.t_us - a.t_us);
    const int ai = rec.site.find_anchor(r.anchor_id);
    const int ti = rec.site.find_tag(r.tag_id);
    if (ai < 0 || ti < 0) continue;
    const Vec3f& l = rec.site.tags[ti].lever_body_m;
    const double lv[3] = {static_cast<double>(l.x), static_cast<double>(l.y), static_cast<double>(l.z)};
    double q[4] = {1, 0, 0, 0};
    if (a.has_attitude) {
      for (int k = 0; k < 4; ++k) q[k] = a.q_nav_body[k];
    }
    // v' = v + 2 qw (u x v) + 2 u x (u x v), u = (qx, qy, qz)
    const double u[3] = {q[1], q[2], q[3]};
    const double c1[3] = {u[1] * lv[2] - u[2] * lv[1], u[2] * lv[0] - u[0] * lv[2], u[0] * lv[1] - u[1] * lv[0]};
    const double c2[3] = {u[1] * c1[2] - u[2] * c1[1], u[2] * c1[0] - u[0] * c1[2], u[0] * c1[1] - u[1] * c1[0]};
    const Vec3f& an = rec.site.anchors[ai].pos_nav_m;
    const double anv[3] = {static_cast<double>(an.x), static_cast<double>(an.y), static_cast<double>(an.z)};
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double p = (1.0 - w) * a.pos_nav_m[k] + w * b.pos_nav_m[k] + lv[k] + 2.0 * q[0] * c1[k] + 2.0 * c2[k];
      d2 += (p - anv[k]) * (p - anv[k]);
    }
    resid[i] = static_cast<double>(r.range_m) - std::sqrt(d2);
  }
  std::map<std::pair<uint16_t, uint8_t>, std::vector<double>> per_pair;
  for (size_t i = 0; i < resid.size(); ++i) {
    if (!std::isnan(resid[i])) per_pair[{rec.uwb[i].range.anchor_id, rec.uwb[i].range.tag_id}].push_back(resid[i]);
  }
  std::map<std::pair<uint16_t, uint8_t>, double> median;
  for (auto& [k, v] : per_pair) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    median[k] = v[v.size() / 2];
  }
  std::vector<bool> good(rec.uwb.size(), false);
  for (size_t i = 0; i < resid.size(); ++i) {
    if (std::isnan(resid[i])) continue;
    good[i] = std::fabs(resid[i] - median[{rec.uwb[i].range.anchor_id, rec.uwb[i].range.tag_id}]) < 1.0;
  }
  return good;
}

TEST(ValidatorFalseReject, NoRuleRejectsAGoodFrameOfSimulatedRecordings) {
  // 3-tag trolley, 1 cm resolution at 100 Hz: many equal consecutive values.
  const testing::TrolleyRecording trolley = testing::make_trolley(31);
  const std::vector<UwbRange> tr = ranges_of(trolley.rec);
  const std::vector<bool> all_good(tr.size(), true);
  const RuleStats st_trolley = validate_uwb(trolley.rec.site, tr, all_good);
  const uint64_t old_trolley = old_repeat_rule_drops(tr, all_good);
  print_row("sim trolley 1cm (seed 31)", "uwb", st_trolley, old_trolley);
  EXPECT_EQ(st_trolley.false_total(), 0U);
  // The data must exercise repeated values (12.5 Hz per pair here: ~5 %; the
  // issue's 100 Hz-per-pair trolley repeats 14-15 %).
  EXPECT_GT(old_trolley * 100, st_trolley.good * 2) << "too few repeated values to test the duplicate rule";

  for (const char* preset : {"parking_los", "parking_nlos", "indoor3d"}) {
    SCOPED_TRACE(preset);
    sim::SimOptions opt;
    opt.seed = 32;
    sim::SimOutput out;
    std::string err;
    ASSERT_TRUE(ok(sim::simulate(preset, opt, out, &err))) << err;
    const std::vector<UwbRange> r = ranges_of(out.rec);
    std::vector<bool> good(r.size());
    for (size_t i = 0; i < r.size(); ++i) good[i] = out.range_truth[i].cause != sim::RangeCause::kOutlier;
    const RuleStats su = validate_uwb(out.rec.site, r, good);
    const RuleStats si = validate_imu(out.rec.site, out.rec.imu);
    const std::string name = std::string("sim ") + preset + " (seed 32)";
    print_row(name.c_str(), "uwb", su, old_repeat_rule_drops(r, good));
    print_row(name.c_str(), "imu", si, UINT64_MAX);
    EXPECT_EQ(su.false_total(), 0U);
    EXPECT_EQ(si.false_total(), 0U);
    EXPECT_GT(si.frames, 10000U);
  }
}

TEST(ValidatorFalseReject, NoRuleRejectsAGoodFrameOfTheRealRecordings) {
  const std::string root = UWBNAV_DATA_DIR;
  ASSERT_TRUE(std::filesystem::is_directory(root + "/hanyang")) << root << ": the shipped real recordings are required";
  size_t seen = 0;
  for (const char* name : {"hanyang/hanyang_los_trajA_case1", "hanyang/hanyang_los_trajA_case2",
                           "hanyang/hanyang_nlos_trajA_case1", "hanyang/hanyang_nlos_trajA_case2",
                           "miluv/miluv_3drone_ifo001"}) {
    SCOPED_TRACE(name);
    dataset::Recording rec;
    dataset::ReadReport rep;
    ASSERT_EQ(dataset::read_recording(root + "/" + name, rec, rep), Status::kOk) << rep.error;
    ++seen;
    const std::vector<UwbRange> r = ranges_of(rec);
    const std::vector<bool> good = good_by_truth(rec);
    const RuleStats su = validate_uwb(rec.site, r, good);
    const uint64_t old = old_repeat_rule_drops(r, good);
    print_row(name, "uwb", su, old);
    EXPECT_EQ(su.false_total(), 0U);
    EXPECT_GT(su.good * 10, su.frames * 9);  // the truth test itself keeps >= 90 % as good
    if (!rec.imu.empty()) {
      const RuleStats si = validate_imu(rec.site, rec.imu);
      print_row(name, "imu", si, UINT64_MAX);
      EXPECT_EQ(si.false_total(), 0U);
    }
    if (std::string(name).find("hanyang") != std::string::npos) {
      // The hanyang repeats (~7 % equal consecutive values of a pair) are new
      // measurements: never the same timestamp, different channel diagnostics.
      EXPECT_GT(old * 100, su.good * 5);
      EXPECT_EQ(su.rejected[static_cast<size_t>(RejectReason::kDuplicate)], 0U);
    }
  }
  EXPECT_EQ(seen, 5U);
}

TEST(ValidatorDuplicate, ReReportedFramesAreRejectedAndTheOriginalsKept) {
  const testing::TrolleyRecording trolley = testing::make_trolley(33, 20.0);
  std::vector<UwbRange> r;
  std::vector<bool> good;
  size_t injected = 0;
  for (size_t i = 0; i < trolley.rec.uwb.size(); ++i) {
    r.push_back(trolley.rec.uwb[i].range);
    good.push_back(true);
    if (i % 10 == 0) {
      r.push_back(trolley.rec.uwb[i].range);  // the radio reports the same exchange again
      good.push_back(false);
      ++injected;
    }
    if (i % 25 == 0) {
      UwbRange conflicting = trolley.rec.uwb[i].range;  // same pair and stamp, another value
      conflicting.range_m += 0.37F;
      r.push_back(conflicting);
      good.push_back(false);
      ++injected;
    }
  }
  const RuleStats st = validate_uwb(trolley.rec.site, r, good);
  EXPECT_EQ(st.false_total(), 0U);
  EXPECT_EQ(st.rejected[static_cast<size_t>(RejectReason::kDuplicate)], injected);
}

}  // namespace
}  // namespace uwbnav
