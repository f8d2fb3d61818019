// Typed CAN messages: Intel bit layout, encode/decode round trip within the
// DBC resolution, saturation with the Saturated flag, non-finite handling.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"

namespace uwbnav::can {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

TEST(CanBits, IntelOrderPutsLsbFirstAcrossByteBoundaries) {
  uint8_t d[8] = {};
  put_bits(d, 12, 12, 0xABC);  // bits 12..23
  EXPECT_EQ(d[1], 0xC0);
  EXPECT_EQ(d[2], 0xAB);
  EXPECT_EQ(get_bits(d, 12, 12), 0xABCU);
  put_bits(d, 16, 48, 0x0000123456789ABCULL);
  EXPECT_EQ(d[2], 0xBC);
  EXPECT_EQ(d[6], 0x34);
  EXPECT_EQ(d[7], 0x12);
  EXPECT_EQ(get_bits(d, 16, 48), 0x123456789ABCULL);
}

TEST(CanMessages, PosXyKnownFrameBytes) {
  PosXYMsg m;
  m.status = NavStatus::kDegraded;
  m.x_nav_m = 1.0F;    // raw 1000 = 0x0003E8
  m.y_nav_m = -0.002F; // raw -2 = 0xFFFFFE
  hal::CanFrame f;
  EXPECT_FALSE(encode(m, 3, f));
  EXPECT_EQ(f.id, 0x101U);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[1], 0x23);  // status 2 in bits 12..13, counter 3
  EXPECT_EQ(f.data[2], 0xE8);
  EXPECT_EQ(f.data[3], 0x03);
  EXPECT_EQ(f.data[4], 0x00);
  EXPECT_EQ(f.data[5], 0xFE);
  EXPECT_EQ(f.data[6], 0xFF);
  EXPECT_EQ(f.data[7], 0xFF);
  EXPECT_EQ(f.data[0], e2e_crc(0x1101, f.data, 8));
}

TEST(CanMessages, NavOutputSignalsRoundTripWithinResolution) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> pos(-8000.0F, 8000.0F), z(-30.0F, 30.0F), vel(-60.0F, 60.0F),
      hdg(-3.14159F, 3.14159F), sig(0.0F, 20.0F), corr(-1.0F, 1.0F);
  for (int i = 0; i < 2000; ++i) {
    hal::CanFrame f;
    PosXYMsg p{NavStatus::kValid, pos(rng), pos(rng)};
    PosXYMsg pd;
    ASSERT_FALSE(encode(p, static_cast<uint8_t>(i % 15), f));
    FrameMeta meta;
    ASSERT_EQ(decode(f, pd, &meta), Status::kOk);
    EXPECT_EQ(meta.counter, i % 15);
    EXPECT_FALSE(meta.saturated);
    EXPECT_EQ(pd.status, NavStatus::kValid);
    // Half an LSB of quantization; float storage of the decoded value adds < 0.5 ulp at 8 km.
    EXPECT_NEAR(pd.x_nav_m, p.x_nav_m, 0.0005 + 0.0005);
    EXPECT_NEAR(pd.y_nav_m, p.y_nav_m, 0.0005 + 0.0005);

    PosZMsg zm{NavStatus::kDegraded, z(rng), vel(rng), static_cast<uint16_t>(i % 256), static_cast<uint16_t>(i % 7)};
    PosZMsg zd;
    ASSERT_FALSE(encode(zm, 0, f));
    ASSERT_EQ(decode(f, zd), Status::kOk);
    EXPECT_NEAR(zd.z_nav_m, zm.z_nav_m, 0.0005 + 1e-6);
    EXPECT_NEAR(zd.vz_nav_mps, zm.vz_nav_mps, 0.005 + 1e-5);
    EXPECT_EQ(zd.ranges_used, zm.ranges_used);
    EXPECT_EQ(zd.ranges_rejected, zm.ranges_rejected);
    EXPECT_EQ(zd.status, NavStatus::kDegraded);

    VelHdgMsg v{vel(rng), vel(rng), hdg(rng)};
    VelHdgMsg vd;
    ASSERT_FALSE(encode(v, 0, f));
    ASSERT_EQ(decode(f, vd), Status::kOk);
    EXPECT_NEAR(vd.vx_nav_mps, v.vx_nav_mps, 0.005 + 1e-5);
    EXPECT_NEAR(vd.vy_nav_mps, v.vy_nav_mps, 0.005 + 1e-5);
    EXPECT_NEAR(vd.heading_rad, v.heading_rad, 0.00005 + 1e-6);

    AccuracyMsg a{sig(rng), sig(rng), sig(rng), corr(rng)};
    AccuracyMsg ad;
    ASSERT_FALSE(encode(a, 0, f));
    ASSERT_EQ(decode(f, ad), Status::kOk);
    EXPECT_NEAR(ad.sigma_x_m, a.sigma_x_m, 0.0025 + 1e-6);
    EXPECT_NEAR(ad.sigma_z_m, a.sigma_z_m, 0.0025 + 1e-6);
    EXPECT_NEAR(ad.corr_xy, a.corr_xy, 0.0005 + 1e-6);
  }
}

TEST(CanMessages, OutOfRangeValuesSaturateAndSetTheFlagInsteadOfWrapping) {
  hal::CanFrame f;
  PosXYMsg p{NavStatus::kValid, 9000.0F, -9000.0F};
  EXPECT_TRUE(encode(p, 0, f));
  PosXYMsg d;
  FrameMeta meta;
  ASSERT_EQ(decode(f, d, &meta), Status::kOk);
  EXPECT_TRUE(meta.saturated);
  EXPECT_NEAR(d.x_nav_m, 8388.607F, 1e-3F);
  EXPECT_NEAR(d.y_nav_m, -8388.608F, 1e-3F);

  PosZMsg z{NavStatus::kValid, 40.0F, 0.0F, 300, 0};
  EXPECT_TRUE(encode(z, 0, f));
  PosZMsg zd;
  ASSERT_EQ(decode(f, zd, &meta), Status::kOk);
  EXPECT_TRUE(meta.saturated);
  EXPECT_NEAR(zd.z_nav_m, 32.767F, 1e-4F);
  EXPECT_EQ(zd.ranges_used, 255);

  DiagMsg g{0xFFFF, 100, 1000000, 70000};
  EXPECT_TRUE(encode(g, 0, f));
  DiagMsg gd;
  ASSERT_EQ(decode(f, gd, &meta), Status::kOk);
  EXPECT_EQ(gd.resets, 7U);
  EXPECT_EQ(gd.overruns, 65535U);
  EXPECT_EQ(gd.input_rejects, 65535U);
  EXPECT_EQ(gd.nlos_mask, 0xFFFF);

  // Exactly at the limits: no flag.
  PosXYMsg edge{NavStatus::kValid, 8388.0F, -8388.0F};
  EXPECT_FALSE(encode(edge, 0, f));
}

TEST(CanMessages, NonFiniteValuesAreFlaggedOrMarkedNotAvailable) {
  hal::CanFrame f;
  FrameMeta meta;
  PosXYMsg p{NavStatus::kInvalid, kNan, 1.0F};
  EXPECT_TRUE(encode(p, 0, f));
  PosXYMsg pd;
  ASSERT_EQ(decode(f, pd, &meta), Status::kOk);
  EXPECT_TRUE(meta.saturated);
  EXPECT_EQ(pd.x_nav_m, 0.0F);

  AccuracyMsg a{kNan, 0.1F, 0.1F, 0.0F};
  EXPECT_TRUE(encode(a, 0, f));
  AccuracyMsg ad;
  ASSERT_EQ(decode(f, ad), Status::kOk);
  EXPECT_NEAR(ad.sigma_x_m, 20.475F, 1e-4F) << "unknown sigma is sent as the worst value";

  HilUwbTimeMsg t{123, kNan, -90.25F};
  EXPECT_FALSE(encode(t, 0, f)) << "not-available power is a code, not a saturation";
  HilUwbTimeMsg td;
  ASSERT_EQ(decode(f, td), Status::kOk);
  EXPECT_TRUE(std::isnan(td.fp_power_dbm));
  EXPECT_NEAR(td.rx_power_dbm, -90.25F, 0.25F);
  EXPECT_EQ(td.t_sensor_us, 123U);
}

TEST(CanMessages, HeadingIsWrappedIntoPlusMinusPiWithoutSaturation) {
  hal::CanFrame f;
  VelHdgMsg v{0.0F, 0.0F, 3.5F};
  EXPECT_FALSE(encode(v, 0, f));
  VelHdgMsg d;
  ASSERT_EQ(decode(f, d), Status::kOk);
  EXPECT_NEAR(d.heading_rad, 3.5F - 2.0F * 3.14159265F, 1e-4F);
  VelHdgMsg neg{0.0F, 0.0F, -7.0F};
  EXPECT_FALSE(encode(neg, 0, f));
  ASSERT_EQ(decode(f, d), Status::kOk);
  EXPECT_NEAR(d.heading_rad, -7.0F + 2.0F * 3.14159265F, 0.00005F + 1e-6F);
}

TEST(CanMessages, NavTimeCarriesTheSolutionModeOfItsGroup) {
  hal::CanFrame f;
  for (const NavMode mode : {NavMode::kNone, NavMode::kInertial, NavMode::kUwbOnly, NavMode::kAligning,
                             NavMode::kRecovering, NavMode::kLsFix}) {
    encode(NavTimeMsg{987654321ULL, mode}, 3, f);
    NavTimeMsg t;
    ASSERT_EQ(decode(f, t), Status::kOk);
    EXPECT_EQ(t.mode, mode);
    EXPECT_EQ(t.nav_t_us, 987654321ULL);
  }
}

TEST(CanMessages, DecodeRejectsWrongIdLengthCrcAndCounterFifteen) {
  hal::CanFrame f;
  encode(NavTimeMsg{123456789012ULL}, 4, f);
  NavTimeMsg t;
  ASSERT_EQ(decode(f, t), Status::kOk);
  EXPECT_EQ(t.nav_t_us, 123456789012ULL);
  PosXYMsg p;
  EXPECT_EQ(decode(f, p), Status::kInvalidArgument);
  hal::CanFrame bad = f;
  bad.data[5] ^= 0x10;
  EXPECT_EQ(decode(bad, t), Status::kRejected);
  bad = f;
  bad.len = 7;
  EXPECT_EQ(decode(bad, t), Status::kInvalidArgument);
  bad = f;
  e2e_protect(find_message(f.id)->data_id, 15, bad.data, 8);
  EXPECT_EQ(decode(bad, t), Status::kOutOfRange);
}

TEST(CanMessages, HilImuFramesRoundTrip) {
  hal::CanFrame f;
  HilImuAccelMsg a{Vec3f{0.1234F, -9.80665F, 150.0F}};
  EXPECT_FALSE(encode(a, 0, f));
  HilImuAccelMsg ad;
  ASSERT_EQ(decode(f, ad), Status::kOk);
  EXPECT_NEAR(ad.accel_body_mps2.x, 0.1234F, 0.0025F + 1e-6F);
  EXPECT_NEAR(ad.accel_body_mps2.y, -9.80665F, 0.0025F + 1e-6F);
  HilImuGyroMsg g{Vec3f{0.0005F, -1.0F, 40.0F}};
  EXPECT_TRUE(encode(g, 0, f)) << "40 rad/s exceeds the 32.767 rad/s field";
  HilUwbRangeMsg r{513, 2, 123.4567F};
  EXPECT_FALSE(encode(r, 0, f));
  HilUwbRangeMsg rd;
  ASSERT_EQ(decode(f, rd), Status::kOk);
  EXPECT_EQ(rd.anchor_id, 513);
  EXPECT_EQ(rd.tag_id, 2);
  EXPECT_NEAR(rd.range_m, 123.4567F, 0.0005F + 1e-5F);
  HilUwbRangeMsg neg{1, 0, -0.5F};
  EXPECT_FALSE(encode(neg, 0, f)) << "small negative ranges are legal radio output";
  ASSERT_EQ(decode(f, rd), Status::kOk);
  EXPECT_NEAR(rd.range_m, -0.5F, 1e-6F);
}

}  // namespace
}  // namespace uwbnav::can
