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

class ScriptNeighbours final : public hal::NeighbourSource {
 public:
  std::deque<NeighbourState> frames;
  Status poll(uint64_t up_to_us, NeighbourState& out) override {
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

// A vehicle whose GNSS receiver talks CAN (GNSS_Fix* from its gateway): fixes
// from the bus pass the same validation as the board's GnssSource and reach
// the estimator with HIL input off; a no-fix group and a flagged group are
// dropped by the decoder and never counted as fixes.
TEST(FirmwareGnss, FixesFromTheVehicleBusAreValidatedAndReachTheEstimatorWithoutHil) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};  // no GnssSource: CAN only
  App app(board);
  ASSERT_TRUE(ok(app.init()));
  ASSERT_LT(app.params()[ParamId::kCanHilRxEnable], 0.5F);
  GnssCountingObserver obs;
  app.set_observer(&obs);

  auto send = [&](const GnssFix& fix, uint8_t counter, uint64_t rx_us) {
    hal::CanFrame frames[can::kGnssFrames];
    const bool saturated = can::encode_gnss(fix, counter, frames);
    for (hal::CanFrame& f : frames) {
      f.t_us = rx_us;
      can.inject(f);
    }
    return saturated;
  };
  ASSERT_FALSE(send(gnss_fix(100000, 0), 0, 150000));    // good, 50 ms latency at the tick
  app.tick(150000);
  ASSERT_FALSE(send(gnss_fix(120000, 0), 1, 700000));    // latency 0.58 s > gnss.max_latency: out of range
  app.tick(700000);
  GnssFix none = gnss_fix(710000, 0);
  none.fix = GnssFixType::kNone;
  ASSERT_FALSE(send(none, 2, 760000));                   // no fix: dropped by the decoder
  app.tick(760000);
  GnssFix flagged = gnss_fix(770000, 0);
  flagged.pos_sigma_m.x = 50.0F;
  ASSERT_TRUE(send(flagged, 3, 800000));                 // sigma beyond the signal: flagged, dropped
  app.tick(800000);
  ASSERT_FALSE(send(gnss_fix(810000, 0), 4, 850000));    // good
  app.tick(850000);

  const AppStats& st = app.stats();
  EXPECT_EQ(st.gnss.received, 3U);
  EXPECT_EQ(st.gnss.accepted, 2U);
  EXPECT_EQ(st.gnss.rejected[static_cast<size_t>(RejectReason::kOutOfRange)], 1U);
  EXPECT_EQ(app.navigator().diagnostics().gnss_received, 2U);
  EXPECT_EQ(obs.gnss, 2U);
  EXPECT_EQ(app.can_rx_stats().gnss_fixes, 3U);
  EXPECT_EQ(app.can_rx_stats().gnss_no_fix, 1U);
  EXPECT_EQ(app.can_rx_stats().saturated, 1U);
}

#if UWBNAV_COOP
NeighbourState neighbour(uint16_t id, uint64_t t_us, uint64_t latency_us) {
  NeighbourState s;
  s.vehicle_id = id;
  s.t_us = t_us;
  s.rx_t_us = t_us + latency_us;
  s.pos_nav_m = {30.0F, 10.0F, 1.5F};
  const float cov[6] = {0.01F, 0.002F, 0.0F, 0.01F, 0.0F, 0.04F};
  for (size_t k = 0; k < 6; ++k) s.cov_pos_m2[k] = cov[k];
  s.vel_nav_mps = {1.0F, 0.0F, 0.0F};
  return s;
}

TEST(FirmwareValidation, MalformedNeighbourStatesAndVehicleRangesAreRejectedPerReasonAndNeverReachTheEstimator) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  ScriptNeighbours nbs;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};
  board.neighbours = &nbs;

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  constexpr uint16_t kA = 0x8001;
  constexpr uint16_t kB = 0x8002;
  nbs.frames.push_back(neighbour(kA, 100000, 20000));   // good
  NeighbourState s = neighbour(kB, 110000, 20000);
  s.vehicle_id = 7;
  nbs.frames.push_back(s);                              // not a vehicle id (an anchor's)
  s = neighbour(kB, 120000, 20000);
  s.pos_nav_m.z = nan;
  nbs.frames.push_back(s);                              // not finite
  s = neighbour(kB, 130000, 20000);
  s.vel_nav_mps.x = inf;
  nbs.frames.push_back(s);                              // not finite: velocity Inf (NaN means "not reported")
  s = neighbour(kB, 140000, 20000);
  s.cov_pos_m2[1] = 0.02F;
  nbs.frames.push_back(s);                              // out of range: covariance not positive definite
  s = neighbour(kB, 150000, 20000);
  s.cov_pos_m2[5] = 0.0F;
  nbs.frames.push_back(s);                              // out of range: zero vertical variance
  nbs.frames.push_back(neighbour(kB, 100000, 600000));  // out of range: latency 0.6 s > coop.max_age 0.5 s
  nbs.frames.push_back(neighbour(kB, 700000, 20000));   // good
  nbs.frames.push_back(neighbour(kB, 700000, 25000));   // duplicate
  nbs.frames.push_back(neighbour(kB, 650000, 100000));  // out of order for kB
  nbs.frames.push_back(neighbour(kA, 650000, 100000));  // good: in order for kA

  // Ranges to the vehicles' tags: checked like ranges to anchors, duplicates per vehicle and tag.
  UwbRange r;
  r.t_us = 800000;
  r.anchor_id = kA;
  r.range_m = 12.0F;
  uwb.frames.push_back(r);                              // good
  r.anchor_id = kB;
  uwb.frames.push_back(r);                              // good: same time, another vehicle
  uwb.frames.push_back(r);                              // duplicate
  r.t_us = 810000;
  r.tag_id = 5;
  uwb.frames.push_back(r);                              // unknown tag
  r.tag_id = 0;
  r.range_m = nan;
  uwb.frames.push_back(r);                              // not finite

  App app(board);
  ASSERT_TRUE(ok(app.init()));
  for (uint64_t t = 10000; t <= 900000; t += 10000) app.tick(t);
  // A state that arrived 0.79 s before the loop drains it (in.stale_us 0.2 s): stale.
  nbs.frames.push_back(neighbour(kA, 1000000, 10000));
  app.tick(1800000);

  const AppStats& st = app.stats();
  auto rej = [&](RejectReason reason) { return st.neighbours.rejected[static_cast<size_t>(reason)]; };
  EXPECT_EQ(st.neighbours.received, 12U);
  EXPECT_EQ(rej(RejectReason::kUnknownAnchor), 1U);
  EXPECT_EQ(rej(RejectReason::kNotFinite), 2U);
  EXPECT_EQ(rej(RejectReason::kOutOfRange), 3U);
  EXPECT_EQ(rej(RejectReason::kDuplicate), 1U);
  EXPECT_EQ(rej(RejectReason::kOutOfOrder), 1U);
  EXPECT_EQ(rej(RejectReason::kStale), 1U);
  EXPECT_EQ(st.neighbours.accepted, 3U);
  EXPECT_EQ(st.neighbours.accepted + st.neighbours.rejected_total(), st.neighbours.received);
  EXPECT_EQ(app.navigator().diagnostics().neighbour_states, 3U);
  auto uwb_rej = [&](RejectReason reason) { return st.uwb.rejected[static_cast<size_t>(reason)]; };
  EXPECT_EQ(st.uwb.received, 5U);
  EXPECT_EQ(st.uwb.accepted, 2U);
  EXPECT_EQ(uwb_rej(RejectReason::kDuplicate), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kUnknownTag), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kNotFinite), 1U);
  EXPECT_EQ(uwb_rej(RejectReason::kUnknownAnchor), 0U);  // vehicle ids are not unknown anchors
  EXPECT_EQ(app.navigator().diagnostics().neighbour_ranges, 2U);
}

// Neighbour states come over the vehicle bus (V2X_Neighbour*, from the V2X
// gateway) on ECUs without a HIL rig: the App drains the bus for them even with
// can.hil_rx_enable = 0, and the HIL sensor groups stay ignored.
TEST(FirmwareCoop, NeighbourStatesFromTheVehicleBusReachTheEstimatorWithoutHilAndHilSensorsDoNot) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};
  App app(board);
  ASSERT_TRUE(ok(app.init()));
  ASSERT_LT(app.params()[ParamId::kCanHilRxEnable], 0.5F);

  hal::CanFrame frames[can::kCoopFrames];
  ASSERT_FALSE(can::encode_coop(neighbour(0x8003, 100000, 0), can::CoopGroup::kNeighbour, 0, frames));
  for (hal::CanFrame& f : frames) {
    f.t_us = 105000;
    can.inject(f);
  }
  // A HIL IMU frame on the same bus: not a sensor on this ECU.
  hal::CanFrame hil;
  hil.id = can::id_of(can::MsgId::kHilImuAccel);
  hil.len = 8;
  can.inject(hil);
  app.tick(110000);
  app.tick(120000);

  EXPECT_EQ(app.stats().neighbours.received, 1U);
  EXPECT_EQ(app.stats().neighbours.accepted, 1U);
  EXPECT_EQ(app.navigator().diagnostics().neighbour_states, 1U);
  EXPECT_EQ(app.stats().can_rx.received, 0U) << "HIL sensor frames are not accepted with HIL off";
}

// With coop.vehicle_id set, the App broadcasts its own state (UWBNAV_Coop*) at
// its tag antenna once it has a position; without one it stays silent.
TEST(FirmwareCoop, OwnStateIsBroadcastAtTheTagOnceThePositionIsValidAndNeverBefore) {
  const SiteConfig site = square_site();
  ScriptImu imu;
  ScriptUwb uwb;
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};
  App app(board);
  ASSERT_TRUE(ok(app.init()));
  ASSERT_TRUE(ok(app.set_param(ParamId::kCoopVehicleId, 4.0F)));

  // At rest with the body origin at (8, 6, 0): the tag (lever 0, 0, 1) is at (8, 6, 1).
  const float tag[3] = {8.0F, 6.0F, 1.0F};
  const float anchors[4][3] = {{0, 0, 2}, {20, 0, 2}, {20, 20, 2}, {0, 20, 2}};
  constexpr uint64_t kEnd = 20000000;
  for (uint64_t t = 5000; t <= kEnd; t += 5000) imu.frames.push_back(rest_imu(t));
  for (uint64_t t = 50000; t <= kEnd; t += 50000) {
    const size_t a = (t / 50000) % 4;
    const float dx = anchors[a][0] - tag[0];
    const float dy = anchors[a][1] - tag[1];
    const float dz = anchors[a][2] - tag[2];
    uwb.frames.push_back(range(t, static_cast<uint16_t>(a + 1), std::sqrt(dx * dx + dy * dy + dz * dz)));
  }
  auto sent_coop = [&](std::vector<hal::CanFrame>& out) {
    hal::CanFrame f;
    while (ok(can.receive_sent(f))) {
      if (f.id >= can::coop_id(can::CoopGroup::kOwn, 0) && f.id < can::coop_id(can::CoopGroup::kOwn, can::kCoopFrames)) {
        out.push_back(f);
      }
    }
  };
  std::vector<hal::CanFrame> before;
  app.tick(10000);
  sent_coop(before);
  EXPECT_TRUE(before.empty()) << "no position yet: no state to offer the neighbours";

  std::vector<hal::CanFrame> coop;
  for (uint64_t t = 20000; t <= kEnd; t += 10000) {
    app.tick(t);
    sent_coop(coop);
  }
  ASSERT_GE(coop.size(), can::kCoopFrames * 10U);
  ASSERT_EQ(coop.size() % can::kCoopFrames, 0U);
  hal::CanFrame group[can::kCoopFrames];
  for (size_t k = 0; k < can::kCoopFrames; ++k) group[k] = coop[coop.size() - can::kCoopFrames + k];
  NeighbourState d;
  ASSERT_EQ(can::decode_coop(group, can::CoopGroup::kOwn, kEnd, d), Status::kOk);
  EXPECT_EQ(d.vehicle_id, 0x8004);
  EXPECT_NEAR(d.pos_nav_m.x, tag[0], 0.1F);
  EXPECT_NEAR(d.pos_nav_m.y, tag[1], 0.1F);
  EXPECT_NEAR(d.pos_nav_m.z, tag[2], 0.3F);
  EXPECT_FALSE(d.cooperative) << "no neighbour ranges were fused";
}
#endif

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
