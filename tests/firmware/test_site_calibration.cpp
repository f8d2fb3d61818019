// The board's site range calibration at firmware start-up: App::init accepts
// an uncalibrated site and a commissioned one, refuses unusable offsets (and
// then runs no cycle), and a calibration file loaded by a host board reaches
// the SiteConfig the firmware runs on, pair by pair.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "firmware/app.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/dataset/calibration.hpp"
#include "tools/eval/replay.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

class OutputCounter final : public AppObserver {
 public:
  uint64_t outputs = 0;
  void on_range(const RangeReport&) override {}
  void on_output(const NavOutput&) override { ++outputs; }
};

// Status of App::init on `site`, and whether a cycle then produced an output.
Status init_status(const SiteConfig& site, bool* ran) {
  dataset::Recording rec;
  rec.site = site;
  hal::ReplaySources sources(rec);
  hal::LockstepClock clock;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{sources.imu, sources.uwb, can, serial, clock, store, site};
  App app(board);
  const Status s = app.init();
  OutputCounter obs;
  app.set_observer(&obs);
  app.tick(10000);
  *ran = obs.outputs > 0;
  return s;
}

SiteConfig square_site() {
  SiteConfig s;
  EXPECT_TRUE(ok(s.add_anchor(1, {0, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(2, {20, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(3, {20, 20, 2})));
  EXPECT_TRUE(ok(s.add_tag(0, {0, 0, 1})));
  return s;
}

TEST(FirmwareSiteCalibration, UsableCalibrationsStartAndUnusableOnesAreRefusedBeforeTheFirstCycle) {
  bool ran = false;
  SiteConfig s = square_site();
  EXPECT_EQ(init_status(s, &ran), Status::kOk);  // uncalibrated: sigma NaN, offsets zero
  EXPECT_TRUE(ran);
  s.range_offset_sigma_m = 0.004F;
  s.range_offset_m[0][0] = 0.15F;
  s.range_offset_m[2][0] = -0.05F;
  EXPECT_EQ(init_status(s, &ran), Status::kOk);
  EXPECT_TRUE(ran);

  struct Bad {
    const char* what;
    float sigma;
    float offset;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Bad& b : {Bad{"NaN offset", 0.004F, nan}, Bad{"infinite offset", 0.004F, INFINITY},
                       Bad{"offset beyond 10 m", 0.004F, 10.5F}, Bad{"sigma zero", 0.0F, 0.1F},
                       Bad{"negative sigma", -0.01F, 0.1F}, Bad{"sigma beyond 1 m", 1.5F, 0.1F},
                       Bad{"offsets on an uncalibrated site", nan, 0.1F}}) {
    SiteConfig bad = square_site();
    bad.range_offset_sigma_m = b.sigma;
    bad.range_offset_m[1][0] = b.offset;
    EXPECT_EQ(init_status(bad, &ran), Status::kInvalidArgument) << b.what;
    EXPECT_FALSE(ran) << b.what;
  }
  // The commissioning's systematic sigma: part of a calibration, in [0, 1] m.
  s.range_systematic_sigma_m = 0.003F;
  EXPECT_EQ(init_status(s, &ran), Status::kOk);
  EXPECT_TRUE(ran);
  for (const float sys : {-0.001F, 1.5F, INFINITY}) {
    SiteConfig bad = s;
    bad.range_systematic_sigma_m = sys;
    EXPECT_EQ(init_status(bad, &ran), Status::kInvalidArgument) << sys;
    EXPECT_FALSE(ran) << sys;
  }
  SiteConfig uncalibrated = square_site();
  uncalibrated.range_systematic_sigma_m = 0.003F;
  EXPECT_EQ(init_status(uncalibrated, &ran), Status::kInvalidArgument) << "systematic sigma on an uncalibrated site";
  EXPECT_FALSE(ran);
}

TEST(FirmwareSiteCalibration, LoadedFileFillsTheSiteTheReplayBoardHandsTheFirmware) {
  dataset::Recording rec;
  std::string err;
  ASSERT_TRUE(ok(sim::simulate("parking_los", 3, rec, &err))) << err;
  rec.uwb.resize(rec.uwb.size() / 20);
  rec.imu.resize(rec.imu.size() / 20);
  const SiteConfig& s = rec.site;
  std::string text = std::string(dataset::kCalibrationMagic) + "\nsite_sigma_m = 0.006\nanchor_id,tag_id,offset_m,sigma_m\n";
  for (size_t a = s.num_anchors; a-- > 0;) {  // rows in reverse order: the file order must not matter
    char row[80];
    std::snprintf(row, sizeof row, "%u,%u,%.4f,0.005\n", static_cast<unsigned>(s.anchors[a].id),
                  static_cast<unsigned>(s.tags[0].id), 0.1 + 0.05 * static_cast<double>(a));
    text += row;
  }
  const std::string path = (std::filesystem::temp_directory_path() / "uwbnav_site_calibration_test.cal").string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(std::fwrite(text.data(), 1, text.size(), f), text.size());
  std::fclose(f);

  std::vector<std::string> errors;
  ASSERT_EQ(dataset::load_calibration(path, rec.site, errors), Status::kOk) << errors.at(0);
  EXPECT_FLOAT_EQ(rec.site.range_offset_sigma_m, 0.006F);
  for (size_t a = 0; a < s.num_anchors; ++a) {
    EXPECT_FLOAT_EQ(rec.site.range_offset_m[a][0], static_cast<float>(0.1 + 0.05 * static_cast<double>(a))) << a;
  }
  // The replay board passes this site to App::init: a calibrated replay runs.
  eval::ReplayResult result;
  ASSERT_EQ(eval::run_replay(rec, eval::ReplayOptions{}, result, &err), Status::kOk) << err;
  EXPECT_GT(result.estimates.size(), 100U);
  // An unusable calibration stops the replay at start-up with a reason.
  rec.site.range_offset_m[0][0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(eval::run_replay(rec, eval::ReplayOptions{}, result, &err), Status::kOk);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace uwbnav
