// CanPublisher: per-message periods on the 10 ms tick, alive counters, what
// the vehicle decodes, and counted (never blocking, never retried) drops.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "firmware/can/e2e.hpp"
#include "firmware/can/publisher.hpp"
#include "firmware/can/sensor_decoder.hpp"
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

TEST(CanDiag, InputRejectsCountEverySourceIncludingGnssAndNeighbours) {
  AppStats stats;
  stats.imu.rejected[0] = 1;
  stats.uwb.rejected[1] = 2;
  stats.can_rx.rejected[0] = 4;
  stats.loop.overruns = 3;
  uint32_t expected = 7;
#if UWBNAV_GNSS
  stats.gnss.rejected[2] = 8;
  expected += 8;
#endif
#if UWBNAV_COOP
  stats.neighbours.rejected[1] = 16;
  expected += 16;
#endif
  CanDiag diag;
  diag.set_from_stats(stats);
  EXPECT_EQ(diag.input_rejects, expected);
  EXPECT_EQ(diag.loop_overruns, 3U);
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

#if UWBNAV_COOP
// ---- UWBNAV_Coop*: this vehicle's state for the V2X gateway ------------------

const Vec3f kLever{0.8F, -0.3F, 1.1F};  // tag antenna on the body (FLU) [m]

Params coop_params(float vehicle_n, float period_ms = 100.0F) {
  Params params;
  EXPECT_EQ(params.set(ParamId::kCoopVehicleId, vehicle_n), Status::kOk);
  EXPECT_EQ(params.set(ParamId::kCanCoopPeriodMs, period_ms), Status::kOk);
  return params;
}

// Runs `cycles` 10 ms cycles from t0 with a coop state set each cycle; returns
// the UWBNAV_Coop* frames sent.
std::vector<hal::CanFrame> run_coop(CanPublisher& pub, uint64_t t0, int cycles, NavStatus status = NavStatus::kValid,
                                    bool set_state = true) {
  hal::MemCanBus bus(64, 16, 8192);
  CanDiag diag;
  std::vector<hal::CanFrame> coop;
  for (int i = 0; i < cycles; ++i) {
    const uint64_t t = t0 + static_cast<uint64_t>(i) * kCanTickUs;
    NavOutput o = sample_output(t - 3000);
    o.status = status;
    if (set_state) pub.set_coop_state(coop_state_from(o, kLever, pub.coop_vehicle_id(), i % 2 == 0));
    pub.on_cycle(t, o, diag, bus);
    for (const auto& f : drain(bus)) {
      if (f.id >= coop_id(CoopGroup::kOwn, 0) && f.id < coop_id(CoopGroup::kOwn, kCoopFrames)) coop.push_back(f);
    }
  }
  return coop;
}

TEST(CanPublisherCoop, StateFromTheNavOutputPutsTheTagAtTheRotatedLeverArm) {
  NavOutput o;
  o.t_us = 123456789;
  o.status = NavStatus::kValid;
  o.pos_nav_m = Vec3f{10.0F, 20.0F, 1.0F};
  o.vel_nav_mps = Vec3f{2.0F, -1.0F, 0.1F};
  const float h = 0.5F * 1.5707963F;  // yaw +90 deg: body x is nav y, body y is nav -x
  o.q_nav_body[0] = std::cos(h);
  o.q_nav_body[3] = std::sin(h);
  o.pos_sigma_m = Vec3f{0.05F, 0.08F, 0.2F};
  o.pos_xy_corr = -0.4F;
  const NeighbourState s = coop_state_from(o, Vec3f{1.0F, 0.5F, 1.2F}, 0x8007, true);
  EXPECT_NEAR(s.pos_nav_m.x, 10.0F - 0.5F, 1e-5F);
  EXPECT_NEAR(s.pos_nav_m.y, 20.0F + 1.0F, 1e-5F);
  EXPECT_NEAR(s.pos_nav_m.z, 1.0F + 1.2F, 1e-5F);
  EXPECT_EQ(s.t_us, o.t_us);
  EXPECT_EQ(s.vehicle_id, 0x8007);
  EXPECT_TRUE(s.cooperative);
  EXPECT_EQ(s.vel_nav_mps.x, 2.0F) << "the body origin's velocity (no omega x lever term)";
  EXPECT_EQ(s.vel_nav_mps.z, 0.1F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[0], 0.0025F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[1], -0.4F * 0.05F * 0.08F);
  EXPECT_EQ(s.cov_pos_m2[2], 0.0F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[3], 0.0064F);
  EXPECT_EQ(s.cov_pos_m2[4], 0.0F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[5], 0.04F);
  // Level, heading 0: the lever adds as it is.
  NavOutput level = o;
  level.q_nav_body[0] = 1.0F;
  level.q_nav_body[3] = 0.0F;
  const NeighbourState l = coop_state_from(level, Vec3f{1.0F, 0.5F, 1.2F}, 0x8007, false);
  EXPECT_NEAR(l.pos_nav_m.x, 11.0F, 1e-6F);
  EXPECT_NEAR(l.pos_nav_m.y, 20.5F, 1e-6F);
}

TEST(CanPublisherCoop, SendsTheSixFrameGroupEveryCoopPeriodWithOneCounter) {
  CanPublisher pub;
  pub.configure(coop_params(5));
  EXPECT_EQ(pub.coop_vehicle_id(), 0x8005);
  const auto frames = run_coop(pub, 1000000, 100);  // 1 s
  ASSERT_EQ(frames.size(), 10U * kCoopFrames) << "default can.coop_period_ms = 100";
  for (size_t g = 0; g < 10; ++g) {
    hal::CanFrame group[kCoopFrames];
    for (size_t k = 0; k < kCoopFrames; ++k) {
      group[k] = frames[g * kCoopFrames + k];
      EXPECT_EQ(group[k].id, coop_id(CoopGroup::kOwn, k)) << "parts in order";
      EXPECT_EQ(group[k].t_us, group[0].t_us) << "one cycle";
    }
    const uint64_t t = group[0].t_us;
    EXPECT_EQ(t, 1000000U + g * 100000U);
    NeighbourState d;
    CoopMeta meta;
    ASSERT_EQ(decode_coop(group, CoopGroup::kOwn, t, d, &meta), Status::kOk) << "one alive counter per group";
    EXPECT_EQ(meta.counter, g % 15);
    EXPECT_TRUE(meta.valid);
    EXPECT_FALSE(meta.saturated);
    const NeighbourState want = coop_state_from(sample_output(t - 3000), kLever, 0x8005, true);
    EXPECT_EQ(d.vehicle_id, 0x8005);
    EXPECT_EQ(d.t_us, t - 3000) << "time of validity = the NavOutput's";
    EXPECT_TRUE(d.cooperative) << "set on even cycles, which are the due ones";
    EXPECT_NEAR(d.pos_nav_m.x, want.pos_nav_m.x, 0.0005F + 1e-5F);
    EXPECT_NEAR(d.pos_nav_m.y, want.pos_nav_m.y, 0.0005F + 1e-5F);
    EXPECT_NEAR(d.pos_nav_m.z, want.pos_nav_m.z, 0.0005F + 1e-5F);
    EXPECT_NEAR(d.vel_nav_mps.x, 1.5F, 0.005F);
    EXPECT_NEAR(std::sqrt(d.cov_pos_m2[3]), 0.06F, 0.0005F + 1e-6F);
    EXPECT_NEAR(d.cov_pos_m2[1] / std::sqrt(d.cov_pos_m2[0] * d.cov_pos_m2[3]), -0.3F, 0.5F / 127.0F + 1e-5F);
  }
  EXPECT_EQ(pub.stats().sent, 510U + 60U);
}

TEST(CanPublisherCoop, PeriodFollowsTheParameterRoundedToTheTick) {
  for (const auto& c : {std::pair<float, size_t>{10.0F, 100}, {35.0F, 25}, {250.0F, 4}, {1000.0F, 1}}) {
    CanPublisher pub;
    pub.configure(coop_params(1, c.first));
    EXPECT_EQ(run_coop(pub, 2000000, 100).size(), c.second * kCoopFrames) << c.first << " ms";
  }
}

TEST(CanPublisherCoop, SilentWithoutVehicleIdUsableStatusOrAStateThisCycle) {
  CanPublisher none;
  none.configure(coop_params(0));
  EXPECT_EQ(none.coop_vehicle_id(), kNoVehicleId);
  EXPECT_TRUE(run_coop(none, 1000000, 50).empty()) << "coop.vehicle_id = 0: no broadcast";

  for (const NavStatus st : {NavStatus::kInitialising, NavStatus::kInvalid}) {
    CanPublisher pub;
    pub.configure(coop_params(3));
    EXPECT_TRUE(run_coop(pub, 1000000, 50, st).empty()) << nav_status_name(st);
  }
  CanPublisher degraded;
  degraded.configure(coop_params(3));
  EXPECT_EQ(run_coop(degraded, 1000000, 50, NavStatus::kDegraded).size(), 5U * kCoopFrames);

  CanPublisher stale;
  stale.configure(coop_params(3));
  EXPECT_TRUE(run_coop(stale, 1000000, 50, NavStatus::kValid, false).empty()) << "no state set: nothing sent";
  // A state set once is not resent in later cycles.
  hal::MemCanBus bus(64, 16, 4096);
  CanDiag diag;
  stale.set_coop_state(coop_state_from(sample_output(1500000), kLever, stale.coop_vehicle_id(), false));
  stale.on_cycle(1500000, sample_output(1500000), diag, bus);
  stale.on_cycle(1600000, sample_output(1600000), diag, bus);
  stale.on_cycle(1700000, sample_output(1700000), diag, bus);
  size_t coop = 0;
  for (const auto& f : drain(bus)) coop += f.id >= 0x110 && f.id <= 0x115 ? 1 : 0;
  EXPECT_EQ(coop, kCoopFrames);

  Params off = coop_params(3);
  ASSERT_EQ(off.set(ParamId::kCanTxEnable, 0.0F), Status::kOk);
  CanPublisher quiet;
  quiet.configure(off);
  EXPECT_TRUE(run_coop(quiet, 1000000, 50).empty()) << "can.tx_enable = 0 silences the group too";
}

TEST(CanPublisherCoop, StatusGapRestartsAndTheVehicleIdIsThePublishersOwn) {
  CanPublisher pub;
  pub.configure(coop_params(42));
  hal::MemCanBus bus(64, 16, 8192);
  CanDiag diag;
  size_t coop = 0;
  for (int i = 0; i < 60; ++i) {
    const uint64_t t = 1000000 + static_cast<uint64_t>(i) * kCanTickUs;
    NavOutput o = sample_output(t);
    o.status = i >= 20 && i < 35 ? NavStatus::kInvalid : NavStatus::kValid;
    pub.set_coop_state(coop_state_from(o, kLever, 0x9999, false));  // wrong id: replaced
    pub.on_cycle(t, o, diag, bus);
    for (const auto& f : drain(bus)) {
      if (f.id != 0x110) continue;
      CoopParts p;
      ASSERT_EQ(decode_coop_part(f, CoopGroup::kOwn, 0, p), Status::kOk);
      EXPECT_EQ(p.vehicle_id, 0x8000 + 42);
      EXPECT_TRUE(i < 20 || i >= 35) << "silent while invalid, cycle " << i;
      ++coop;
    }
  }
  EXPECT_EQ(coop, 2U + 3U) << "cycles 0, 10, then 35 (back to valid), 45, 55";
}

// Vehicle A publishes, the gateway relays A's UWBNAV_Coop* group as
// V2X_Neighbour*, vehicle B's decoder delivers A's tag state.
TEST(CanPublisherCoop, StateReachesAnotherVehicleThroughTheGateway) {
  Params params = coop_params(12);
  CanPublisher a;
  a.configure(params);
  hal::MemCanBus a_bus(64, 64, 64);
  hal::MemCanBus gw_a(64, 64, 64);
  hal::MemCanBus::connect(a_bus, gw_a);
  hal::MemCanBus gw_b(64, 64, 64);
  hal::MemCanBus b_bus(64, 64, 64);
  hal::MemCanBus::connect(gw_b, b_bus);
  CanSensorDecoder b;
  b.configure(Params{});
  b.set_hil_enabled(false);
  CanDiag diag;
  uint8_t gw_counter = 0;
  int delivered = 0;
  for (int i = 0; i < 100; ++i) {
    const uint64_t t = 5000000 + static_cast<uint64_t>(i) * kCanTickUs;
    const NavOutput o = sample_output(t - 4000);
    a.set_coop_state(coop_state_from(o, kLever, a.coop_vehicle_id(), false));
    a.on_cycle(t, o, diag, a_bus);
    // Gateway: collects A's group, forwards it as a neighbour state.
    hal::CanFrame f;
    hal::CanFrame group[kCoopFrames];
    size_t n = 0;
    while (gw_a.receive(f) == Status::kOk) {
      if (f.id >= 0x110 && f.id <= 0x115) group[n++] = f;
    }
    if (n == kCoopFrames) {
      NeighbourState relayed;
      CoopMeta meta;
      ASSERT_EQ(decode_coop(group, CoopGroup::kOwn, t, relayed, &meta), Status::kOk);
      hal::CanFrame out[kCoopFrames];
      EXPECT_FALSE(encode_coop(relayed, CoopGroup::kNeighbour, gw_counter, out, meta.valid));
      gw_counter = next_alive_counter(gw_counter);
      for (const auto& g : out) ASSERT_EQ(gw_b.send(g), Status::kOk);
    }
    // Vehicle B, 5 ms later.
    while (b_bus.receive(f) == Status::kOk) {
      CanSensorSample s;
      if (b.on_frame(f, t + 5000, s) != Status::kOk) continue;
      ASSERT_EQ(s.kind, SensorKind::kNeighbour);
      const NeighbourState want = coop_state_from(o, kLever, 0x800C, false);
      EXPECT_EQ(s.neighbour.vehicle_id, 0x800C);
      EXPECT_EQ(s.neighbour.t_us, t - 4000);
      EXPECT_EQ(s.neighbour.rx_t_us, t + 5000);
      // Quantised twice with the same steps: the second pass is exact.
      EXPECT_NEAR(s.neighbour.pos_nav_m.x, want.pos_nav_m.x, 0.0005F + 1e-5F);
      EXPECT_NEAR(s.neighbour.pos_nav_m.y, want.pos_nav_m.y, 0.0005F + 1e-5F);
      EXPECT_NEAR(s.neighbour.pos_nav_m.z, want.pos_nav_m.z, 0.0005F + 1e-5F);
      for (int k : {0, 3, 5}) {
        EXPECT_NEAR(std::sqrt(s.neighbour.cov_pos_m2[k]), std::sqrt(want.cov_pos_m2[k]), 0.0005F + 1e-6F) << k;
      }
      EXPECT_EQ(s.neighbour.cov_pos_m2[2], 0.0F);
      ++delivered;
    }
  }
  EXPECT_EQ(delivered, 10);
  EXPECT_EQ(b.stats().neighbour_states, 10U);
}
#endif  // UWBNAV_COOP

}  // namespace
}  // namespace uwbnav::can
