// Typed CAN messages: Intel bit layout, encode/decode round trip within the
// DBC resolution, saturation with the Saturated flag, non-finite handling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
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

// The byte-wise put_bits/get_bits against the one-bit-at-a-time definition of
// the Intel layout: every start bit and length a 64-byte payload admits, on a
// random background that bits outside the signal must keep.
TEST(CanBits, ByteWisePackingMatchesTheBitwiseDefinitionForEveryStartAndLength) {
  std::mt19937_64 rng(7);
  for (unsigned start = 0; start < 256; ++start) {
    for (unsigned len = 1; len <= 64; ++len) {
      uint8_t background[64];
      for (auto& b : background) b = static_cast<uint8_t>(rng());
      const uint64_t raw = len == 64 ? rng() : rng() & ((uint64_t{1} << len) - 1U);
      uint8_t expected[64];
      std::copy(std::begin(background), std::end(background), std::begin(expected));
      for (unsigned i = 0; i < len; ++i) {
        const unsigned bit = start + i;
        const auto mask = static_cast<uint8_t>(1U << (bit % 8));
        expected[bit / 8] = static_cast<uint8_t>(((raw >> i) & 1U) != 0 ? expected[bit / 8] | mask
                                                                          : expected[bit / 8] & ~mask);
      }
      uint8_t got[64];
      std::copy(std::begin(background), std::end(background), std::begin(got));
      put_bits(got, static_cast<uint8_t>(start), static_cast<uint8_t>(len), raw);
      ASSERT_TRUE(std::equal(std::begin(got), std::end(got), std::begin(expected))) << start << " " << len;
      ASSERT_EQ(get_bits(got, static_cast<uint8_t>(start), static_cast<uint8_t>(len)), raw) << start << " " << len;
    }
  }
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

#if UWBNAV_COOP
// ---- Cooperative positioning: UWBNAV_Coop* / V2X_Neighbour* ----------------

// A state with the covariance built from sigmas and correlations.
NeighbourState coop_state(Vec3f pos, Vec3f vel, Vec3f sigma, float rxy, float rxz, float ryz) {
  NeighbourState s;
  s.t_us = 7000123456ULL;  // above 2^32: the frames carry the low 32 bits
  s.rx_t_us = s.t_us;
  s.vehicle_id = 0x8005;
  s.pos_nav_m = pos;
  s.vel_nav_mps = vel;
  s.cov_pos_m2[0] = sigma.x * sigma.x;
  s.cov_pos_m2[1] = rxy * sigma.x * sigma.y;
  s.cov_pos_m2[2] = rxz * sigma.x * sigma.z;
  s.cov_pos_m2[3] = sigma.y * sigma.y;
  s.cov_pos_m2[4] = ryz * sigma.y * sigma.z;
  s.cov_pos_m2[5] = sigma.z * sigma.z;
  s.cooperative = true;
  return s;
}

float ulp(float v) { return std::nextafter(std::fabs(v), std::numeric_limits<float>::infinity()) - std::fabs(v); }

TEST(CanCoop, KnownFrameBytesOfTheTimeAndPosXParts) {
  CoopParts p;
  p.valid = true;
  p.cooperative = true;
  p.vehicle_id = 0x8005;
  p.t_sensor_us = 0x12345678U;
  p.pos_nav_m = Vec3f{-1.5F, 0.0F, 0.0F};  // raw -1500 = 0xFFFFFA24
  p.vel_nav_mps = Vec3f{kNan, 0.0F, 0.0F}; // not reported: raw 0x8000
  hal::CanFrame f;
  EXPECT_FALSE(encode_coop_part(p, CoopGroup::kOwn, 0, 4, f));
  EXPECT_EQ(f.id, 0x110U);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[1], 0x34);  // Valid (bit 12), Cooperative (bit 13), counter 4
  EXPECT_EQ(f.data[2], 0x05);
  EXPECT_EQ(f.data[3], 0x80);
  EXPECT_EQ(f.data[4], 0x78);
  EXPECT_EQ(f.data[5], 0x56);
  EXPECT_EQ(f.data[6], 0x34);
  EXPECT_EQ(f.data[7], 0x12);
  EXPECT_EQ(f.data[0], e2e_crc(0x1110, f.data, 8));
  EXPECT_FALSE(encode_coop_part(p, CoopGroup::kNeighbour, 1, 4, f)) << "not reported is a code, not a saturation";
  EXPECT_EQ(f.id, 0x0C1U);
  EXPECT_EQ(f.data[1], 0x04);
  EXPECT_EQ(f.data[2], 0x24);
  EXPECT_EQ(f.data[3], 0xFA);
  EXPECT_EQ(f.data[4], 0xFF);
  EXPECT_EQ(f.data[5], 0xFF);
  EXPECT_EQ(f.data[6], 0x00);
  EXPECT_EQ(f.data[7], 0x80);
  EXPECT_EQ(f.data[0], e2e_crc(0x10C1, f.data, 8));
  CoopParts d;
  ASSERT_EQ(decode_coop_part(f, CoopGroup::kNeighbour, 1, d), Status::kOk);
  EXPECT_EQ(d.pos_nav_m.x, -1.5F);
  EXPECT_TRUE(std::isnan(d.vel_nav_mps.x));
  EXPECT_EQ(decode_coop_part(f, CoopGroup::kOwn, 1, d), Status::kInvalidArgument) << "the other group's id";
  EXPECT_EQ(decode_coop_part(f, CoopGroup::kNeighbour, 2, d), Status::kInvalidArgument) << "another part's id";
}

TEST(CanCoop, StatesRoundTripWithinTheQuantisationOfBothGroups) {
  std::mt19937 rng(16);
  std::uniform_real_distribution<float> horiz(-2.0e6F, 2.0e6F), local(-8000.0F, 8000.0F), vert(-10000.0F, 10000.0F),
      vel(-320.0F, 320.0F), sig(0.002F, 60.0F), rho(-0.95F, 0.95F);
  for (int i = 0; i < 5000; ++i) {
    const bool far = i % 2 == 0;
    const Vec3f pos{far ? horiz(rng) : local(rng), far ? horiz(rng) : local(rng), vert(rng)};
    const float a = rho(rng), b = rho(rng);
    // xz, yz such that the correlation matrix stays positive definite
    NeighbourState s = coop_state(pos, Vec3f{vel(rng), vel(rng), vel(rng)}, Vec3f{sig(rng), sig(rng), sig(rng)}, a,
                                  0.5F * b, 0.3F * a);
    s.cooperative = i % 3 == 0;
    s.vehicle_id = static_cast<uint16_t>(0x8000 + 1 + i % 32766);
    const CoopGroup g = i % 2 == 0 ? CoopGroup::kOwn : CoopGroup::kNeighbour;
    hal::CanFrame f[kCoopFrames];
    ASSERT_FALSE(encode_coop(s, g, static_cast<uint8_t>(i % 15), f));
    for (size_t k = 0; k < kCoopFrames; ++k) EXPECT_EQ(f[k].id, coop_id(g, k));
    NeighbourState d;
    CoopMeta meta;
    const uint64_t now = s.t_us + 20000;  // received 20 ms later
    ASSERT_EQ(decode_coop(f, g, now, d, &meta), Status::kOk);
    EXPECT_EQ(meta.counter, i % 15);
    EXPECT_FALSE(meta.saturated);
    EXPECT_TRUE(meta.valid);
    EXPECT_EQ(d.t_us, s.t_us) << "unwrapped from the 32-bit time";
    EXPECT_EQ(d.rx_t_us, now);
    EXPECT_EQ(d.vehicle_id, s.vehicle_id);
    EXPECT_EQ(d.cooperative, s.cooperative);
    // Half a millimetre of quantisation plus half an ulp of the float result.
    EXPECT_NEAR(d.pos_nav_m.x, s.pos_nav_m.x, 0.0005F + ulp(s.pos_nav_m.x) / 2.0F);
    EXPECT_NEAR(d.pos_nav_m.y, s.pos_nav_m.y, 0.0005F + ulp(s.pos_nav_m.y) / 2.0F);
    EXPECT_NEAR(d.pos_nav_m.z, s.pos_nav_m.z, 0.0005F + ulp(s.pos_nav_m.z) / 2.0F);
    if (std::fabs(s.pos_nav_m.x) >= 16384.0F) {
      EXPECT_EQ(d.pos_nav_m.x, s.pos_nav_m.x) << "beyond 16 km a float step exceeds 2 mm: the same float comes back";
    }
    EXPECT_NEAR(d.vel_nav_mps.x, s.vel_nav_mps.x, 0.005F + 1e-4F);
    EXPECT_NEAR(d.vel_nav_mps.z, s.vel_nav_mps.z, 0.005F + 1e-4F);
    const float sx = std::sqrt(s.cov_pos_m2[0]), sy = std::sqrt(s.cov_pos_m2[3]), sz = std::sqrt(s.cov_pos_m2[5]);
    const float dsx = std::sqrt(d.cov_pos_m2[0]), dsy = std::sqrt(d.cov_pos_m2[3]), dsz = std::sqrt(d.cov_pos_m2[5]);
    EXPECT_NEAR(dsx, sx, 0.0005F + 1e-5F);
    EXPECT_NEAR(dsy, sy, 0.0005F + 1e-5F);
    EXPECT_NEAR(dsz, sz, 0.0005F + 1e-5F);
    EXPECT_NEAR(d.cov_pos_m2[1] / (dsx * dsy), s.cov_pos_m2[1] / (sx * sy), 0.5F / 127.0F + 1e-5F);
    EXPECT_NEAR(d.cov_pos_m2[2] / (dsx * dsz), s.cov_pos_m2[2] / (sx * sz), 0.5F / 127.0F + 1e-5F);
    EXPECT_NEAR(d.cov_pos_m2[4] / (dsy * dsz), s.cov_pos_m2[4] / (sy * sz), 0.5F / 127.0F + 1e-5F);
  }
}

TEST(CanCoop, OutOfRangeValuesSaturateWithTheFlagAndUnknownVelocityIsACode) {
  hal::CanFrame f[kCoopFrames];
  NeighbourState d;
  CoopMeta meta;
  // In range at the limits: nothing flagged.
  NeighbourState s = coop_state(Vec3f{2147483.0F, -2147483.0F, -16777.0F}, Vec3f{327.67F, -327.67F, kNan},
                                Vec3f{65.535F, 0.001F, 1.0F}, 0.0F, 0.0F, 0.0F);
  EXPECT_FALSE(encode_coop(s, CoopGroup::kOwn, 0, f));
  ASSERT_EQ(decode_coop(f, CoopGroup::kOwn, s.t_us, d, &meta), Status::kOk);
  EXPECT_FALSE(meta.saturated);
  EXPECT_EQ(d.pos_nav_m.x, 2147483.0F);
  EXPECT_EQ(d.pos_nav_m.y, -2147483.0F);
  EXPECT_NEAR(d.vel_nav_mps.y, -327.67F, 1e-4F) << "the minimum is a value, not the not-reported code";
  EXPECT_TRUE(std::isnan(d.vel_nav_mps.z));
  EXPECT_NEAR(d.cov_pos_m2[0], 65.535F * 65.535F, 1e-2F);

  // Beyond the fields: clipped to the nearest limit (never wrapped), flagged.
  const struct {
    Vec3f pos, vel, sigma;
  } cases[] = {
      {Vec3f{3.0e6F, 0, 0}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}},
      {Vec3f{0, -2.2e6F, 0}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}},
      {Vec3f{0, 0, 17000.0F}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}},
      {Vec3f{0, 0, 0}, Vec3f{400.0F, 0, 0}, Vec3f{1, 1, 1}},
      {Vec3f{0, 0, 0}, Vec3f{0, -400.0F, 0}, Vec3f{1, 1, 1}},
      {Vec3f{0, 0, 0}, Vec3f{0, 0, 0}, Vec3f{1, 70.0F, 1}},
      {Vec3f{kNan, 0, 0}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}},
  };
  for (const auto& c : cases) {
    s = coop_state(c.pos, c.vel, c.sigma, 0.0F, 0.0F, 0.0F);
    EXPECT_TRUE(encode_coop(s, CoopGroup::kOwn, 1, f));
    ASSERT_EQ(decode_coop(f, CoopGroup::kOwn, s.t_us, d, &meta), Status::kOk);
    EXPECT_TRUE(meta.saturated);
  }
  s = coop_state(Vec3f{3.0e6F, -2.2e6F, 17000.0F}, Vec3f{400.0F, -400.0F, 0}, Vec3f{1, 70.0F, 1}, 0, 0, 0);
  EXPECT_TRUE(encode_coop(s, CoopGroup::kOwn, 1, f));
  ASSERT_EQ(decode_coop(f, CoopGroup::kOwn, s.t_us, d, &meta), Status::kOk);
  EXPECT_NEAR(d.pos_nav_m.x, 2147483.647F, 0.125F);
  EXPECT_NEAR(d.pos_nav_m.y, -2147483.648F, 0.125F);
  EXPECT_NEAR(d.pos_nav_m.z, 16777.215F, 0.001F);
  EXPECT_NEAR(d.vel_nav_mps.x, 327.67F, 1e-4F);
  EXPECT_NEAR(d.vel_nav_mps.y, -327.67F, 1e-4F);
  EXPECT_NEAR(std::sqrt(d.cov_pos_m2[3]), 65.535F, 1e-4F);

  // A variance that is negative or NaN has no sigma: sent as the maximum, flagged.
  s = coop_state(Vec3f{1, 2, 3}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}, 0, 0, 0);
  s.cov_pos_m2[5] = -0.01F;
  EXPECT_TRUE(encode_coop(s, CoopGroup::kOwn, 2, f));
  // A non-finite off-diagonal is flagged too.
  s = coop_state(Vec3f{1, 2, 3}, Vec3f{0, 0, 0}, Vec3f{1, 1, 1}, 0, 0, 0);
  s.cov_pos_m2[1] = kNan;
  EXPECT_TRUE(encode_coop(s, CoopGroup::kOwn, 2, f));
}

TEST(CanCoop, CorrelationsAreClampedToPlusMinusOneAndRoundedToSteps) {
  const CoopParts exact = coop_parts_from(coop_state(Vec3f{}, Vec3f{}, Vec3f{0.1F, 0.2F, 0.3F}, 1.0F, -1.0F, 0.5F), true);
  EXPECT_EQ(exact.corr_xy, 1.0F);
  EXPECT_EQ(exact.corr_xz, -1.0F);
  NeighbourState s = coop_state(Vec3f{}, Vec3f{}, Vec3f{0.1F, 0.2F, 0.3F}, 0.0F, 0.0F, 0.0F);
  s.cov_pos_m2[1] = 1.0001F * 0.1F * 0.2F;   // |rho| a rounding error above 1
  s.cov_pos_m2[2] = -5.0F;                   // grossly inconsistent: still the nearest valid correlation
  s.cov_pos_m2[4] = 0.5F / 127.0F * 0.2F * 0.3F;  // exactly half a step: rounds away from zero
  hal::CanFrame f[kCoopFrames];
  EXPECT_FALSE(encode_coop(s, CoopGroup::kNeighbour, 0, f)) << "clamping is not a saturation";
  CoopParts p;
  for (size_t k = 0; k < kCoopFrames; ++k) ASSERT_EQ(decode_coop_part(f[k], CoopGroup::kNeighbour, k, p), Status::kOk);
  EXPECT_EQ(read_raw(signal_layout(*find_layout(0x0C5), kFirstPayloadSignal), f[5].data), 127);
  EXPECT_EQ(read_raw(signal_layout(*find_layout(0x0C5), kFirstPayloadSignal + 1), f[5].data), -127);
  const int64_t yz = read_raw(signal_layout(*find_layout(0x0C5), kFirstPayloadSignal + 2), f[5].data);
  EXPECT_TRUE(yz == 0 || yz == 1) << yz;  // the float product lands within a rounding error of the tie
  EXPECT_EQ(p.corr_xy, 1.0F);
  EXPECT_EQ(p.corr_xz, -1.0F);
  // A zero sigma has no correlation: 0, not NaN.
  s = coop_state(Vec3f{}, Vec3f{}, Vec3f{0.0F, 0.2F, 0.3F}, 0.0F, 0.0F, 0.0F);
  const CoopParts z = coop_parts_from(s, true);
  EXPECT_EQ(z.corr_xy, 0.0F);
  EXPECT_EQ(z.corr_xz, 0.0F);
  EXPECT_FALSE(encode_coop(s, CoopGroup::kNeighbour, 0, f));
}

TEST(CanCoop, CovarianceIsRebuiltFromSigmasAndCorrelations) {
  CoopParts p;
  p.valid = true;
  p.vehicle_id = 0x8001;
  p.t_sensor_us = 1000;
  p.sigma_m = Vec3f{0.05F, 0.08F, 0.2F};
  p.corr_xy = 0.5F;
  p.corr_xz = -0.25F;
  p.corr_yz = 0.125F;
  const NeighbourState s = neighbour_state_from(p, 5000);
  EXPECT_EQ(s.t_us, 1000U);
  EXPECT_EQ(s.rx_t_us, 5000U);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[0], 0.0025F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[1], 0.5F * 0.05F * 0.08F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[2], -0.25F * 0.05F * 0.2F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[3], 0.0064F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[4], 0.125F * 0.08F * 0.2F);
  EXPECT_FLOAT_EQ(s.cov_pos_m2[5], 0.04F);
  EXPECT_TRUE(std::isnan(s.vel_nav_mps.x)) << "velocity not reported stays NaN";
}

TEST(CanCoop, GroupDecodeNeedsOneCounterTheRightIdsAndGoodCrcs) {
  const NeighbourState s = coop_state(Vec3f{10, 20, 1}, Vec3f{1, 0, 0}, Vec3f{0.1F, 0.1F, 0.3F}, 0, 0, 0);
  hal::CanFrame a[kCoopFrames];
  hal::CanFrame b[kCoopFrames];
  ASSERT_FALSE(encode_coop(s, CoopGroup::kNeighbour, 3, a));
  ASSERT_FALSE(encode_coop(s, CoopGroup::kNeighbour, 4, b));
  NeighbourState d;
  hal::CanFrame mixed[kCoopFrames];
  for (size_t k = 0; k < kCoopFrames; ++k) mixed[k] = k == 3 ? b[k] : a[k];
  EXPECT_EQ(decode_coop(mixed, CoopGroup::kNeighbour, s.t_us, d), Status::kRejected) << "two groups mixed";
  EXPECT_EQ(decode_coop(a, CoopGroup::kOwn, s.t_us, d), Status::kInvalidArgument) << "neighbour ids are not ours";
  a[4].data[6] ^= 0x20;
  EXPECT_EQ(decode_coop(a, CoopGroup::kNeighbour, s.t_us, d), Status::kRejected) << "bad CRC";
  NeighbourState not_valid_src = s;
  ASSERT_FALSE(encode_coop(not_valid_src, CoopGroup::kNeighbour, 5, b, false));
  CoopMeta meta;
  ASSERT_EQ(decode_coop(b, CoopGroup::kNeighbour, s.t_us, d, &meta), Status::kOk);
  EXPECT_FALSE(meta.valid);
}
#endif  // UWBNAV_COOP

#if UWBNAV_GNSS
// ---- GNSS_Fix*: receiver fixes from the GNSS gateway -----------------------

GnssFix gnss_fix_at(uint64_t t_us) {
  GnssFix f;
  f.t_us = t_us;
  f.rx_t_us = t_us + 60000;
  f.pos_nav_m = Vec3f{-1523.4567F, 20456.125F, 3.217F};
  f.pos_sigma_m = Vec3f{0.8F, 0.9F, 1.7F};
  f.vel_nav_mps = Vec3f{12.34F, -0.56F, kNan};
  f.vel_sigma_mps = 0.15F;
  f.fix = GnssFixType::kRtkFloat;
  f.num_sv = 17;
  return f;
}

TEST(CanGnss, FixesRoundTripWithinTheQuantisationAndNotReportedStaysNotReported) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> horiz(-2.1e6F, 2.1e6F), vert(-16000.0F, 16000.0F), vel(-300.0F, 300.0F),
      sig(0.005F, 20.0F);
  const GnssFixType types[] = {GnssFixType::kSingle, GnssFixType::kDgnss, GnssFixType::kRtkFixed,
                               GnssFixType::kRtkFloat};
  for (int i = 0; i < 200; ++i) {
    GnssFix f = gnss_fix_at(0x3456789ABCULL + static_cast<uint64_t>(i) * 100000U);
    if (i > 0) {
      f.pos_nav_m = Vec3f{horiz(rng), horiz(rng), vert(rng)};
      f.vel_nav_mps = Vec3f{vel(rng), i % 3 == 0 ? kNan : vel(rng), vel(rng)};
      f.pos_sigma_m = Vec3f{sig(rng), sig(rng), sig(rng)};
      f.vel_sigma_mps = i % 5 == 0 ? kNan : sig(rng);
      f.fix = types[i % 4];
      f.num_sv = static_cast<uint8_t>(i);
    }
    hal::CanFrame frames[kGnssFrames];
    ASSERT_FALSE(encode_gnss(f, static_cast<uint8_t>(i % 15), frames)) << i;
    GnssParts parts;
    for (size_t k = 0; k < kGnssFrames; ++k) {
      EXPECT_EQ(frames[k].id, gnss_id(k));
      FrameMeta meta;
      ASSERT_EQ(decode_gnss_part(frames[k], k, parts, &meta), Status::kOk);
      EXPECT_EQ(meta.counter, i % 15);
      EXPECT_FALSE(meta.saturated);
    }
    GnssFix g;
    const uint64_t now = f.t_us + 80000;
    ASSERT_EQ(gnss_fix_from(parts, now, g), Status::kOk);
    EXPECT_EQ(g.t_us, f.t_us) << "32-bit time unwrapped against the receiver clock";
    EXPECT_EQ(g.rx_t_us, now);
    EXPECT_EQ(g.fix, f.fix);
    EXPECT_EQ(g.num_sv, f.num_sv);
    // 1 mm steps: half a step plus the float's own spacing (about 0.25 m at
    // 2000 km, 1 mm at 10 km up).
    EXPECT_NEAR(g.pos_nav_m.x, f.pos_nav_m.x, 0.0005F + std::fabs(f.pos_nav_m.x) * 0x1p-23F);
    EXPECT_NEAR(g.pos_nav_m.y, f.pos_nav_m.y, 0.0005F + std::fabs(f.pos_nav_m.y) * 0x1p-23F);
    EXPECT_NEAR(g.pos_nav_m.z, f.pos_nav_m.z, 0.0005F + std::fabs(f.pos_nav_m.z) * 0x1p-23F);
    for (int a = 0; a < 3; ++a) {
      const float want = a == 0 ? f.vel_nav_mps.x : (a == 1 ? f.vel_nav_mps.y : f.vel_nav_mps.z);
      const float got = a == 0 ? g.vel_nav_mps.x : (a == 1 ? g.vel_nav_mps.y : g.vel_nav_mps.z);
      if (std::isnan(want)) {
        EXPECT_TRUE(std::isnan(got)) << "not reported stays not reported";
      } else {
        EXPECT_NEAR(got, want, 0.005F + 1e-5F);
      }
    }
    EXPECT_NEAR(g.pos_sigma_m.x, f.pos_sigma_m.x, 0.0025F + 1e-6F);
    EXPECT_NEAR(g.pos_sigma_m.z, f.pos_sigma_m.z, 0.0025F + 1e-6F);
    if (std::isnan(f.vel_sigma_mps)) {
      EXPECT_TRUE(std::isnan(g.vel_sigma_mps));
    } else {
      EXPECT_NEAR(g.vel_sigma_mps, f.vel_sigma_mps, 0.0025F + 1e-6F);
    }
  }
}

TEST(CanGnss, NoFixAndUnknownFixTypesAreRefusedAndOversizedOrUnknownSigmasAreFlagged) {
  hal::CanFrame frames[kGnssFrames];
  GnssFix f = gnss_fix_at(5000000);
  GnssParts parts;
  GnssFix out = gnss_fix_at(1);
  // Fix type 0 (no fix) and the GGA codes GnssFix has no type for.
  for (uint8_t type : {0, 3, 6, 7}) {
    parts = gnss_parts_from(f);
    parts.fix_type = type;
    ASSERT_FALSE(encode_gnss_part(parts, 0, 3, frames[0]));
    GnssParts back;
    ASSERT_EQ(decode_gnss_part(frames[0], 0, back), Status::kOk);
    EXPECT_EQ(back.fix_type, type);
    EXPECT_EQ(gnss_fix_from(back, 5100000, out), Status::kRejected) << int{type};
    EXPECT_EQ(out.t_us, 1U) << "a refused fix leaves the output untouched";
  }
  // A claimed sigma beyond 20.475 m and an unknown (NaN) position sigma: sent
  // as the maximum with the Saturated flag (the decoder then drops the fix).
  f.pos_sigma_m.x = 25.0F;
  EXPECT_TRUE(encode_gnss(f, 0, frames));
  f = gnss_fix_at(5000000);
  f.pos_sigma_m.z = kNan;
  EXPECT_TRUE(encode_gnss(f, 0, frames));
  FrameMeta meta;
  ASSERT_EQ(decode_gnss_part(frames[4], 4, parts, &meta), Status::kOk);
  EXPECT_TRUE(meta.saturated);
  EXPECT_NEAR(parts.sigma_m.z, 20.475F, 1e-5F);
  // Wrong part for the id, and a part index past the group.
  EXPECT_EQ(decode_gnss_part(frames[1], 2, parts), Status::kInvalidArgument);
  EXPECT_EQ(decode_gnss_part(frames[1], kGnssFrames, parts), Status::kInvalidArgument);
}
#endif  // UWBNAV_GNSS

}  // namespace
}  // namespace uwbnav::can
