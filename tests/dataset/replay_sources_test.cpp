// Host replay sources hand out recorded samples in order, only when due, each
// once; the lockstep and real-time clocks keep their sleep contracts.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <vector>

#include "hal/host/lockstep_clock.hpp"
#include "hal/host/realtime_clock.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::hal {
namespace {

dataset::Recording make_recording() {
  dataset::Recording rec;
  for (uint64_t t : {0ULL, 4000ULL, 10000ULL, 10000ULL, 15000ULL, 30000ULL}) {
    ImuSample s;
    s.t_us = t;
    s.accel_body_mps2.z = static_cast<float>(t);
    rec.imu.push_back(s);
  }
  for (uint64_t t : {2000ULL, 10000ULL, 10000ULL, 25000ULL}) {
    dataset::UwbRow r;
    r.range.t_us = t;
    r.range.anchor_id = static_cast<uint16_t>(t / 1000U);
    r.range.range_m = 1.5F;
    r.range.fp_power_dbm = -80.0F;
    r.nlos_label = 1;
    rec.uwb.push_back(r);
  }
  return rec;
}

TEST(ReplaySources, HandOutEverySampleOnceInOrderAndOnlyWhenDue) {
  const dataset::Recording rec = make_recording();
  ReplaySources src(rec);
  std::vector<uint64_t> imu_t;
  std::vector<uint64_t> uwb_t;
  for (uint64_t now = 0; now <= 40000; now += 10000) {
    ImuSample s;
    while (src.imu.poll(now, s) == Status::kOk) {
      EXPECT_LE(s.t_us, now);
      EXPECT_EQ(s.accel_body_mps2.z, static_cast<float>(s.t_us));
      imu_t.push_back(s.t_us);
    }
    UwbRange r;
    while (src.uwb.poll(now, r) == Status::kOk) {
      EXPECT_LE(r.t_us, now);
      uwb_t.push_back(r.t_us);
    }
    if (now == 10000) {
      EXPECT_EQ(imu_t.size(), 4U) << "ties at the deadline are due";
      EXPECT_EQ(uwb_t.size(), 3U);
      EXPECT_FALSE(src.imu.finished());
    }
  }
  EXPECT_EQ(imu_t, (std::vector<uint64_t>{0, 4000, 10000, 10000, 15000, 30000}));
  EXPECT_EQ(uwb_t, (std::vector<uint64_t>{2000, 10000, 10000, 25000}));
  EXPECT_TRUE(src.imu.finished());
  EXPECT_TRUE(src.uwb.finished());
  ImuSample s;
  EXPECT_EQ(src.imu.poll(UINT64_MAX, s), Status::kEmpty);
}

TEST(ReplaySources, NothingIsDueBeforeTheFirstSample) {
  const dataset::Recording rec = make_recording();
  ReplayUwbSource uwb(rec);
  UwbRange r;
  EXPECT_EQ(uwb.poll(1999, r), Status::kEmpty);
  EXPECT_EQ(uwb.delivered(), 0U);
  EXPECT_EQ(uwb.next_t_us(), 2000U);
  EXPECT_EQ(uwb.poll(2000, r), Status::kOk);
}

TEST(ReplaySources, UwbSourceCopiesTheRangeFieldsOfTheRow) {
  const dataset::Recording rec = make_recording();
  ReplayUwbSource uwb(rec.uwb);
  UwbRange r;
  ASSERT_EQ(uwb.poll(2000, r), Status::kOk);
  EXPECT_EQ(r.anchor_id, 2);
  EXPECT_EQ(r.range_m, 1.5F);
  EXPECT_EQ(r.fp_power_dbm, -80.0F);

  const std::vector<UwbRange> bare{rec.uwb[0].range, rec.uwb[1].range};
  ReplayUwbSource from_ranges(bare);
  EXPECT_EQ(from_ranges.size(), 2U);
  ASSERT_EQ(from_ranges.poll(10000, r), Status::kOk);
  ASSERT_EQ(from_ranges.poll(10000, r), Status::kOk);
  EXPECT_TRUE(from_ranges.finished());
}

TEST(ReplaySources, EmptyRecordingIsFinishedAtOnce) {
  const dataset::Recording rec;
  ReplaySources src(rec);
  EXPECT_TRUE(src.imu.finished());
  EXPECT_TRUE(src.uwb.finished());
  ImuSample s;
  EXPECT_EQ(src.imu.poll(1000, s), Status::kEmpty);
}

NeighbourState neighbour_state(uint16_t id, uint64_t t_us, uint64_t rx_t_us) {
  NeighbourState n;
  n.vehicle_id = id;
  n.t_us = t_us;
  n.rx_t_us = rx_t_us;
  n.pos_nav_m = Vec3f{static_cast<float>(t_us) * 1e-3F, 1.0F, 1.2F};
  return n;
}

TEST(ReplayNeighbourSource, HandsOutStatesOnceInArrivalOrderOnlyWhenTheyHaveArrived) {
  dataset::Recording rec = make_recording();
  // Arrival order, as the reader stores them; the second arrives before its validity's successor.
  rec.neighbours = {neighbour_state(kFirstVehicleId, 0, 30000), neighbour_state(kFirstVehicleId + 1, 10000, 30000),
                    neighbour_state(kFirstVehicleId, 20000, 45000), neighbour_state(kFirstVehicleId + 1, 50000, 90000)};
  ReplaySources src(rec);
  ASSERT_EQ(src.neighbours_or_null(rec), &src.neighbours);
  EXPECT_EQ(src.gnss_or_null(rec), nullptr);
  NeighbourState n;
  EXPECT_EQ(src.neighbours.poll(29999, n), Status::kEmpty) << "not due at its time of validity";
  EXPECT_EQ(src.neighbours.next_rx_t_us(), 30000U);
  std::vector<uint64_t> t;
  for (uint64_t now = 30000; now <= 100000; now += 10000) {
    while (src.neighbours.poll(now, n) == Status::kOk) {
      EXPECT_LE(n.rx_t_us, now);
      EXPECT_EQ(n.pos_nav_m.x, static_cast<float>(n.t_us) * 1e-3F);
      t.push_back(n.t_us);
    }
    if (now == 30000) {
      EXPECT_EQ(t.size(), 2U) << "ties at the deadline are due";
    }
  }
  EXPECT_EQ(t, (std::vector<uint64_t>{0, 10000, 20000, 50000}));
  EXPECT_EQ(src.neighbours.delivered(), 4U);
  EXPECT_TRUE(src.neighbours.finished());
  EXPECT_EQ(src.neighbours.poll(UINT64_MAX, n), Status::kEmpty);
}

TEST(ReplayNeighbourSource, RecordingWithoutNeighboursGivesTheBoardNoSource) {
  const dataset::Recording rec = make_recording();
  ReplaySources src(rec);
  EXPECT_EQ(src.neighbours_or_null(rec), nullptr);
  EXPECT_TRUE(src.neighbours.finished());
  const std::vector<NeighbourState> states{neighbour_state(0xFFFE, 5, 7)};
  ReplayNeighbourSource direct(states);
  NeighbourState n;
  EXPECT_EQ(direct.poll(6, n), Status::kEmpty);
  ASSERT_EQ(direct.poll(7, n), Status::kOk);
  EXPECT_EQ(n.vehicle_id, 0xFFFE);
  EXPECT_TRUE(direct.finished());
}

TEST(LockstepClock, SleepAdvancesTimeButNeverBackwards) {
  LockstepClock clock(500);
  EXPECT_EQ(clock.now_us(), 500U);
  clock.sleep_until_us(10000);
  EXPECT_EQ(clock.now_us(), 10000U);
  clock.sleep_until_us(9000);
  EXPECT_EQ(clock.now_us(), 10000U);
  clock.set_us(42);
  EXPECT_EQ(clock.now_us(), 42U);
}

TEST(RealtimeClock, SleepsUntilTheAbsoluteDeadline) {
  RealtimeClock clock(1000000);
  const uint64_t t0 = clock.now_us();
  EXPECT_GE(t0, 1000000U);
  const uint64_t deadline = t0 + 3000;
  clock.sleep_until_us(deadline);
  EXPECT_GE(clock.now_us(), deadline);

  const auto w0 = std::chrono::steady_clock::now();
  clock.sleep_until_us(t0);  // already passed
  clock.sleep_until_us(0);
  const auto waited = std::chrono::steady_clock::now() - w0;
  EXPECT_LT(std::chrono::duration<double>(waited).count(), 0.05);
}

}  // namespace
}  // namespace uwbnav::hal
