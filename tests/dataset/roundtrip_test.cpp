// Format v1 writer/reader round trips: read(write(x)) reproduces every
// estimator input bit for bit (GNSS fixes and lever, neighbour states included); replay outputs
// read back; a one-hour IMU loads fast.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tests/dataset/dataset_test_util.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::dataset {
namespace {

using testutil::dump;
using testutil::read_text;
using testutil::scratch_dir;

bool same_bits(float a, float b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// A recording with awkward values: tiny/huge magnitudes, negative zero,
// non-decimal floats, ties in time, every optional field used somewhere.
Recording make_recording(std::mt19937& rng, size_t n_imu, size_t n_uwb) {
  std::uniform_real_distribution<float> uni(-50.0F, 50.0F);
  std::uniform_int_distribution<int> coin(0, 3);
  Recording rec;
  rec.meta["name"] = "roundtrip";
  rec.meta["description"] = "synthetic, with = signs and unicode \xC2\xB0";
  rec.meta["imu_rate_hz"] = "100";
  rec.site.platform = Platform::kAir;
  rec.site.gravity_mps2 = 9.7803253F;
  rec.meta["uwb_sigma_m"] = "0.123456789";
  for (uint16_t i = 0; i < 5; ++i) {
    EXPECT_EQ(rec.site.add_anchor(static_cast<uint16_t>(i * 1000U + 7U), Vec3f{uni(rng), uni(rng), uni(rng) / 7.0F}),
              Status::kOk);
  }
  EXPECT_EQ(rec.site.add_tag(0, Vec3f{0.1F, -0.2F, 1.0F / 3.0F}), Status::kOk);
  EXPECT_EQ(rec.site.add_tag(200, Vec3f{-0.0F, 1e-8F, 3.4e38F}), Status::kOk);
  uint64_t t_us = 1723710007000000ULL;  // Unix-time scale stamps must survive too
  for (size_t i = 0; i < n_imu; ++i) {
    t_us += (i % 10 == 3) ? 0 : 9999;
    ImuSample s;
    s.t_us = t_us;
    s.accel_body_mps2 = Vec3f{uni(rng), uni(rng) * 1e-7F, 9.80665F + uni(rng) / 3.0F};
    s.gyro_body_radps = Vec3f{uni(rng) / 1e3F, -0.0F, std::nextafter(1.0F, 2.0F)};
    rec.imu.push_back(s);
  }
  t_us = 1723710007000001ULL;
  for (size_t i = 0; i < n_uwb; ++i) {
    t_us += (i % 4 == 1) ? 0 : 20001;
    UwbRow r;
    r.range.t_us = t_us;
    r.range.anchor_id = rec.site.anchors[i % rec.site.num_anchors].id;
    r.range.tag_id = (i % 3 == 0) ? 200 : 0;
    r.range.range_m = std::fabs(uni(rng)) / 3.0F;
    r.nlos_label = static_cast<int8_t>(coin(rng) - 1 < 0 ? -1 : coin(rng) % 2);
    r.range.fp_power_dbm = coin(rng) == 0 ? kNaNf : -80.0F + uni(rng) / 9.0F;
    r.range.rx_power_dbm = coin(rng) == 0 ? kNaNf : -78.0F + uni(rng) / 9.0F;
    rec.uwb.push_back(r);
  }
  for (size_t i = 0; i < 50; ++i) {
    TruthRow t;
    t.t_us = 1723710007000000ULL + i * 125000U;
    t.pos_nav_m[0] = 1.0 / 3.0 + static_cast<double>(i);
    t.pos_nav_m[1] = -1e-12;
    t.pos_nav_m[2] = 123456.789012345678;
    t.has_attitude = i % 5 != 0;
    if (t.has_attitude) {
      t.q_nav_body[0] = std::sqrt(0.5);
      t.q_nav_body[3] = -std::sqrt(0.5);
    }
    rec.truth.push_back(t);
  }
  return rec;
}

void expect_same(const Recording& a, const Recording& b) {
  ASSERT_EQ(a.site.num_anchors, b.site.num_anchors);
  for (size_t i = 0; i < a.site.num_anchors; ++i) {
    EXPECT_EQ(a.site.anchors[i].id, b.site.anchors[i].id);
    EXPECT_TRUE(same_bits(a.site.anchors[i].pos_nav_m.x, b.site.anchors[i].pos_nav_m.x));
    EXPECT_TRUE(same_bits(a.site.anchors[i].pos_nav_m.y, b.site.anchors[i].pos_nav_m.y));
    EXPECT_TRUE(same_bits(a.site.anchors[i].pos_nav_m.z, b.site.anchors[i].pos_nav_m.z));
  }
  ASSERT_EQ(a.site.num_tags, b.site.num_tags);
  for (size_t i = 0; i < a.site.num_tags; ++i) {
    EXPECT_EQ(a.site.tags[i].id, b.site.tags[i].id);
    EXPECT_TRUE(same_bits(a.site.tags[i].lever_body_m.x, b.site.tags[i].lever_body_m.x));
    EXPECT_TRUE(same_bits(a.site.tags[i].lever_body_m.y, b.site.tags[i].lever_body_m.y));
    EXPECT_TRUE(same_bits(a.site.tags[i].lever_body_m.z, b.site.tags[i].lever_body_m.z));
  }
  EXPECT_EQ(a.site.platform, b.site.platform);
  EXPECT_TRUE(same_bits(a.site.gravity_mps2, b.site.gravity_mps2));
  EXPECT_EQ(a.meta.count("uwb_sigma_m"), b.meta.count("uwb_sigma_m"));
  if (a.meta.count("uwb_sigma_m") != 0 && b.meta.count("uwb_sigma_m") != 0) {
    EXPECT_EQ(a.meta.at("uwb_sigma_m"), b.meta.at("uwb_sigma_m"));
  }
  EXPECT_EQ(a.site.has_imu, b.site.has_imu);
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (size_t i = 0; i < a.imu.size(); ++i) {
    const ImuSample& x = a.imu[i];
    const ImuSample& y = b.imu[i];
    ASSERT_EQ(x.t_us, y.t_us) << i;
    ASSERT_TRUE(same_bits(x.accel_body_mps2.x, y.accel_body_mps2.x) &&
                same_bits(x.accel_body_mps2.y, y.accel_body_mps2.y) &&
                same_bits(x.accel_body_mps2.z, y.accel_body_mps2.z) &&
                same_bits(x.gyro_body_radps.x, y.gyro_body_radps.x) &&
                same_bits(x.gyro_body_radps.y, y.gyro_body_radps.y) &&
                same_bits(x.gyro_body_radps.z, y.gyro_body_radps.z))
        << "imu row " << i;
  }
  ASSERT_EQ(a.uwb.size(), b.uwb.size());
  for (size_t i = 0; i < a.uwb.size(); ++i) {
    const UwbRow& x = a.uwb[i];
    const UwbRow& y = b.uwb[i];
    ASSERT_EQ(x.range.t_us, y.range.t_us) << i;
    ASSERT_EQ(x.range.anchor_id, y.range.anchor_id) << i;
    ASSERT_EQ(x.range.tag_id, y.range.tag_id) << i;
    ASSERT_EQ(x.nlos_label, y.nlos_label) << i;
    ASSERT_TRUE(same_bits(x.range.range_m, y.range.range_m) &&
                same_bits(x.range.fp_power_dbm, y.range.fp_power_dbm) &&
                same_bits(x.range.rx_power_dbm, y.range.rx_power_dbm))
        << "uwb row " << i;
  }
  ASSERT_EQ(a.truth.size(), b.truth.size());
  for (size_t i = 0; i < a.truth.size(); ++i) {
    EXPECT_EQ(a.truth[i].t_us, b.truth[i].t_us);
    EXPECT_EQ(a.truth[i].has_attitude, b.truth[i].has_attitude);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.truth[i].pos_nav_m[k], b.truth[i].pos_nav_m[k]);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(a.truth[i].q_nav_body[k], b.truth[i].q_nav_body[k]);
  }
}

TEST(DatasetRoundTrip, ReadOfWriteReproducesEstimatorInputsBitForBit) {
  std::mt19937 rng(42);
  const Recording rec = make_recording(rng, 3000, 2000);
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_EQ(rep.rows_skipped, 0U) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  expect_same(rec, back);
  for (const auto& kv : rec.meta) EXPECT_EQ(back.meta[kv.first], kv.second) << kv.first;
  EXPECT_EQ(back.name(), "roundtrip");

  // Written again from what was read: byte-identical files.
  const std::string dir2 = dir + "/again";
  ASSERT_EQ(write_recording(dir2, back), Status::kOk);
  for (const char* f : {"anchors.csv", "tags.csv", "uwb.csv", "imu.csv", "truth.csv", "meta.ini"}) {
    EXPECT_EQ(read_text(dir + "/" + f), read_text(dir2 + "/" + f)) << f;
  }
}

TEST(DatasetRoundTrip, OptionalUwbColumnsWrittenOnlyUpToTheLastOneUsed) {
  Recording rec;
  rec.site.has_imu = false;
  ASSERT_EQ(rec.site.add_anchor(1, Vec3f{1, 2, 3}), Status::kOk);
  ASSERT_EQ(rec.site.add_tag(0, Vec3f{}), Status::kOk);
  UwbRow r;
  r.range.t_us = 1000;
  r.range.anchor_id = 1;
  r.range.range_m = 4.25F;
  rec.uwb.push_back(r);
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/uwb.csv"), "t_s,anchor_id,range_m\n0.001000,1,4.25\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/imu.csv")) << "UWB-only recording has no imu.csv";
  EXPECT_FALSE(std::filesystem::exists(dir + "/truth.csv"));

  rec.uwb[0].range.fp_power_dbm = -80.5F;
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/uwb.csv"),
            "t_s,anchor_id,range_m,tag_id,nlos,fp_power_dbm\n0.001000,1,4.25,0,,-80.5\n");
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_FALSE(back.site.has_imu);
  expect_same(rec, back);
}

TEST(DatasetRoundTrip, WriterRemovesOptionalFilesTheRecordingLacks) {
  std::mt19937 rng(7);
  Recording rec = make_recording(rng, 10, 10);
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  rec.imu.clear();
  rec.truth.clear();
  rec.site.has_imu = false;
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(back.imu.empty());
  EXPECT_TRUE(back.truth.empty());
  EXPECT_FALSE(back.site.has_imu);
}

TEST(DatasetRoundTrip, OneHourOfImuAt100HzLoadsInWellUnderASecond) {
  std::mt19937 rng(3);
  const Recording rec = make_recording(rng, 360000, 180000);
  const std::string dir = scratch_dir();
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  const auto t1 = std::chrono::steady_clock::now();
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  const auto t2 = std::chrono::steady_clock::now();
  const double write_s = std::chrono::duration<double>(t1 - t0).count();
  const double read_s = std::chrono::duration<double>(t2 - t1).count();
  std::printf("360k IMU + 180k UWB rows: write %.3f s, read %.3f s\n", write_s, read_s);
  EXPECT_EQ(back.imu.size(), 360000U);
  EXPECT_EQ(back.uwb.size(), 180000U);
  // Generous bound so sanitizer/debug builds pass; Release reads in ~0.2 s.
  EXPECT_LT(read_s, 5.0);
}

// Fixes with every optional field used somewhere; latencies vary so the
// arrival order differs from the validity order. In arrival order, as the
// reader returns them.
std::vector<GnssFix> make_gnss() {
  std::vector<GnssFix> fixes;
  const uint64_t t0_us = 1723710007000000ULL;
  for (uint64_t k = 0; k < 40; ++k) {
    GnssFix f;
    f.t_us = t0_us + k * 200000U;
    f.rx_t_us = f.t_us + (k % 3 == 0 ? 310000U : 45000U + k * 1000U);
    f.pos_nav_m = Vec3f{1.0F / 3.0F + static_cast<float>(k), -123.456F, 0.1F * static_cast<float>(k % 7)};
    f.pos_sigma_m = Vec3f{0.8F, 0.8125F, 1.7F};
    if (k % 4 != 1) {
      f.vel_nav_mps = Vec3f{2.5F, -0.0F, 1e-7F};
      f.vel_sigma_mps = k % 4 == 2 ? kNaNf : 0.05F;
    }
    f.fix = k % 5 == 0 ? GnssFixType::kRtkFloat : k % 5 == 1 ? GnssFixType::kRtkFixed : GnssFixType::kDgnss;
    f.num_sv = static_cast<uint8_t>(k % 2 == 0 ? 0 : 4 + k);
    fixes.push_back(f);
  }
  std::stable_sort(fixes.begin(), fixes.end(),
                   [](const GnssFix& a, const GnssFix& b) { return a.rx_t_us < b.rx_t_us; });
  return fixes;
}

void expect_same_gnss(const std::vector<GnssFix>& a, const std::vector<GnssFix>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    const GnssFix& x = a[i];
    const GnssFix& y = b[i];
    ASSERT_EQ(x.t_us, y.t_us) << i;
    ASSERT_EQ(x.rx_t_us, y.rx_t_us) << i;
    ASSERT_EQ(x.fix, y.fix) << i;
    ASSERT_EQ(x.num_sv, y.num_sv) << i;
    ASSERT_TRUE(same_bits(x.pos_nav_m.x, y.pos_nav_m.x) && same_bits(x.pos_nav_m.y, y.pos_nav_m.y) &&
                same_bits(x.pos_nav_m.z, y.pos_nav_m.z) && same_bits(x.pos_sigma_m.x, y.pos_sigma_m.x) &&
                same_bits(x.pos_sigma_m.y, y.pos_sigma_m.y) && same_bits(x.pos_sigma_m.z, y.pos_sigma_m.z) &&
                same_bits(x.vel_nav_mps.x, y.vel_nav_mps.x) && same_bits(x.vel_nav_mps.y, y.vel_nav_mps.y) &&
                same_bits(x.vel_nav_mps.z, y.vel_nav_mps.z) && same_bits(x.vel_sigma_mps, y.vel_sigma_mps))
        << "gnss fix " << i;
  }
}

TEST(DatasetRoundTripGnss, GnssFixesAndAntennaLeverReadBackBitForBitInArrivalOrder) {
  std::mt19937 rng(11);
  Recording rec = make_recording(rng, 200, 100);
  rec.gnss = make_gnss();
  rec.site.gnss_lever_body_m = Vec3f{1.25F, -0.1F, 1.0F / 3.0F};
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  const std::string text = read_text(dir + "/gnss.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s,vx_mps,vy_mps,vz_mps,sv_mps");
  EXPECT_NE(read_text(dir + "/meta.ini").find("gnss_lever_m = 1.25,-0.1,0.33333334\n"), std::string::npos)
      << read_text(dir + "/meta.ini");

  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  expect_same(rec, back);
  expect_same_gnss(rec.gnss, back.gnss);
  EXPECT_TRUE(same_bits(back.site.gnss_lever_body_m.x, 1.25F));
  EXPECT_TRUE(same_bits(back.site.gnss_lever_body_m.y, -0.1F));
  EXPECT_TRUE(same_bits(back.site.gnss_lever_body_m.z, 1.0F / 3.0F));

  // Written again from what was read: byte-identical files.
  const std::string dir2 = dir + "/again";
  ASSERT_EQ(write_recording(dir2, back), Status::kOk);
  for (const char* f : {"gnss.csv", "meta.ini"}) EXPECT_EQ(read_text(dir + "/" + f), read_text(dir2 + "/" + f)) << f;
}

TEST(DatasetRoundTripGnss, OptionalGnssColumnsWrittenOnlyUpToTheLastOneUsed) {
  Recording rec;
  ASSERT_EQ(rec.site.add_anchor(1, Vec3f{1, 2, 3}), Status::kOk);
  ASSERT_EQ(rec.site.add_tag(0, Vec3f{}), Status::kOk);
  GnssFix f;
  f.t_us = 2000000;
  f.rx_t_us = f.t_us;
  f.pos_nav_m = Vec3f{10.5F, -4.0F, 0.25F};
  f.pos_sigma_m = Vec3f{0.5F, 0.5F, 1.0F};
  rec.gnss.push_back(f);
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/gnss.csv"), "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m\n2.000000,10.5,-4,0.25,0.5,0.5,1\n");
  EXPECT_NE(read_text(dir + "/meta.ini").find("gnss_lever_m = 0,0,0\n"), std::string::npos)
      << "a receiver at the body origin still says so";

  rec.gnss[0].rx_t_us += 80000;
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/gnss.csv"),
            "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s\n2.000000,10.5,-4,0.25,0.5,0.5,1,1,0,0.080000\n");
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  expect_same_gnss(rec.gnss, back.gnss);

  // Velocity on one fix only: the others get three empty cells, never a partial velocity.
  GnssFix g = rec.gnss[0];
  g.t_us += 200000;
  g.rx_t_us += 200000;
  g.vel_nav_mps = Vec3f{1.0F, 2.0F, 0.0F};
  rec.gnss.push_back(g);
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/gnss.csv"),
            "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s,vx_mps,vy_mps,vz_mps\n"
            "2.000000,10.5,-4,0.25,0.5,0.5,1,1,0,0.080000,,,\n"
            "2.200000,10.5,-4,0.25,0.5,0.5,1,1,0,0.080000,1,2,0\n");
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  expect_same_gnss(rec.gnss, back.gnss);
}

TEST(DatasetRoundTripGnss, RecordingWithoutGnssWritesNoGnssFileNoLeverAndRemovesAStaleOne) {
  std::mt19937 rng(5);
  Recording rec = make_recording(rng, 10, 10);
  rec.gnss = make_gnss();
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  ASSERT_TRUE(std::filesystem::exists(dir + "/gnss.csv"));
  rec.gnss.clear();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_FALSE(std::filesystem::exists(dir + "/gnss.csv"));
  EXPECT_EQ(read_text(dir + "/meta.ini").find("gnss_lever_m"), std::string::npos)
      << "meta.ini of a recording without a receiver is as before";
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(back.gnss.empty());
}

// Neighbour states of three vehicles with every optional field used somewhere;
// latencies vary so the arrival order differs from the validity order. In
// arrival order, as the reader returns them.
std::vector<NeighbourState> make_neighbours() {
  std::vector<NeighbourState> states;
  const uint64_t t0_us = 1723710007000000ULL;
  for (uint64_t k = 0; k < 60; ++k) {
    NeighbourState n;
    n.vehicle_id = static_cast<uint16_t>(k % 3 == 2 ? 0xFFFE : kFirstVehicleId + k % 3);
    n.t_us = t0_us + (k / 3) * 100000U + (k % 3) * 7U;
    n.rx_t_us = n.t_us + (k % 4 == 0 ? 230000U : 20000U + k * 1000U);
    n.pos_nav_m = Vec3f{1.0F / 3.0F + static_cast<float>(k), -123.456F, 0.1F * static_cast<float>(k % 7)};
    const float cov[6] = {0.01F + 1e-4F * static_cast<float>(k), -0.0F, 1e-7F, 0.0225F, 0.003F, 0.09F};
    for (size_t i = 0; i < 6; ++i) n.cov_pos_m2[i] = cov[i];
    if (k % 5 != 1) n.vel_nav_mps = Vec3f{2.5F, -0.0F, 1e-7F * static_cast<float>(k)};
    n.cooperative = k % 7 == 3;
    states.push_back(n);
  }
  std::stable_sort(states.begin(), states.end(),
                   [](const NeighbourState& a, const NeighbourState& b) { return a.rx_t_us < b.rx_t_us; });
  return states;
}

void expect_same_neighbours(const std::vector<NeighbourState>& a, const std::vector<NeighbourState>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    const NeighbourState& x = a[i];
    const NeighbourState& y = b[i];
    ASSERT_EQ(x.t_us, y.t_us) << i;
    ASSERT_EQ(x.rx_t_us, y.rx_t_us) << i;
    ASSERT_EQ(x.vehicle_id, y.vehicle_id) << i;
    ASSERT_EQ(x.cooperative, y.cooperative) << i;
    ASSERT_TRUE(same_bits(x.pos_nav_m.x, y.pos_nav_m.x) && same_bits(x.pos_nav_m.y, y.pos_nav_m.y) &&
                same_bits(x.pos_nav_m.z, y.pos_nav_m.z) && same_bits(x.vel_nav_mps.x, y.vel_nav_mps.x) &&
                same_bits(x.vel_nav_mps.y, y.vel_nav_mps.y) && same_bits(x.vel_nav_mps.z, y.vel_nav_mps.z))
        << "neighbour state " << i;
    for (size_t c = 0; c < 6; ++c) ASSERT_TRUE(same_bits(x.cov_pos_m2[c], y.cov_pos_m2[c])) << i << " cov " << c;
  }
}

TEST(DatasetRoundTripNeighbours, NeighbourStatesReadBackBitForBitInArrivalOrder) {
  std::mt19937 rng(13);
  Recording rec = make_recording(rng, 200, 100);
  rec.uwb[3].range.anchor_id = kFirstVehicleId;  // a range to a vehicle's tag
  rec.uwb[4].range.anchor_id = 0xFFFE;
  rec.neighbours = make_neighbours();
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  const std::string text = read_text(dir + "/neighbours.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps,coop");

  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(rep.warnings.empty()) << dump(rep);
  expect_same(rec, back);
  expect_same_neighbours(rec.neighbours, back.neighbours);
  EXPECT_EQ(back.uwb[3].range.anchor_id, kFirstVehicleId);
  EXPECT_EQ(back.uwb[4].range.anchor_id, 0xFFFE);

  // Written again from what was read: byte-identical files.
  const std::string dir2 = dir + "/again";
  ASSERT_EQ(write_recording(dir2, back), Status::kOk);
  for (const char* f : {"neighbours.csv", "uwb.csv", "meta.ini"}) {
    EXPECT_EQ(read_text(dir + "/" + f), read_text(dir2 + "/" + f)) << f;
  }
}

TEST(DatasetRoundTripNeighbours, OptionalNeighbourColumnsWrittenOnlyUpToTheLastOneUsed) {
  Recording rec;
  ASSERT_EQ(rec.site.add_anchor(1, Vec3f{1, 2, 3}), Status::kOk);
  ASSERT_EQ(rec.site.add_tag(0, Vec3f{}), Status::kOk);
  NeighbourState n;
  n.t_us = 2000000;
  n.rx_t_us = n.t_us;
  n.vehicle_id = 32770;
  n.pos_nav_m = Vec3f{10.5F, -4.0F, 1.25F};
  const float cov[6] = {0.01F, 0.0F, 0.0F, 0.0225F, 0.0F, 0.25F};
  for (size_t i = 0; i < 6; ++i) n.cov_pos_m2[i] = cov[i];
  rec.neighbours.push_back(n);
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/neighbours.csv"),
            "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2\n"
            "2.000000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25\n");
  EXPECT_EQ(read_text(dir + "/meta.ini").find("gnss_lever_m"), std::string::npos);

  rec.neighbours[0].rx_t_us += 40000;
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/neighbours.csv"),
            "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s\n"
            "2.000000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25,0.040000\n");
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  expect_same_neighbours(rec.neighbours, back.neighbours);

  // Velocity on one state only: the others get three empty cells; coop written once one is cooperative.
  NeighbourState m = rec.neighbours[0];
  m.t_us += 100000;
  m.rx_t_us += 100000;
  m.vel_nav_mps = Vec3f{1.0F, 2.0F, 0.0F};
  rec.neighbours.push_back(m);
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/neighbours.csv"),
            "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps\n"
            "2.000000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25,0.040000,,,\n"
            "2.100000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25,0.040000,1,2,0\n");
  rec.neighbours[0].cooperative = true;
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_EQ(read_text(dir + "/neighbours.csv"),
            "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps,coop\n"
            "2.000000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25,0.040000,,,,1\n"
            "2.100000,32770,10.5,-4,1.25,0.01,0,0,0.0225,0,0.25,0.040000,1,2,0,0\n");
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  expect_same_neighbours(rec.neighbours, back.neighbours);
}

TEST(DatasetRoundTripNeighbours, RecordingWithoutNeighboursWritesNoFileAndRemovesAStaleOne) {
  std::mt19937 rng(5);
  Recording rec = make_recording(rng, 10, 10);
  rec.neighbours = make_neighbours();
  const std::string dir = scratch_dir();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  ASSERT_TRUE(std::filesystem::exists(dir + "/neighbours.csv"));
  rec.neighbours.clear();
  ASSERT_EQ(write_recording(dir, rec), Status::kOk);
  EXPECT_FALSE(std::filesystem::exists(dir + "/neighbours.csv"));
  Recording back;
  ReadReport rep;
  ASSERT_EQ(read_recording(dir, back, rep), Status::kOk) << dump(rep);
  EXPECT_TRUE(back.neighbours.empty());
}

TEST(DatasetOutputs, EstimatesWriteAndReadBack) {
  const std::string path = scratch_dir() + "/estimates.csv";
  EstimatesWriter w;
  NavOutput o;
  EXPECT_EQ(w.write(o), Status::kNotInitialised);
  ASSERT_EQ(w.open(path), Status::kOk);
  o.t_us = 10000;
  o.status = NavStatus::kDegraded;
  o.pos_nav_m = Vec3f{1.0F / 3.0F, -2.5F, 1e-9F};
  o.vel_nav_mps = Vec3f{0.1F, 0.2F, -0.0F};
  o.q_nav_body[0] = 0.70710677F;
  o.q_nav_body[3] = 0.70710677F;
  o.pos_sigma_m = Vec3f{0.05F, kNaNf, 0.3F};
  ASSERT_EQ(w.write(o), Status::kOk);
  o.t_us = 20000;
  o.status = NavStatus::kValid;
  ASSERT_EQ(w.write(o), Status::kOk);
  ASSERT_EQ(w.close(), Status::kOk);

  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,qw,qx,qy,qz,sx_m,sy_m,sz_m,status");
  EXPECT_NE(text.find(",0.05,,0.3,2\n"), std::string::npos) << text;

  std::vector<EstimateRow> rows;
  ReadReport rep;
  ASSERT_EQ(read_estimates(path, rows, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0].t_us, 10000U);
  EXPECT_EQ(rows[0].status, static_cast<int>(NavStatus::kDegraded));
  EXPECT_EQ(rows[1].status, static_cast<int>(NavStatus::kValid));
  EXPECT_EQ(static_cast<float>(rows[0].pos_nav_m[0]), 1.0F / 3.0F);
  EXPECT_EQ(static_cast<float>(rows[0].pos_nav_m[2]), 1e-9F);
  EXPECT_EQ(static_cast<float>(rows[0].q_nav_body[3]), 0.70710677F);
  EXPECT_TRUE(std::isnan(rows[0].pos_sigma_m[1]));
  EXPECT_EQ(static_cast<float>(rows[0].pos_sigma_m[2]), 0.3F);
}

TEST(DatasetOutputs, RangesWriteAndReadBackWithEmptyCellsForModelsThatDidNotRun) {
  const std::string path = scratch_dir() + "/ranges.csv";
  std::vector<RangeReport> in(3);
  in[0].t_us = 5;
  in[0].anchor_id = 12;
  in[0].tag_id = 1;
  in[0].range_m = 7.125F;
  in[0].innovation_m = -0.0625F;
  in[0].p_svm = 0.9F;
  in[0].p_mc = 0.25F;
  in[0].p_fused = 0.75F;
  in[0].nlos = true;
  in[1].t_us = 5;  // tie
  in[1].anchor_id = 3;
  in[1].range_m = 2.0F;
  in[1].used = true;
  in[2].t_us = 3600000000ULL;
  in[2].anchor_id = 65535;
  in[2].tag_id = 255;
  in[2].range_m = -20.5F;  // gross outliers can be negative
  in[2].innovation_m = 1e30F;
  {
    RangesWriter w;
    ASSERT_EQ(w.open(path), Status::kOk);
    for (const auto& r : in) ASSERT_EQ(w.write(r), Status::kOk);
  }  // destructor closes and flushes
  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "t_s,anchor_id,tag_id,range_m,innovation_m,p_svm,p_mc,p_fused,nlos,used");
  EXPECT_NE(text.find("\n0.000005,3,0,2,,,,,0,1\n"), std::string::npos) << text;

  std::vector<RangeReport> out;
  ReadReport rep;
  ASSERT_EQ(read_ranges(path, out, rep), Status::kOk) << dump(rep);
  ASSERT_EQ(out.size(), in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].t_us, in[i].t_us);
    EXPECT_EQ(out[i].anchor_id, in[i].anchor_id);
    EXPECT_EQ(out[i].tag_id, in[i].tag_id);
    EXPECT_TRUE(same_bits(out[i].range_m, in[i].range_m));
    EXPECT_TRUE(same_bits(out[i].innovation_m, in[i].innovation_m));
    EXPECT_TRUE(same_bits(out[i].p_svm, in[i].p_svm));
    EXPECT_TRUE(same_bits(out[i].p_mc, in[i].p_mc));
    EXPECT_TRUE(same_bits(out[i].p_fused, in[i].p_fused));
    EXPECT_EQ(out[i].nlos, in[i].nlos);
    EXPECT_EQ(out[i].used, in[i].used);
  }
}

TEST(DatasetOutputs, ReadersSkipBadRowsAndRejectWrongHeaders) {
  const std::string dir = scratch_dir();
  testutil::write_file(dir + "/ranges.csv",
                       "t_s,anchor_id,tag_id,range_m,innovation_m,p_svm,p_mc,p_fused,nlos,used\n"
                       "0.1,1,0,5,,,,,0,1\n"
                       "0.2,1,0,5,,,,,2,1\n"  // nlos must be 0/1
                       "0.3,1,0,,,,,,0,1\n");  // range_m required
  std::vector<RangeReport> out;
  ReadReport rep;
  ASSERT_EQ(read_ranges(dir + "/ranges.csv", out, rep), Status::kOk);
  EXPECT_EQ(out.size(), 1U);
  EXPECT_EQ(rep.rows_skipped, 2U);
  EXPECT_TRUE(testutil::has_warning(rep, "ranges.csv:3:", "nlos")) << dump(rep);
  EXPECT_TRUE(testutil::has_warning(rep, "ranges.csv:4:", "range_m")) << dump(rep);

  testutil::write_file(dir + "/estimates.csv", "t_s,x_m,y_m\n");
  std::vector<EstimateRow> est;
  rep = ReadReport{};
  EXPECT_EQ(read_estimates(dir + "/estimates.csv", est, rep), Status::kInvalidArgument);
  EXPECT_NE(rep.error.find("wrong header"), std::string::npos) << rep.error;
  EXPECT_EQ(read_estimates(dir + "/missing.csv", est, rep), Status::kNotFound);
}

}  // namespace
}  // namespace uwbnav::dataset
