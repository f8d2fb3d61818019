// Writes the seed corpora of the fuzz targets that need well-formed binary
// input (valid E2E-protected CAN frames, parameter blobs with a good CRC, a
// plausible IMU/UWB sequence): `fuzz_make_seeds CORPUS_DIR`. The text seeds
// (recording files, console lines) come from make_seeds.py.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "estimator/params.hpp"
#include "firmware/can/sensor_decoder.hpp"
#include "firmware/param_blob.hpp"

namespace {

using Bytes = std::vector<uint8_t>;

bool write(const std::string& path, const Bytes& b) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool good = std::fwrite(b.data(), 1, b.size(), f) == b.size();
  return std::fclose(f) == 0 && good;
}

void u16(Bytes& b, int v) {
  const auto u = static_cast<uint16_t>(static_cast<int16_t>(v));
  b.push_back(static_cast<uint8_t>(u & 0xFFU));
  b.push_back(static_cast<uint8_t>(u >> 8));
}

// fuzz_can_decoder records: selector, len, flags, dt [ms], payload.
void frame(Bytes& b, const uwbnav::hal::CanFrame& f, uint8_t dt_ms) {
  // The selector table of tests/fuzz/fuzz_can_decoder.cpp.
  static constexpr uint32_t kIds[] = {0x0A0, 0x0A1, 0x0A2, 0x0B0, 0x0B1, 0x100, 0x105,
                                      0x0C0, 0x0C1, 0x0C2, 0x0C3, 0x0C4, 0x0C5, 0x110,
                                      0x0D0, 0x0D1, 0x0D2, 0x0D3, 0x0D4};
  uint8_t sel = 0;
  for (uint8_t i = 0; i < sizeof kIds / sizeof kIds[0]; ++i) {
    if (kIds[i] == f.id) sel = i;
  }
  b.push_back(sel);
  b.push_back(f.len);
  b.push_back(f.flags);
  b.push_back(dt_ms);
  b.insert(b.end(), f.data, f.data + f.len);
}

Bytes can_seed(size_t n) {
  using namespace uwbnav;
  can::CanSensorEncoder enc;
  Bytes b;
  for (size_t i = 0; i < n; ++i) {
    ImuSample s;
    s.t_us = 1000000 + i * 4000;
    s.accel_body_mps2 = Vec3f{0.1F, -0.05F, 9.81F};
    s.gyro_body_radps = Vec3f{0.001F, 0.0F, 0.02F};
    hal::CanFrame imu[can::kImuFrames];
    (void)enc.encode_imu(s, imu);
    for (const auto& f : imu) frame(b, f, 0);
    if (i % 4 == 0) {
      UwbRange r;
      r.t_us = s.t_us;
      r.anchor_id = static_cast<uint16_t>(1 + i % 4);
      r.range_m = 12.5F + 0.01F * static_cast<float>(i);
      r.fp_power_dbm = -82.0F;
      r.rx_power_dbm = -79.5F;
      hal::CanFrame uwb[can::kUwbFrames];
      (void)enc.encode_uwb(r, uwb);
      for (const auto& f : uwb) frame(b, f, 1);
    }
  }
  return b;
}

#if UWBNAV_COOP
// V2X_Neighbour groups of `n` states from three vehicles in turn (10 Hz each,
// one with velocity not reported, one cooperative), interleaved with HIL IMU
// samples when `with_imu`; the last group misses a part.
Bytes neighbour_seed(size_t n, bool with_imu) {
  using namespace uwbnav;
  can::CanSensorEncoder enc;
  Bytes b;
  uint8_t counter = 0;
  for (size_t i = 0; i < n; ++i) {
    NeighbourState s;
    s.t_us = 1000000 + i * 33000;
    s.vehicle_id = static_cast<uint16_t>(kFirstVehicleId + 1 + i % 3);
    const float a = 0.05F * static_cast<float>(i);
    s.pos_nav_m = Vec3f{15.0F + 10.0F * std::cos(a), 15.0F + 10.0F * std::sin(a), 1.2F};
    s.vel_nav_mps = i % 3 == 1 ? Vec3f{kNaNf, kNaNf, kNaNf} : Vec3f{-0.5F * std::sin(a), 0.5F * std::cos(a), 0.0F};
    const float sx = 0.05F + 0.01F * static_cast<float>(i % 4), sy = 0.07F, sz = 0.3F;
    s.cov_pos_m2[0] = sx * sx;
    s.cov_pos_m2[1] = 0.2F * sx * sy;
    s.cov_pos_m2[2] = 0.0F;
    s.cov_pos_m2[3] = sy * sy;
    s.cov_pos_m2[4] = 0.0F;
    s.cov_pos_m2[5] = sz * sz;
    s.cooperative = i % 3 == 2;
    hal::CanFrame g[can::kCoopFrames];
    (void)can::encode_coop(s, can::CoopGroup::kNeighbour, counter, g);
    counter = can::next_alive_counter(counter);
    for (size_t k = 0; k < can::kCoopFrames; ++k) {
      if (i + 1 == n && k == 3) continue;  // a lost part: incomplete group
      frame(b, g[k], k == 0 ? 11 : 0);
      if (with_imu && k == 2) {
        ImuSample m;
        m.t_us = s.t_us;
        m.accel_body_mps2 = Vec3f{0.1F, -0.05F, 9.81F};
        m.gyro_body_radps = Vec3f{0.001F, 0.0F, 0.02F};
        hal::CanFrame imu[can::kImuFrames];
        (void)enc.encode_imu(m, imu);
        for (const auto& f : imu) frame(b, f, 0);
      }
    }
  }
  return b;
}
#endif

#if UWBNAV_GNSS
// GNSS_Fix groups: `n` fixes at 5 Hz (RTK float, one without velocity), then a
// no-fix group, then a group whose last part is lost.
Bytes gnss_seed(size_t n) {
  using namespace uwbnav;
  Bytes b;
  uint8_t counter = 0;
  for (size_t i = 0; i < n + 2; ++i) {
    GnssFix f;
    f.t_us = 1000000 + i * 200000;
    f.pos_nav_m = Vec3f{5.0F + 1.0F * static_cast<float>(i), 15.0F, 1.7F};
    f.pos_sigma_m = Vec3f{0.3F, 0.3F, 0.6F};
    f.vel_nav_mps = i % 4 == 3 ? Vec3f{kNaNf, kNaNf, kNaNf} : Vec3f{5.0F, 0.0F, 0.0F};
    f.vel_sigma_mps = i % 4 == 3 ? kNaNf : 0.05F;
    f.fix = i == n ? GnssFixType::kNone : GnssFixType::kRtkFloat;
    f.num_sv = 14;
    hal::CanFrame g[can::kGnssFrames];
    (void)can::encode_gnss(f, counter, g);
    counter = can::next_alive_counter(counter);
    for (size_t k = 0; k < can::kGnssFrames; ++k) {
      if (i == n + 1 && k == can::kGnssFrames - 1) continue;  // a lost part: incomplete group
      frame(b, g[k], k == 0 ? 100 : 0);
    }
  }
  return b;
}
#endif

// fuzz_sequence: a vehicle in the 30 m anchor square driving along +x at
// `speed_mps` from (5, 15, 0) (heading 0, so an IMU at constant velocity reads
// gravity only), IMU every 10 ms, a range every 25 ms (anchors 1..4 in turn).
// Moving, the filter acquires its heading and reaches status valid.
// With `with_gnss` the antenna (1.2 m mast, 0.5 m ahead) sends a DGNSS fix
// every 200 ms, 100 ms late, with velocity. With `with_neighbours` a car
// (0x8001) parked with its tag at (20, 5, 1) broadcasts its state every 100 ms,
// 40 ms late, and is ranged every 100 ms.
Bytes sequence_seed(bool with_imu, double seconds, double speed_mps, bool with_gnss = false,
                    bool with_neighbours = false) {
  Bytes b;
  b.push_back(static_cast<uint8_t>((with_imu ? 1 : 0) | (with_gnss ? 4 : 0)));
  const double ax[4] = {0, 30, 30, 0};
  const double ay[4] = {0, 0, 30, 30};
  const int steps = static_cast<int>(seconds * 1000.0);
  int since = 0;
  int anchor = 0;
  for (int ms = 0; ms < steps; ++ms) {
    ++since;
    if (with_imu && ms % 10 == 0) {
      b.push_back(static_cast<uint8_t>(since << 2));  // IMU, step `since` ms
      since = 0;
      u16(b, 0);
      u16(b, 0);
      u16(b, 0);  // az = 9.80665
      u16(b, 0);
      u16(b, 0);
      u16(b, 0);
    }
    if (with_gnss && ms % 200 == 100) {
      b.push_back(static_cast<uint8_t>((since << 2) | 1));
      since = 0;
      b.push_back(193);  // GNSS fix with velocity
      const double x = 5.0 + speed_mps * ms * 1e-3 + 0.5;
      u16(b, static_cast<int>(std::lround(x * 100.0)));
      u16(b, 1500);
      u16(b, 120);
      b.push_back(9);   // sigma_h 0.5 m
      b.push_back(19);  // sigma_v 1.0 m
      b.push_back(50);  // 100 ms latency
      u16(b, static_cast<int>(std::lround(speed_mps * 100.0)));
      u16(b, 0);
      u16(b, 0);
      b.push_back(9);   // 0.1 m/s
      b.push_back(2);   // DGNSS
      b.push_back(11);  // satellites
    }
    if (with_neighbours && ms % 100 == 50) {
      b.push_back(static_cast<uint8_t>((since << 2) | 1));
      since = 0;
      b.push_back(128);  // state of 0x8001, with velocity
      u16(b, 2000);
      u16(b, 500);
      u16(b, 100);
      b.push_back(10);  // sigma_h 0.1 m
      b.push_back(20);  // sigma_v 0.2 m
      b.push_back(0);   // rho_xy 0
      b.push_back(10);  // 40 ms latency
      u16(b, 0);
      u16(b, 0);
      u16(b, 0);
    }
    if (with_neighbours && ms % 100 == 60) {
      b.push_back(static_cast<uint8_t>((since << 2) | 1));
      since = 0;
      b.push_back(160);  // range to 0x8001's tag from tag 0
      const double x = 5.0 + speed_mps * ms * 1e-3;
      const double r = std::sqrt((x - 20.0) * (x - 20.0) + 100.0);
      u16(b, static_cast<int>(std::lround(r * 1000.0)));
      b.push_back(164);
      b.push_back(159);
    }
    if (ms % 25 == 0) {
      b.push_back(static_cast<uint8_t>((since << 2) | 1));
      since = 0;
      b.push_back(static_cast<uint8_t>(anchor + 1));
      const double x = 5.0 + speed_mps * ms * 1e-3;
      const double r = std::sqrt((x - ax[anchor]) * (x - ax[anchor]) + (15 - ay[anchor]) * (15 - ay[anchor]) + 1.0);
      u16(b, static_cast<int>(std::lround(r * 1000.0)));  // < 32.7 m: fits the signed 16-bit writer
      b.push_back(164);  // fp -82 dBm
      b.push_back(159);  // rx -79.5 dBm
      anchor = (anchor + 1) % 4;
    }
  }
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace uwbnav;
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds CORPUS_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  bool good = write(dir + "/fuzz_can_decoder/imu_uwb_valid", can_seed(24));
#if UWBNAV_COOP
  good = good && write(dir + "/fuzz_can_decoder/neighbour_valid", neighbour_seed(8, false));
  good = good && write(dir + "/fuzz_can_decoder/neighbour_imu_interleaved", neighbour_seed(6, true));
#endif
#if UWBNAV_GNSS
  good = good && write(dir + "/fuzz_can_decoder/gnss_fixes", gnss_seed(5));
#endif
  Params p;
  uint8_t blob[kParamBlobMaxBytes];
  size_t n = param_blob_write(p, blob, sizeof blob);
  good = good && write(dir + "/fuzz_param_blob/defaults", Bytes(blob, blob + n));
  if (!ok(p.set(kParamDefs[0].index, kParamDefs[0].max))) return 1;
  n = param_blob_write(p, blob, sizeof blob);
  good = good && write(dir + "/fuzz_param_blob/first_at_max", Bytes(blob, blob + n));
  good = good && write(dir + "/fuzz_sequence/static_imu_uwb", sequence_seed(true, 6.0, 2.0));
  good = good && write(dir + "/fuzz_sequence/static_uwb_only", sequence_seed(false, 3.0, 0.0));
  good = good && write(dir + "/fuzz_sequence/drive_imu_uwb_gnss", sequence_seed(true, 6.0, 2.0, true));
#if UWBNAV_COOP
  good = good && write(dir + "/fuzz_sequence/drive_imu_uwb_neighbour", sequence_seed(true, 6.0, 2.0, false, true));
#endif
  if (!good) {
    std::fprintf(stderr, "fuzz_make_seeds: cannot write under %s (create the target folders)\n", dir.c_str());
    return 1;
  }
  return 0;
}
