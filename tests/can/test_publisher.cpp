// CanPublisher: per-message periods on the 10 ms tick, alive counters, what
// the vehicle decodes, and counted (never blocking, never retried) drops.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "firmware/can/e2e.hpp"
#include "firmware/can/publisher.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::can {
namespace {

NavOutput sample_output(uint64_t t_us) {
  NavOutput o;
  o.t_us = t_us;
  o.status = NavStatus::kValid;
  o.pos_nav_m = Vec3f{12.345F, -67.891F, 1.234F};
  o.vel_nav_mps = Vec3f{1.5F, -0.25F, 0.01F};
  o.heading_rad = 0.7F;
  o.heading_sigma_rad = 0.02F;
  // Z-Y-X attitude: yaw 0.7, pitch -0.1, roll 0.05 [rad]
  const double h[3] = {0.5 * 0.7, 0.5 * -0.1, 0.5 * 0.05};
  const double cy = std::cos(h[0]), sy = std::sin(h[0]), cp = std::cos(h[1]), sp = std::sin(h[1]);
  const double cr = std::cos(h[2]), sr = std::sin(h[2]);
  o.q_nav_body[0] = static_cast<float>(cr * cp * cy + sr * sp * sy);
  o.q_nav_body[1] = static_cast<float>(sr * cp * cy - cr * sp * sy);
  o.q_nav_body[2] = static_cast<float>(cr * sp * cy + sr * cp * sy);
  o.q_nav_body[3] = static_cast<float>(cr * cp * sy - sr * sp * cy);
  o.pos_sigma_m = Vec3f{0.05F, 0.06F, 0.2F};
  o.pos_xy_corr = -0.3F;
  o.ranges_used = 4;
  o.ranges_rejected = 1;
  o.resets = 2;
  return o;
}

std::vector<hal::CanFrame> drain(hal::MemCanBus& bus) {
  std::vector<hal::CanFrame> out;
  hal::CanFrame f;
  while (bus.receive_sent(f) == Status::kOk) out.push_back(f);
  return out;
}

TEST(CanPublisher, SendsEachMessageAtItsPeriodOverOneSecond) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(64, 16, 4096);
  CanDiag diag;
  for (uint64_t t = 1000000; t < 2000000; t += kCanTickUs) pub.on_cycle(t, sample_output(t - 3000), diag, bus);
  std::map<uint32_t, int> per_id;
  for (const auto& f : drain(bus)) ++per_id[f.id];
  EXPECT_EQ(per_id[0x100], 100);
  EXPECT_EQ(per_id[0x101], 100);
  EXPECT_EQ(per_id[0x102], 100);
  EXPECT_EQ(per_id[0x103], 100);
  EXPECT_EQ(per_id[0x104], 50);
  EXPECT_EQ(per_id[0x105], 10);
  EXPECT_EQ(per_id[0x106], 50);
  EXPECT_EQ(pub.stats().sent, 510U);
  EXPECT_EQ(pub.stats().dropped, 0U);
}

TEST(CanPublisher, PeriodsFollowParametersAndToleratesLoopJitter) {
  Params params;
  ASSERT_EQ(params.set(ParamId::kCanAccPeriodMs, 100.0F), Status::kOk);
  ASSERT_EQ(params.set(ParamId::kCanDiagPeriodMs, 500.0F), Status::kOk);
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(64, 16, 4096);
  CanDiag diag;
  for (int i = 0; i < 100; ++i) {
    const uint64_t t = 5000000 + static_cast<uint64_t>(i) * kCanTickUs + (i % 2 == 0 ? 0 : 900);  // +-0.9 ms jitter
    pub.on_cycle(t, sample_output(t), diag, bus);
  }
  std::map<uint32_t, int> per_id;
  for (const auto& f : drain(bus)) ++per_id[f.id];
  EXPECT_EQ(per_id[0x101], 100);
  EXPECT_EQ(per_id[0x104], 10);
  EXPECT_EQ(per_id[0x106], 10);
  EXPECT_EQ(per_id[0x105], 2);
}

TEST(CanPublisher, FramesDecodeToTheNavOutputAndShareTheGroupCounter) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(64, 16, 4096);
  CanDiag diag;
  diag.set_anchor_nlos(3, true);
  diag.set_anchor_nlos(5, true);
  diag.set_anchor_nlos(5, false);
  diag.loop_overruns = 7;
  diag.input_rejects = 11;
  diag.resets = 2;
  std::map<uint32_t, int> last_counter;
  for (int i = 0; i < 40; ++i) {
    const uint64_t t = 1000000 + static_cast<uint64_t>(i) * kCanTickUs;
    pub.on_cycle(t, sample_output(t - 2000), diag, bus);
    uint8_t group_counter = 0xFF;
    for (const auto& f : drain(bus)) {
      EXPECT_EQ(f.t_us, t);
      FrameMeta meta;
      const NavOutput o = sample_output(t - 2000);
      if (f.id == 0x100) {
        NavTimeMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_EQ(m.nav_t_us, t - 2000);
        group_counter = meta.counter;
      } else if (f.id == 0x101) {
        PosXYMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_NEAR(m.x_nav_m, o.pos_nav_m.x, 0.0005F);
        EXPECT_NEAR(m.y_nav_m, o.pos_nav_m.y, 0.0005F);
        EXPECT_EQ(m.status, NavStatus::kValid);
        EXPECT_EQ(meta.counter, group_counter);
      } else if (f.id == 0x102) {
        PosZMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_NEAR(m.z_nav_m, o.pos_nav_m.z, 0.0005F);
        EXPECT_EQ(m.ranges_used, 4);
        EXPECT_EQ(m.ranges_rejected, 1);
        EXPECT_EQ(meta.counter, group_counter);
      } else if (f.id == 0x103) {
        VelHdgMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_NEAR(m.heading_rad, 0.7F, 0.0001F);
        EXPECT_NEAR(m.vx_nav_mps, 1.5F, 0.005F);
      } else if (f.id == 0x104) {
        AccuracyMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_NEAR(m.sigma_y_m, 0.06F, 0.0025F);
        EXPECT_NEAR(m.corr_xy, -0.3F, 0.0005F);
      } else if (f.id == 0x106) {
        AttitudeMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_NEAR(m.heading_sigma_rad, 0.02F, 0.0005F);
        EXPECT_NEAR(m.roll_rad, 0.05F, 0.0002F);
        EXPECT_NEAR(m.pitch_rad, -0.1F, 0.0002F);
        EXPECT_FALSE(meta.saturated);
      } else if (f.id == 0x105) {
        DiagMsg m;
        ASSERT_EQ(decode(f, m, &meta), Status::kOk);
        EXPECT_EQ(m.nlos_mask, 1U << 3);
        EXPECT_EQ(m.overruns, 7U);
        EXPECT_EQ(m.input_rejects, 11U);
        EXPECT_EQ(m.resets, 2U);
      }
      auto it = last_counter.find(f.id);
      if (it != last_counter.end()) {
        EXPECT_EQ(meta.counter, (it->second + 1) % 15) << "id " << f.id;
      }
      last_counter[f.id] = meta.counter;
    }
  }
}

TEST(CanPublisher, FullDriverQueueDropsAndCountsWithoutRetryAndCountersStillAdvance) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(2, 16, 4096);  // driver holds 2 frames
  bus.set_auto_flush(false);
  CanDiag diag;
  pub.on_cycle(1000000, sample_output(1000000), diag, bus);
  // 7 frames due (4 position group + accuracy + attitude + diag), 2 accepted.
  EXPECT_EQ(pub.stats().sent, 2U);
  EXPECT_EQ(pub.stats().dropped, 5U);
  EXPECT_EQ(bus.counters().tx_dropped, 5U);
  EXPECT_EQ(bus.flush(), 2U);
  pub.on_cycle(1010000, sample_output(1010000), diag, bus);
  bus.flush();
  const auto frames = drain(bus);
  ASSERT_EQ(frames.size(), 4U);
  // Second cycle's NavTime carries counter 1: the dropped cycle is visible to receivers.
  NavTimeMsg m;
  FrameMeta meta;
  ASSERT_EQ(decode(frames[2], m, &meta), Status::kOk);
  EXPECT_EQ(meta.counter, 1);
}

TEST(CanPublisher, BusOffFailsAreCountedAndSilentWhenDisabled) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus;
  bus.set_state(hal::CanBusState::kBusOff);
  CanDiag diag;
  pub.on_cycle(1000000, sample_output(1000000), diag, bus);
  EXPECT_EQ(pub.stats().failed, 7U);
  EXPECT_EQ(pub.stats().sent, 0U);

  ASSERT_EQ(params.set(ParamId::kCanTxEnable, 0.0F), Status::kOk);
  CanPublisher off;
  off.configure(params);
  hal::MemCanBus quiet;
  off.on_cycle(1000000, sample_output(1000000), diag, quiet);
  hal::CanFrame f;
  EXPECT_EQ(quiet.receive_sent(f), Status::kEmpty);
}

TEST(CanPublisher, SaturatedFramesAreCounted) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus;
  NavOutput o = sample_output(1000000);
  o.pos_nav_m.z = 100.0F;  // beyond +-32.767 m
  CanDiag diag;
  pub.on_cycle(1000000, o, diag, bus);
  EXPECT_EQ(pub.stats().saturated, 1U);
}

TEST(CanPublisher, ClockJumpBackRestartsTheScheduleInsteadOfGoingSilent) {
  Params params;
  CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(64, 16, 4096);
  CanDiag diag;
  pub.on_cycle(50000000, sample_output(0), diag, bus);
  drain(bus);
  pub.on_cycle(1000000, sample_output(0), diag, bus);
  std::map<uint32_t, int> per_id;
  for (const auto& f : drain(bus)) ++per_id[f.id];
  EXPECT_EQ(per_id[0x101], 1);
  EXPECT_EQ(per_id[0x105], 1);
}

}  // namespace
}  // namespace uwbnav::can
