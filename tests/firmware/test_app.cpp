// Firmware App tests: input validation per reason, no heap after start-up,
// lockstep determinism, parameter blob.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <vector>

#include "alloc_counter.hpp"
#include "firmware/app.hpp"
#include "firmware/param_blob.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/eval/replay.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

// Hands out a fixed script of frames, including malformed ones.
template <typename T>
class ScriptSource {
 public:
  std::deque<T> frames;
  Status pop(uint64_t up_to_us, T& out) {
    if (frames.empty() || frames.front().t_us > up_to_us) return Status::kEmpty;
    out = frames.front();
    frames.pop_front();
    return Status::kOk;
  }
};
class ScriptImu final : public hal::ImuSource, public ScriptSource<ImuSample> {
 public:
  Status poll(uint64_t up_to_us, ImuSample& out) override { return pop(up_to_us, out); }
  bool finished() const override { return frames.empty(); }
};
class ScriptUwb final : public hal::UwbSource, public ScriptSource<UwbRange> {
 public:
  Status poll(uint64_t up_to_us, UwbRange& out) override { return pop(up_to_us, out); }
  bool finished() const override { return frames.empty(); }
};

// GNSS fixes in arrival order (rx_t_us is what becomes due).
class ScriptGnss final : public hal::GnssSource {
 public:
  std::deque<GnssFix> frames;
  Status poll(uint64_t up_to_us, GnssFix& out) override {
    if (frames.empty() || frames.front().rx_t_us > up_to_us) return Status::kEmpty;
    out = frames.front();
    frames.pop_front();
    return Status::kOk;
  }
  bool finished() const override { return frames.empty(); }
};

SiteConfig square_site() {
  SiteConfig s;
  EXPECT_TRUE(ok(s.add_anchor(1, {0, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(2, {20, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(3, {20, 20, 2})));
  EXPECT_TRUE(ok(s.add_anchor(4, {0, 20, 2})));
  EXPECT_TRUE(ok(s.add_tag(0, {0, 0, 1})));
  return s;
}

ImuSample rest_imu(uint64_t t_us) {
  ImuSample s;
  s.t_us = t_us;
  s.accel_body_mps2 = {0.0F, 0.0F, 9.80665F};
  return s;
}

UwbRange range(uint64_t t_us, uint16_t anchor, float r_m) {
  UwbRange r;
  r.t_us = t_us;
  r.anchor_id = anchor;
  r.range_m = r_m;
  return r;
}

class CountingObserver final : public AppObserver {
 public:
  uint64_t ranges = 0;
  uint64_t outputs = 0;
  bool any_nan = false;  // an estimate (mode not none) with a non-finite number
  void on_range(const RangeReport&) override { ++ranges; }
  void on_output(const NavOutput& o) override {
    ++outputs;
    // Without an estimate the position is NaN on purpose (never publish a position that is not one).
    if (o.mode == NavMode::kNone) return;
    any_nan |= !std::isfinite(o.pos_nav_m.x) || !std::isfinite(o.pos_nav_m.y) || !std::isfinite(o.pos_nav_m.z) ||
               !std::isfinite(o.pos_sigma_m.x);
  }
};

TEST(FirmwareValidation, MalformedFramesAreRejectedPerReasonAndNeverReachTheEstimator) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};

  const float nan = std::numeric_limits<float>::quiet_NaN();
  imu.frames.push_back(rest_imu(1000));
  ImuSample bad = rest_imu(2000);
  bad.gyro_body_radps.x = nan;
  imu.frames.push_back(bad);                  // not finite
  ImuSample huge = rest_imu(3000);
  huge.accel_body_mps2.z = 1e4F;
  imu.frames.push_back(huge);                 // out of range
  imu.frames.push_back(rest_imu(1000));       // duplicate of the first
  imu.frames.push_back(rest_imu(5000));
  imu.frames.push_back(rest_imu(4000));       // out of order

  uwb.frames.push_back(range(1500, 1, 10.0F));
  uwb.frames.push_back(range(1600, 99, 10.0F));      // unknown anchor
  uwb.frames.push_back(range(1700, 2, nan));         // not finite
  uwb.frames.push_back(range(1800, 3, -50.0F));      // out of range
  uwb.frames.push_back(range(1500, 1, 10.5F));       // duplicate stamp of anchor 1
  uwb.frames.push_back(range(1900, 4, 12.0F));
  uwb.frames.push_back(range(1850, 2, 12.0F));       // out of order
  UwbRange tag9 = range(1950, 2, 11.0F);
  tag9.tag_id = 9;
  uwb.frames.push_back(tag9);                        // unknown tag
  uwb.frames.push_back(range(2500, 4, 12.0F));       // same value as anchor 4's last, new stamp: a new measurement

  App app(board);
  ASSERT_TRUE(ok(app.init()));
  CountingObserver obs;
  app.set_observer(&obs);
  app.tick(10000);
  // A frame older than in.stale_us relative to the loop time.
  uwb.frames.push_back(range(20000, 3, 14.0F));
  app.tick(1000000);

  const AppStats& st = app.stats();
  auto imu_rej = [&](RejectReason r) { return st.imu.rejected[static_cast<size_t>(r)]; };
  auto uwb_rej = [&](RejectReason r) { return st.uwb.rejected[static_cast<size_t>(r)]; };
  EXPECT_EQ(st.imu.received, 6U);
  EXPECT_EQ(st.imu.accepted, 2U);
  EXPECT_EQ(imu_rej(RejectReason::kNotFinite), 1U);
  EXPECT_EQ(imu_rej(RejectReason::kOutOfRange), 1U);
  EXPECT_EQ(imu_rej(RejectReason::kDuplicate), 1U);
  EXPECT_EQ(imu_rej(RejectReason::kOutOfOrder), 1U);
  EXPECT_EQ(st.uwb.received, 10U);
  EXPECT_EQ(st.uwb.accepted, 3U);
  EXPECT_EQ(uwb_rej(RejectReason::kUnknownAnchor), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kUnknownTag), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kNotFinite), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kOutOfRange), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kDuplicate), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kOutOfOrder), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kStale), 1U);
  // Only accepted frames reached the estimator.
  EXPECT_EQ(app.navigator().diagnostics().imu_samples, 2U);
  EXPECT_EQ(app.navigator().diagnostics().ranges_received, 3U);
  EXPECT_EQ(obs.ranges, 3U);
  EXPECT_FALSE(obs.any_nan);
}

GnssFix gnss_fix(uint64_t t_us, uint64_t latency_us) {
  GnssFix f;
  f.t_us = t_us;
  f.rx_t_us = t_us + latency_us;
  f.pos_nav_m = {5.0F, 5.0F, 1.5F};
  f.pos_sigma_m = {0.5F, 0.5F, 1.0F};
  f.fix = GnssFixType::kDgnss;
  f.num_sv = 10;
  return f;
}

class GnssCountingObserver final : public AppObserver {
 public:
  uint64_t gnss = 0;
  void on_range(const RangeReport&) override {}
  void on_output(const NavOutput&) override {}
  void on_gnss(const GnssReport&) override { ++gnss; }
};

TEST(FirmwareValidation, MalformedGnssFixesAreRejectedPerReasonAndNeverReachTheEstimator) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  ScriptGnss gnss;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site, &gnss};

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  // In arrival order: the source hands out a fix once its arrival is due.
  gnss.frames.push_back(gnss_fix(100000, 80000));   // good
  GnssFix f = gnss_fix(200000, 80000);
  f.pos_nav_m.y = nan;
  gnss.frames.push_back(f);                         // not finite
  f = gnss_fix(300000, 80000);
  f.vel_nav_mps = {1.0F, inf, 0.0F};
  gnss.frames.push_back(f);                         // not finite: velocity Inf (NaN means "not reported")
  f = gnss_fix(400000, 80000);
  f.pos_sigma_m.x = 0.0F;
  gnss.frames.push_back(f);                         // out of range: a zero claimed sigma
  f = gnss_fix(500000, 0);
  f.rx_t_us = 490000;
  gnss.frames.push_back(f);                         // out of range: arrived before its time of validity
  gnss.frames.push_back(gnss_fix(310000, 600000));  // out of range: latency 0.6 s > gnss.max_latency 0.5 s
  gnss.frames.push_back(gnss_fix(1000000, 40000));  // good
  gnss.frames.push_back(gnss_fix(1000000, 45000));  // duplicate time of validity
  gnss.frames.push_back(gnss_fix(900000, 150000));  // out of order: validity before the last accepted

  App app(board);
  ASSERT_TRUE(ok(app.init()));
  GnssCountingObserver obs;
  app.set_observer(&obs);
  for (uint64_t t = 10000; t <= 1100000; t += 10000) app.tick(t);
  // A fix that arrived 0.79 s before the loop drains it (in.stale_us 0.2 s): stale.
  gnss.frames.push_back(gnss_fix(1200000, 10000));
  app.tick(2000000);

  const AppStats& st = app.stats();
  auto rej = [&](RejectReason r) { return st.gnss.rejected[static_cast<size_t>(r)]; };
  EXPECT_EQ(st.gnss.received, 10U);
  EXPECT_EQ(rej(RejectReason::kNotFinite), 2U);
  EXPECT_EQ(rej(RejectReason::kOutOfRange), 3U);
  EXPECT_EQ(rej(RejectReason::kDuplicate), 1U);
  EXPECT_EQ(rej(RejectReason::kOutOfOrder), 1U);
  EXPECT_EQ(rej(RejectReason::kStale), 1U);
  EXPECT_EQ(st.gnss.accepted, 2U);
  EXPECT_EQ(st.gnss.accepted + st.gnss.rejected_total(), st.gnss.received);
  // Only accepted fixes reached the estimator.
  EXPECT_EQ(app.navigator().diagnostics().gnss_received, 2U);
  EXPECT_EQ(obs.gnss, 2U);
}

TEST(FirmwareHeap, NoHeapAllocationAfterStartUpDuringLongLockstepReplay) {
  if (!alloc_counter::hooks_active()) GTEST_SKIP() << "allocation hooks disabled under AddressSanitizer";
  dataset::Recording rec;
  std::string err;
  ASSERT_TRUE(ok(sim::simulate(sim::preset_names().front(), 11, rec, &err))) << err;
  ASSERT_GT(rec.imu.size(), 10000U);

  hal::ReplaySources sources(rec);
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{sources.imu, sources.uwb, can, serial, clock, store, rec.site};
  App app(board);
  ASSERT_TRUE(ok(app.init()));
  CountingObserver obs;
  app.set_observer(&obs);

  alloc_counter::arm();
  uint64_t t = (rec.imu.front().t_us / kCyclePeriodUs + 1) * kCyclePeriodUs;
  uint64_t cycles = 0;
  while (!(sources.imu.finished() && sources.uwb.finished())) {
    clock.sleep_until_us(t);
    app.tick(t);
    hal::CanFrame f;
    while (ok(can.receive_sent(f))) {
    }
    t += kCyclePeriodUs;
    ++cycles;
  }
  const unsigned long allocations = alloc_counter::disarm();
  EXPECT_EQ(allocations, 0UL) << "heap allocations in " << cycles << " firmware cycles";
  EXPECT_GT(cycles, 10000U);
  EXPECT_GT(obs.ranges, 1000U);
  EXPECT_FALSE(obs.any_nan);
}

TEST(FirmwareLockstep, ReplayIsBitForBitDeterministicAcrossRuns) {
  dataset::Recording rec;
  std::string err;
  ASSERT_TRUE(ok(sim::simulate(sim::preset_names().front(), 5, rec, &err))) << err;
  eval::ReplayOptions opt;
  eval::ReplayResult a, b;
  ASSERT_TRUE(ok(eval::run_replay(rec, opt, a, &err))) << err;
  ASSERT_TRUE(ok(eval::run_replay(rec, opt, b, &err))) << err;
  ASSERT_EQ(a.estimates.size(), b.estimates.size());
  ASSERT_GT(a.estimates.size(), 1000U);
  EXPECT_EQ(0, std::memcmp(a.estimates.data(), b.estimates.data(), a.estimates.size() * sizeof(a.estimates[0])));
  ASSERT_EQ(a.ranges.size(), b.ranges.size());
  for (size_t i = 0; i < a.ranges.size(); ++i) {
    EXPECT_EQ(0, std::memcmp(&a.ranges[i].innovation_m, &b.ranges[i].innovation_m, sizeof(float))) << i;
    EXPECT_EQ(a.ranges[i].used, b.ranges[i].used) << i;
  }
}

TEST(FirmwareParams, BlobRoundTripsAndCorruptBlobsLeaveParamsUntouched) {
  Params p;
  ASSERT_TRUE(ok(p.set(ParamId::kUwbSigma, 0.25F)));
  uint8_t blob[kParamBlobMaxBytes];
  const size_t n = param_blob_write(p, blob, sizeof blob);
  ASSERT_GT(n, 0U);
  Params q;
  ParamBlobReport rep;
  ASSERT_TRUE(ok(param_blob_read(blob, n, q, &rep)));
  EXPECT_EQ(q[ParamId::kUwbSigma], 0.25F);
  EXPECT_EQ(rep.applied, kNumParams);
  blob[10] ^= 0x40;  // corrupt a value: CRC must catch it
  Params r;
  EXPECT_FALSE(ok(param_blob_read(blob, n, r, nullptr)));
  EXPECT_EQ(r[ParamId::kUwbSigma], kParamDefs[static_cast<size_t>(ParamId::kUwbSigma)].def);
  EXPECT_FALSE(ok(param_blob_read(blob, n - 1, r, nullptr)));
  EXPECT_EQ(param_blob_write(p, blob, 8), 0U);
}

TEST(FirmwareParams, OutOfRangeValuesAreRefusedAndKeepTheOldValue) {
  Params p;
  const float before = p[ParamId::kUwbSigma];
  EXPECT_EQ(p.set(ParamId::kUwbSigma, 1e6F), Status::kOutOfRange);
  EXPECT_EQ(p.set(ParamId::kUwbSigma, std::numeric_limits<float>::quiet_NaN()), Status::kNotFinite);
  EXPECT_EQ(p.set_by_name("no.such.param", 1.0F), Status::kNotFound);
  EXPECT_EQ(p[ParamId::kUwbSigma], before);
}

}  // namespace
}  // namespace uwbnav
