// HIL sensor frames: rig encoder -> firmware decoder round trip, E2E failures
// counted and dropped, multi-frame grouping, 32-bit timestamp reconstruction.
#include <gtest/gtest.h>

#include <cmath>

#include "firmware/can/sensor_decoder.hpp"

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

}  // namespace
}  // namespace uwbnav::can
