// Produces a candump log and the matching estimates.csv from CanPublisher
// output (a circle drive with invalid and saturated epochs; with UWBNAV_COOP
// also this vehicle's UWBNAV_Coop* state, tag at the body origin), for the
// python check tests/scripts/can_decode.py, and decodes the log back in C++.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>

#include "firmware/can/messages.hpp"
#include "firmware/can/publisher.hpp"
#include "hal/host/candump_log.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::can {
namespace {

std::string fixture_dir() {
  if (const char* d = std::getenv("UWBNAV_CAN_FIXTURE_DIR"); d != nullptr && *d != '\0') return d;
  return std::string(UWBNAV_BINARY_DIR) + "/tests/can_fixture";
}

NavOutput output_at(int i) {
  NavOutput o;
  o.t_us = 3000000 + static_cast<uint64_t>(i) * 10000 + 1234;  // loop time minus latency
  const float a = 0.01F * static_cast<float>(i);
  o.status = i < 20 ? NavStatus::kInitialising : NavStatus::kValid;
  o.pos_nav_m = Vec3f{25.0F * std::cos(a) + 100.0F, 25.0F * std::sin(a) - 40.0F, 0.5F + 0.001F * static_cast<float>(i % 7)};
  o.vel_nav_mps = Vec3f{-2.5F * std::sin(a), 2.5F * std::cos(a), 0.0F};
  o.heading_rad = a + 1.5707964F;
  o.heading_sigma_rad = 0.03F;
  o.pos_sigma_m = Vec3f{0.04F, 0.05F, 0.12F};
  o.pos_xy_corr = 0.1F;
  o.ranges_used = static_cast<uint16_t>(i % 5);
  o.ranges_rejected = static_cast<uint16_t>(i % 3 == 0 ? 1 : 0);
  if (i == 150) {  // a diverged epoch: no finite position
    o.status = NavStatus::kInvalid;
    o.pos_nav_m.x = std::numeric_limits<float>::quiet_NaN();
  }
  if (i == 160) o.pos_nav_m.z = 50.0F;  // beyond the +-32.767 m PosZ field: saturated and flagged
  return o;
}

TEST(CanFixture, WritesCandumpLogAndEstimatesForThePythonDecoder) {
  const std::string dir = fixture_dir();
  std::filesystem::create_directories(dir);
  hal::MemCanBus bus;
  hal::CandumpLogWriter log;
  ASSERT_EQ(log.open(dir + "/can.log", "can0"), Status::kOk);
  hal::CanLogTee tee(bus, log);
  dataset::EstimatesWriter est;
  ASSERT_EQ(est.open(dir + "/estimates.csv"), Status::kOk);
  Params params;
#if UWBNAV_COOP
  ASSERT_EQ(params.set(ParamId::kCoopVehicleId, 1.0F), Status::kOk);
  // Groups at cycles 20..140 (status initialising before), 151 (150 is invalid), 160..490.
  const uint32_t coop_frames = (13 + 1 + 34) * static_cast<uint32_t>(kCoopFrames);
#else
  const uint32_t coop_frames = 0;
#endif
  CanPublisher pub;
  pub.configure(params);
  CanDiag diag;
  const int n = 500;
  for (int i = 0; i < n; ++i) {
    const NavOutput o = output_at(i);
    ASSERT_EQ(est.write(o), Status::kOk);
    diag.set_anchor_nlos(i % 4, i % 8 < 4);
    diag.resets = o.resets;
#if UWBNAV_COOP
    pub.set_coop_state(coop_state_from(o, Vec3f{}, pub.coop_vehicle_id(), false));
#endif
    pub.on_cycle(3000000 + static_cast<uint64_t>(i) * 10000 + 10000, o, diag, tee);
  }
  ASSERT_EQ(est.close(), Status::kOk);
  ASSERT_EQ(log.close(), Status::kOk);
  EXPECT_EQ(pub.stats().sent, static_cast<uint32_t>(n * 4 + 2 * (n / 2) + n / 10) + coop_frames);
  EXPECT_EQ(pub.stats().saturated, 2U);

  // Read back with the C++ reader: every position frame decodes to its output.
  hal::CandumpLogReader reader;
  ASSERT_EQ(reader.open(dir + "/can.log"), Status::kOk);
  hal::CanFrame f;
  int positions = 0;
  uint32_t coop_read = 0;
  while (reader.next(f) == Status::kOk) {
#if UWBNAV_COOP
    if (f.id >= coop_id(CoopGroup::kOwn, 0) && f.id < coop_id(CoopGroup::kOwn, kCoopFrames)) ++coop_read;
#endif
    if (f.id != id_of(MsgId::kPosXY)) continue;
    PosXYMsg m;
    FrameMeta meta;
    ASSERT_EQ(decode(f, m, &meta), Status::kOk);
    const NavOutput o = output_at(positions);
    if (std::isfinite(o.pos_nav_m.x)) {
      EXPECT_NEAR(m.x_nav_m, o.pos_nav_m.x, 0.0005F + 1e-5F);
      EXPECT_NEAR(m.y_nav_m, o.pos_nav_m.y, 0.0005F + 1e-5F);
    } else {
      EXPECT_TRUE(meta.saturated);
    }
    ++positions;
  }
  EXPECT_EQ(positions, n);
  EXPECT_EQ(coop_read, coop_frames);
  EXPECT_EQ(reader.skipped(), 0U);
}

}  // namespace
}  // namespace uwbnav::can
