// HIL sensor frames: rig encoder -> firmware decoder round trip, E2E failures
// counted and dropped, multi-frame grouping, 32-bit timestamp reconstruction.
#include <gtest/gtest.h>

#include <cmath>

#include "firmware/can/sensor_decoder.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::can {
namespace {

ImuSample imu_at(uint64_t t_us) {
  ImuSample s;
  s.t_us = t_us;
  s.accel_body_mps2 = Vec3f{0.12F, -0.34F, 9.81F};
  s.gyro_body_radps = Vec3f{0.001F, -0.02F, 0.3F};
  return s;
}

UwbRange range_at(uint64_t t_us) {
  UwbRange r;
  r.t_us = t_us;
  r.anchor_id = 7;
  r.tag_id = 1;
  r.range_m = 23.456F;
  r.rx_power_dbm = -80.5F;
  return r;
}

TEST(CanTimeUnwrap, ReconstructsAcrossThe32BitWrapInBothDirections) {
  const uint64_t wrap = uint64_t{1} << 32;
  EXPECT_EQ(unwrap_time_us(0xFFFFFFF0U, wrap + 10), wrap - 16) << "sample just before the wrap, receiver after";
  EXPECT_EQ(unwrap_time_us(5U, wrap - 10), wrap + 5) << "sample just after the wrap, receiver before";
  EXPECT_EQ(unwrap_time_us(1234U, 5 * wrap + 2000), 5 * wrap + 1234);
  EXPECT_EQ(unwrap_time_us(1000U, 900U), 1000U);
  EXPECT_EQ(unwrap_time_us(0xFFFFFF00U, 100U), 0xFFFFFF00U) << "never negative near time zero";
  // Sample 30 min old against the receiver: still exact (limit is +-35.7 min).
  const uint64_t now = 3 * wrap + 123456;
  const uint64_t t = now - 30ULL * 60 * 1000000;
  EXPECT_EQ(unwrap_time_us(static_cast<uint32_t>(t), now), t);
}

TEST(CanSensorDecoder, ImuAndUwbRoundTripThroughTheRigEncoder) {
  Params params;
  CanSensorEncoder enc;
  CanSensorDecoder dec;
  dec.configure(params);
  const uint64_t base = (uint64_t{1} << 32) * 2;  // exercise the high bits
  for (int i = 0; i < 30; ++i) {
    const uint64_t t = base + 1000000 + static_cast<uint64_t>(i) * 10000;
    hal::CanFrame imu_frames[kImuFrames];
    ASSERT_FALSE(enc.encode_imu(imu_at(t), imu_frames));
    CanSensorSample out;
    EXPECT_EQ(dec.on_frame(imu_frames[0], t + 500, out), Status::kEmpty);
    EXPECT_EQ(dec.on_frame(imu_frames[1], t + 500, out), Status::kEmpty);
    ASSERT_EQ(dec.on_frame(imu_frames[2], t + 500, out), Status::kOk);
    ASSERT_EQ(out.kind, SensorKind::kImu);
    EXPECT_EQ(out.imu.t_us, t);
    EXPECT_NEAR(out.imu.accel_body_mps2.z, 9.81F, 0.0025F + 1e-5F);
    EXPECT_NEAR(out.imu.gyro_body_radps.z, 0.3F, 0.0005F + 1e-6F);

    hal::CanFrame uwb_frames[kUwbFrames];
    ASSERT_FALSE(enc.encode_uwb(range_at(t), uwb_frames));
    EXPECT_EQ(dec.on_frame(uwb_frames[0], t + 700, out), Status::kEmpty);
    ASSERT_EQ(dec.on_frame(uwb_frames[1], t + 700, out), Status::kOk);
    ASSERT_EQ(out.kind, SensorKind::kUwb);
    EXPECT_EQ(out.uwb.t_us, t);
    EXPECT_EQ(out.uwb.anchor_id, 7);
    EXPECT_EQ(out.uwb.tag_id, 1);
    EXPECT_NEAR(out.uwb.range_m, 23.456F, 0.0005F + 1e-5F);
    EXPECT_TRUE(std::isnan(out.uwb.fp_power_dbm));
    EXPECT_NEAR(out.uwb.rx_power_dbm, -80.5F, 1e-4F);
  }
  EXPECT_EQ(dec.stats().imu_samples, 30U);
  EXPECT_EQ(dec.stats().uwb_ranges, 30U);
  EXPECT_EQ(dec.stats().crc_errors + dec.stats().counter_errors + dec.stats().incomplete, 0U);
}

TEST(CanSensorDecoder, BadCrcIsCountedAndTheSampleIsNotDelivered) {
  Params params;
  CanSensorEncoder enc;
  CanSensorDecoder dec;
  dec.configure(params);
  hal::CanFrame f[kImuFrames];
  enc.encode_imu(imu_at(1000), f);
  f[1].data[4] ^= 0x01;
  CanSensorSample out;
  EXPECT_EQ(dec.on_frame(f[0], 1000, out), Status::kEmpty);
  EXPECT_EQ(dec.on_frame(f[1], 1000, out), Status::kRejected);
  EXPECT_EQ(dec.on_frame(f[2], 1000, out), Status::kEmpty) << "group lacks its accel part";
  EXPECT_EQ(dec.stats().crc_errors, 1U);
  // The next sample's parts start a new group: the broken one is counted incomplete.
  enc.encode_imu(imu_at(11000), f);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(dec.on_frame(f[i], 11000, out), Status::kEmpty);
  EXPECT_EQ(dec.on_frame(f[2], 11000, out), Status::kOk);
  EXPECT_EQ(out.imu.t_us, 11000U);
  EXPECT_EQ(dec.stats().incomplete, 1U);
}

TEST(CanSensorDecoder, CounterJumpIsDroppedAndTheStreamResyncs) {
  Params params;
  ASSERT_EQ(params.set(ParamId::kCanE2eMaxDelta, 1.0F), Status::kOk);
  CanSensorEncoder enc;
  CanSensorDecoder dec;
  dec.configure(params);
  hal::CanFrame f[kUwbFrames];
  CanSensorSample out;
  enc.encode_uwb(range_at(1000), f);
  ASSERT_EQ(dec.on_frame(f[0], 1000, out), Status::kEmpty);
  ASSERT_EQ(dec.on_frame(f[1], 1000, out), Status::kOk);
  enc.encode_uwb(range_at(2000), f);  // lost on the bus
  enc.encode_uwb(range_at(3000), f);
  EXPECT_EQ(dec.on_frame(f[0], 3000, out), Status::kRejected);
  EXPECT_EQ(dec.on_frame(f[1], 3000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().counter_errors, 2U);
  enc.encode_uwb(range_at(4000), f);
  EXPECT_EQ(dec.on_frame(f[0], 4000, out), Status::kEmpty);
  ASSERT_EQ(dec.on_frame(f[1], 4000, out), Status::kOk);
  EXPECT_EQ(out.uwb.t_us, 4000U);
  // A replayed (repeated) frame is dropped too.
  EXPECT_EQ(dec.on_frame(f[1], 4000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().counter_errors, 3U);
}

TEST(CanSensorDecoder, LossWithinMaxDeltaIsAcceptedAndCounted) {
  Params params;  // default max delta 2
  CanSensorEncoder enc;
  CanSensorDecoder dec;
  dec.configure(params);
  hal::CanFrame f[kUwbFrames];
  CanSensorSample out;
  enc.encode_uwb(range_at(1000), f);
  ignore_status(dec.on_frame(f[0], 1000, out));
  ignore_status(dec.on_frame(f[1], 1000, out));
  enc.encode_uwb(range_at(2000), f);
  enc.encode_uwb(range_at(3000), f);
  EXPECT_EQ(dec.on_frame(f[0], 3000, out), Status::kEmpty);
  EXPECT_EQ(dec.on_frame(f[1], 3000, out), Status::kOk);
  EXPECT_EQ(dec.stats().frames_lost, 2U);
}

TEST(CanSensorDecoder, SaturatedSamplesAreDroppedAndOtherIdsIgnored) {
  Params params;
  CanSensorEncoder enc;
  CanSensorDecoder dec;
  dec.configure(params);
  ImuSample s = imu_at(5000);
  s.gyro_body_radps.z = 50.0F;  // beyond the 32.767 rad/s field
  hal::CanFrame f[kImuFrames];
  EXPECT_TRUE(enc.encode_imu(s, f));
  CanSensorSample out;
  ignore_status(dec.on_frame(f[0], 5000, out));
  ignore_status(dec.on_frame(f[1], 5000, out));
  EXPECT_EQ(dec.on_frame(f[2], 5000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().saturated, 1U);
  hal::CanFrame other;
  other.id = 0x101;
  other.len = 8;
  EXPECT_EQ(dec.on_frame(other, 5000, out), Status::kNotFound);
  EXPECT_EQ(dec.stats().frames, 3U);
}

#if UWBNAV_COOP
// ---- V2X_Neighbour*: other vehicles' states relayed by the V2X gateway -------

NeighbourState neighbour_at(uint64_t t_us, uint16_t vehicle_id) {
  NeighbourState s;
  s.t_us = t_us;
  s.rx_t_us = t_us;
  s.vehicle_id = vehicle_id;
  s.pos_nav_m = Vec3f{123.456F, -78.9F, 1.25F};
  s.vel_nav_mps = Vec3f{4.5F, -0.5F, kNaNf};
  const float sx = 0.05F, sy = 0.07F, sz = 0.2F, rxy = 0.3F;
  s.cov_pos_m2[0] = sx * sx;
  s.cov_pos_m2[1] = rxy * sx * sy;
  s.cov_pos_m2[2] = 0.0F;
  s.cov_pos_m2[3] = sy * sy;
  s.cov_pos_m2[4] = 0.0F;
  s.cov_pos_m2[5] = sz * sz;
  return s;
}

// Feeds a group's frames; returns the status of the last one.
Status feed(CanSensorDecoder& dec, const hal::CanFrame (&f)[kCoopFrames], uint64_t now_us, CanSensorSample& out,
            int skip = -1) {
  Status last = Status::kEmpty;
  for (size_t k = 0; k < kCoopFrames; ++k) {
    if (static_cast<int>(k) == skip) continue;
    last = dec.on_frame(f[k], now_us, out);
    if (k + 1 < kCoopFrames && last == Status::kOk) ADD_FAILURE() << "state complete before its last part";
  }
  return last;
}

TEST(CanSensorDecoderNeighbour, StatesCrossAMemCanBusAndDecodeWithTheReceiverTime) {
  hal::MemCanBus gateway;
  hal::MemCanBus ecu;
  hal::MemCanBus::connect(gateway, ecu);
  Params params;
  CanSensorDecoder dec;
  dec.configure(params);
  const uint64_t base = (uint64_t{1} << 32) * 3 - 250000;  // the 32-bit time wraps during the run
  uint8_t counter = 0;
  int delivered = 0;
  for (int i = 0; i < 20; ++i) {
    const uint64_t t = base + static_cast<uint64_t>(i) * 50000;
    const uint16_t vehicle = static_cast<uint16_t>(0x8001 + i % 3);  // three vehicles in turn
    hal::CanFrame f[kCoopFrames];
    ASSERT_FALSE(encode_coop(neighbour_at(t, vehicle), CoopGroup::kNeighbour, counter, f));
    counter = next_alive_counter(counter);
    for (auto& fr : f) ASSERT_EQ(gateway.send(fr), Status::kOk);
    const uint64_t now = t + 30000;  // 30 ms of gateway and bus latency
    hal::CanFrame rx;
    size_t parts = 0;
    while (ecu.receive(rx) == Status::kOk) {
      CanSensorSample out;
      const Status st = dec.on_frame(rx, now, out);
      ++parts;
      if (parts < kCoopFrames) {
        EXPECT_EQ(st, Status::kEmpty);
        continue;
      }
      ASSERT_EQ(st, Status::kOk);
      ASSERT_EQ(out.kind, SensorKind::kNeighbour);
      const NeighbourState& n = out.neighbour;
      EXPECT_EQ(n.t_us, t);
      EXPECT_EQ(n.rx_t_us, now);
      EXPECT_EQ(n.vehicle_id, vehicle);
      EXPECT_NEAR(n.pos_nav_m.x, 123.456F, 0.0005F + 1e-5F);
      EXPECT_NEAR(n.pos_nav_m.y, -78.9F, 0.0005F + 1e-5F);
      EXPECT_NEAR(n.pos_nav_m.z, 1.25F, 1e-6F);
      EXPECT_NEAR(n.vel_nav_mps.x, 4.5F, 1e-5F);
      EXPECT_TRUE(std::isnan(n.vel_nav_mps.z));
      EXPECT_NEAR(n.cov_pos_m2[0], 0.0025F, 1e-7F);
      EXPECT_NEAR(n.cov_pos_m2[1], 0.3F * 0.05F * 0.07F, 0.5F / 127.0F * 0.05F * 0.07F);
      EXPECT_NEAR(n.cov_pos_m2[5], 0.04F, 1e-7F);
      EXPECT_FALSE(n.cooperative);
      ++delivered;
    }
    EXPECT_EQ(parts, kCoopFrames);
  }
  EXPECT_EQ(delivered, 20);
  const CanSensorStats& st = dec.stats();
  EXPECT_EQ(st.neighbour_states, 20U);
  EXPECT_EQ(st.frames, 120U);
  EXPECT_EQ(st.crc_errors + st.counter_errors + st.incomplete + st.saturated + st.neighbour_invalid, 0U);
  EXPECT_EQ(st.imu_samples + st.uwb_ranges, 0U);
}

TEST(CanSensorDecoderNeighbour, BadCrcRepeatedCounterAndMissingPartDropTheState) {
  Params params;
  CanSensorDecoder dec;
  dec.configure(params);
  CanSensorSample out;
  hal::CanFrame f[kCoopFrames];
  // Counter 0, part 2 corrupted: rejected, the group never completes.
  encode_coop(neighbour_at(1000000, 0x8001), CoopGroup::kNeighbour, 0, f);
  f[2].data[5] ^= 0x01;
  for (size_t k = 0; k < kCoopFrames; ++k) {
    EXPECT_EQ(dec.on_frame(f[k], 1010000, out), k == 2 ? Status::kRejected : Status::kEmpty) << k;
  }
  EXPECT_EQ(dec.stats().crc_errors, 1U);
  // Counter 1 complete: the partial group 0 is counted incomplete, state 1 delivered.
  encode_coop(neighbour_at(1100000, 0x8001), CoopGroup::kNeighbour, 1, f);
  ASSERT_EQ(feed(dec, f, 1110000, out), Status::kOk);
  EXPECT_EQ(out.neighbour.t_us, 1100000U);
  EXPECT_EQ(dec.stats().incomplete, 1U);
  // The same group again (repeated counter): every frame dropped, nothing delivered.
  for (size_t k = 0; k < kCoopFrames; ++k) EXPECT_EQ(dec.on_frame(f[k], 1120000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().counter_errors, 6U);
  // Counter 2 without its Sigma part, then counter 3 complete: 2 is incomplete,
  // the Sigma receiver sees a step of 2 (one frame lost), 3 is delivered.
  encode_coop(neighbour_at(1200000, 0x8002), CoopGroup::kNeighbour, 2, f);
  EXPECT_EQ(feed(dec, f, 1210000, out, 4), Status::kEmpty);
  encode_coop(neighbour_at(1300000, 0x8002), CoopGroup::kNeighbour, 3, f);
  ASSERT_EQ(feed(dec, f, 1310000, out), Status::kOk);
  EXPECT_EQ(out.neighbour.vehicle_id, 0x8002);
  EXPECT_EQ(out.neighbour.t_us, 1300000U);
  EXPECT_EQ(dec.stats().incomplete, 2U);
  EXPECT_EQ(dec.stats().frames_lost, 1U);
  // Counter 4 with its Time part missing and its Corr part arriving late after
  // counter 5's first part: both partial groups are dropped.
  encode_coop(neighbour_at(1400000, 0x8002), CoopGroup::kNeighbour, 4, f);
  for (size_t k = 1; k < 5; ++k) EXPECT_EQ(dec.on_frame(f[k], 1410000, out), Status::kEmpty);
  hal::CanFrame g[kCoopFrames];
  encode_coop(neighbour_at(1500000, 0x8002), CoopGroup::kNeighbour, 5, g);
  EXPECT_EQ(dec.on_frame(g[0], 1510000, out), Status::kEmpty);
  EXPECT_EQ(dec.stats().incomplete, 3U);
  EXPECT_EQ(dec.stats().neighbour_states, 2U);
  // A wrong length is dropped and counted.
  hal::CanFrame shortf = g[1];
  shortf.len = 6;
  EXPECT_EQ(dec.on_frame(shortf, 1510000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().length_errors, 1U);
}

TEST(CanSensorDecoderNeighbour, FlaggedAndNotValidStatesAreDroppedAndCounted) {
  Params params;
  CanSensorDecoder dec;
  dec.configure(params);
  CanSensorSample out;
  hal::CanFrame f[kCoopFrames];
  NeighbourState s = neighbour_at(2000000, 0x8003);
  s.pos_nav_m.x = 3.0e6F;  // beyond the +-2147 km field: clipped and flagged
  EXPECT_TRUE(encode_coop(s, CoopGroup::kNeighbour, 0, f));
  EXPECT_EQ(feed(dec, f, 2000000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().saturated, 1U);
  EXPECT_FALSE(encode_coop(neighbour_at(2100000, 0x8003), CoopGroup::kNeighbour, 1, f, false));
  EXPECT_EQ(feed(dec, f, 2100000, out), Status::kRejected);
  EXPECT_EQ(dec.stats().neighbour_invalid, 1U);
  EXPECT_EQ(dec.stats().neighbour_states, 0U);
  EXPECT_FALSE(encode_coop(neighbour_at(2200000, 0x8003), CoopGroup::kNeighbour, 2, f));
  EXPECT_EQ(feed(dec, f, 2200000, out), Status::kOk);
  // Our own UWBNAV_Coop* frames (if the bus echoes them) are not inputs.
  EXPECT_FALSE(encode_coop(neighbour_at(2300000, 0x8004), CoopGroup::kOwn, 0, f));
  for (const auto& fr : f) EXPECT_EQ(dec.on_frame(fr, 2300000, out), Status::kNotFound);
  EXPECT_EQ(dec.stats().frames, 18U);
}

TEST(CanSensorDecoderNeighbour, NeighbourStatesAreDecodedWhileHilInputIsDisabled) {
  Params params;  // can.hil_rx_enable defaults to 0
  CanSensorDecoder dec;
  dec.configure(params);
  EXPECT_TRUE(dec.hil_enabled()) << "the decoder decodes HIL frames unless told otherwise";
  dec.set_hil_enabled(false);
  CanSensorEncoder enc;
  hal::CanFrame imu[kImuFrames];
  enc.encode_imu(imu_at(3000000), imu);
  hal::CanFrame nb[kCoopFrames];
  encode_coop(neighbour_at(3000000, 0x8009), CoopGroup::kNeighbour, 0, nb);
  CanSensorSample out;
  // Interleaved on the bus: the HIL parts are ignored, the neighbour state arrives.
  for (size_t k = 0; k < kCoopFrames; ++k) {
    if (k < kImuFrames) {
      EXPECT_EQ(dec.on_frame(imu[k], 3005000, out), Status::kNotFound);
    }
    const Status st = dec.on_frame(nb[k], 3005000, out);
    EXPECT_EQ(st, k + 1 < kCoopFrames ? Status::kEmpty : Status::kOk);
  }
  EXPECT_EQ(out.kind, SensorKind::kNeighbour);
  EXPECT_EQ(out.neighbour.vehicle_id, 0x8009);
  EXPECT_EQ(dec.stats().frames, 6U) << "ignored HIL frames are not counted";
  EXPECT_EQ(dec.stats().imu_samples, 0U);
  // Enabled again, both streams decode side by side.
  dec.set_hil_enabled(true);
  enc.encode_imu(imu_at(3010000), imu);
  encode_coop(neighbour_at(3010000, 0x8009), CoopGroup::kNeighbour, 1, nb);
  int imu_ok = 0;
  int nb_ok = 0;
  for (size_t k = 0; k < kCoopFrames; ++k) {
    if (k < kImuFrames && dec.on_frame(imu[k], 3015000, out) == Status::kOk && out.kind == SensorKind::kImu) ++imu_ok;
    if (dec.on_frame(nb[k], 3015000, out) == Status::kOk && out.kind == SensorKind::kNeighbour) ++nb_ok;
  }
  EXPECT_EQ(imu_ok, 1);
  EXPECT_EQ(nb_ok, 1);
}
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
// ---- GNSS_Fix*: receiver fixes from the GNSS gateway -----------------------

GnssFix fix_at(uint64_t t_us, GnssFixType type = GnssFixType::kDgnss) {
  GnssFix f;
  f.t_us = t_us;
  f.rx_t_us = t_us;
  f.pos_nav_m = Vec3f{45.5F, -12.25F, 1.5F};
  f.pos_sigma_m = Vec3f{0.6F, 0.6F, 1.2F};
  f.vel_nav_mps = Vec3f{3.0F, 0.5F, 0.0F};
  f.vel_sigma_mps = 0.1F;
  f.fix = type;
  f.num_sv = 11;
  return f;
}

Status feed_gnss(CanSensorDecoder& dec, const hal::CanFrame (&f)[kGnssFrames], uint64_t now_us, CanSensorSample& out,
                 int skip = -1) {
  Status last = Status::kEmpty;
  for (size_t k = 0; k < kGnssFrames; ++k) {
    if (static_cast<int>(k) == skip) continue;
    last = dec.on_frame(f[k], now_us, out);
    if (k + 1 < kGnssFrames && last == Status::kOk) ADD_FAILURE() << "fix complete before its last part";
  }
  return last;
}

TEST(CanSensorDecoderGnss, FixesAreReassembledWhileHilIsDisabledAndBadGroupsAreDroppedAndCounted) {
  Params params;
  CanSensorDecoder dec;
  dec.configure(params);
  dec.set_hil_enabled(false);  // a vehicle without a HIL rig still hears its GNSS gateway
  CanSensorSample out;
  hal::CanFrame f[kGnssFrames];
  const uint64_t t = (uint64_t{1} << 32) + 1000;  // just past a wrap of the 32-bit time
  ASSERT_FALSE(encode_gnss(fix_at(t), 0, f));
  ASSERT_EQ(feed_gnss(dec, f, t + 70000, out), Status::kOk);
  ASSERT_EQ(out.kind, SensorKind::kGnss);
  EXPECT_EQ(out.gnss.t_us, t);
  EXPECT_EQ(out.gnss.rx_t_us, t + 70000);
  EXPECT_EQ(out.gnss.fix, GnssFixType::kDgnss);
  EXPECT_EQ(out.gnss.num_sv, 11);
  EXPECT_NEAR(out.gnss.pos_nav_m.x, 45.5F, 1e-5F);
  EXPECT_NEAR(out.gnss.vel_sigma_mps, 0.1F, 1e-5F);

  // Part 3 lost: the next group's first part (another counter) drops the partial one.
  ASSERT_FALSE(encode_gnss(fix_at(t + 100000), 1, f));
  EXPECT_EQ(feed_gnss(dec, f, t + 170000, out, 3), Status::kEmpty);
  ASSERT_FALSE(encode_gnss(fix_at(t + 200000), 2, f));
  EXPECT_EQ(feed_gnss(dec, f, t + 270000, out), Status::kOk);
  EXPECT_EQ(out.gnss.t_us, t + 200000);
  // No fix: dropped, counted.
  ASSERT_FALSE(encode_gnss(fix_at(t + 300000, GnssFixType::kNone), 3, f));
  EXPECT_EQ(feed_gnss(dec, f, t + 370000, out), Status::kRejected);
  // A claimed sigma beyond the signal's range: flagged by the sender, dropped.
  GnssFix wide = fix_at(t + 400000);
  wide.pos_sigma_m.y = 30.0F;
  ASSERT_TRUE(encode_gnss(wide, 4, f));
  EXPECT_EQ(feed_gnss(dec, f, t + 470000, out), Status::kRejected);
  // A corrupted part: rejected by the E2E check, the group never completes.
  ASSERT_FALSE(encode_gnss(fix_at(t + 500000), 5, f));
  f[1].data[4] ^= 0x10;
  EXPECT_EQ(feed_gnss(dec, f, t + 570000, out, -1), Status::kEmpty);

  const CanSensorStats& st = dec.stats();
  EXPECT_EQ(st.gnss_fixes, 2U);
  EXPECT_EQ(st.gnss_no_fix, 1U);
  EXPECT_EQ(st.saturated, 1U);
  EXPECT_EQ(st.incomplete, 1U);
  EXPECT_EQ(st.crc_errors, 1U);
  EXPECT_EQ(st.imu_samples + st.uwb_ranges, 0U);
}
#endif  // UWBNAV_GNSS

}  // namespace
}  // namespace uwbnav::can
