// libFuzzer target: arbitrary IMU/UWB/GNSS/neighbour sequences through the firmware
// (App::tick: InputValidator, then the estimator). Whenever the output status
// says valid, position, velocity, attitude and claimed sigmas must be finite
// and bounded; anything else aborts (a finding).
// Input: 1 header byte (bit 0 has IMU, bit 1 air platform, bit 2 GNSS antenna
// on a 1.2 m mast), then records: 1 tag byte (bit 0 UWB or GNSS else IMU, bit 1
// raw float bits + signed time step, bits 2-7 time step [ms]) and its payload;
// a UWB record whose first payload byte is >= 192 is a GNSS fix, 128..159 a
// neighbour vehicle's state, 160..191 a range to a neighbour's tag
// (docs/hardening.md).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "firmware/app.hpp"
#include "tests/fuzz/fuzz_board.hpp"

namespace {

using uwbnav::fuzz::ByteReader;

constexpr uint64_t kStartUs = 1000000;
constexpr size_t kMaxTicks = 600;       // 6 s of loop per input at most (executions per second)
constexpr double kMaxPosM = 1e4;        // 10 km from the 30 m anchor square
constexpr double kMaxVelMps = 1e3;
constexpr double kMaxSigmaM = 1e6;

[[noreturn]] void finding(const char* what, const uwbnav::NavOutput& o) {
  std::fprintf(stderr, "fuzz_sequence: %s at t_us=%llu status=%s mode=%d pos=(%g,%g,%g) vel=(%g,%g,%g) q=(%g,%g,%g,%g) sigma=(%g,%g,%g)\n",
               what, static_cast<unsigned long long>(o.t_us), uwbnav::nav_status_name(o.status),
               static_cast<int>(o.mode), static_cast<double>(o.pos_nav_m.x), static_cast<double>(o.pos_nav_m.y),
               static_cast<double>(o.pos_nav_m.z), static_cast<double>(o.vel_nav_mps.x),
               static_cast<double>(o.vel_nav_mps.y), static_cast<double>(o.vel_nav_mps.z),
               static_cast<double>(o.q_nav_body[0]), static_cast<double>(o.q_nav_body[1]),
               static_cast<double>(o.q_nav_body[2]), static_cast<double>(o.q_nav_body[3]),
               static_cast<double>(o.pos_sigma_m.x), static_cast<double>(o.pos_sigma_m.y),
               static_cast<double>(o.pos_sigma_m.z));
  std::abort();
}

bool finite_within(const uwbnav::Vec3f& v, double bound) {
  const auto in = [bound](float c) { return std::isfinite(c) && std::fabs(static_cast<double>(c)) <= bound; };
  return in(v.x) && in(v.y) && in(v.z);
}

void check_output(const uwbnav::NavOutput& o) {
  if (o.status != uwbnav::NavStatus::kValid) return;
  if (!finite_within(o.pos_nav_m, kMaxPosM)) finding("valid output with position not finite or beyond 10 km", o);
  if (!finite_within(o.vel_nav_mps, kMaxVelMps)) finding("valid output with velocity not finite or beyond 1 km/s", o);
  if (!finite_within(o.pos_sigma_m, kMaxSigmaM) || o.pos_sigma_m.x < 0.0F || o.pos_sigma_m.y < 0.0F ||
      o.pos_sigma_m.z < 0.0F) {
    finding("valid output with position sigma not finite, negative or beyond 1000 km", o);
  }
  if (!finite_within(o.vel_sigma_mps, kMaxSigmaM)) finding("valid output with velocity sigma not finite", o);
  double n2 = 0.0;
  for (float q : o.q_nav_body) {
    if (!std::isfinite(q)) finding("valid output with attitude not finite", o);
    n2 += static_cast<double>(q) * static_cast<double>(q);
  }
  if (std::fabs(std::sqrt(n2) - 1.0) > 1e-3) finding("valid output with attitude quaternion not unit", o);
  if (!std::isfinite(o.heading_rad)) finding("valid output with heading not finite", o);
}

// One GNSS fix: position, claimed sigmas, arrival, fix type and satellites,
// velocity when `with_vel`. Scaled integers, or raw float bits (any value,
// arrival before validity included) when `raw`.
uwbnav::GnssFix gnss_record(ByteReader& in, uint64_t t_us, bool raw, bool with_vel) {
  using namespace uwbnav;
  GnssFix f;
  f.t_us = t_us;
  if (raw) {
    f.pos_nav_m = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
    f.pos_sigma_m = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
    const int64_t latency_us = static_cast<int64_t>(static_cast<int16_t>(in.u16())) * 100;
    f.rx_t_us = latency_us < 0 && static_cast<uint64_t>(-latency_us) > t_us ? 0 : t_us + static_cast<uint64_t>(latency_us);
    if (with_vel) {
      f.vel_nav_mps = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
      f.vel_sigma_mps = in.f32_bits();
    }
  } else {
    const auto p = [&] { return static_cast<float>(static_cast<int16_t>(in.u16())) * 0.01F; };
    const float x = p();
    const float y = p();
    const float z = p();
    f.pos_nav_m = Vec3f{x, y, z};
    const float sh = static_cast<float>(in.u8() + 1U) * 0.05F;
    const float sv = static_cast<float>(in.u8() + 1U) * 0.05F;
    f.pos_sigma_m = Vec3f{sh, sh, sv};
    f.rx_t_us = t_us + static_cast<uint64_t>(in.u8()) * 2000U;  // 0..510 ms latency
    if (with_vel) {
      const float vx = p();
      const float vy = p();
      const float vz = p();
      f.vel_nav_mps = Vec3f{vx, vy, vz};
      f.vel_sigma_mps = static_cast<float>(in.u8() + 1U) * 0.01F;
    }
  }
  const uint8_t q = in.u8();
  f.fix = static_cast<GnssFixType>(q % 6U);  // 3 is no NMEA code: ranks as "no fix"
  f.num_sv = in.u8();
  return f;
}

#if UWBNAV_COOP
// One neighbour state (`who` 128..159): bits 0-1 the vehicle (0x8001..0x8004),
// bit 2 an id from the input instead (anchor ids and 0xFFFF included), bit 3
// the state's own "cooperative" flag, bit 4 no velocity. Scaled integers, or
// raw float bits for position, covariance and velocity (any value, arrival
// before validity included) when `raw`.
uwbnav::NeighbourState neighbour_record(ByteReader& in, uint64_t t_us, bool raw, uint8_t who) {
  using namespace uwbnav;
  NeighbourState s;
  s.t_us = t_us;
  s.vehicle_id = (who & 4U) != 0 ? in.u16() : static_cast<uint16_t>(0x8001U + (who & 3U));
  s.cooperative = (who & 8U) != 0;
  if (raw) {
    s.pos_nav_m = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
    for (float& c : s.cov_pos_m2) c = in.f32_bits();
    const int64_t latency_us = static_cast<int64_t>(static_cast<int16_t>(in.u16())) * 100;
    s.rx_t_us = latency_us < 0 && static_cast<uint64_t>(-latency_us) > t_us ? 0 : t_us + static_cast<uint64_t>(latency_us);
    if ((who & 16U) == 0) s.vel_nav_mps = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
  } else {
    const auto p = [&] { return static_cast<float>(static_cast<int16_t>(in.u16())) * 0.01F; };
    const float x = p();
    const float y = p();
    const float z = p();
    s.pos_nav_m = Vec3f{x, y, z};
    const float sh = static_cast<float>(in.u8()) * 0.01F;  // 0 included: not positive definite
    const float sv = static_cast<float>(in.u8()) * 0.01F;
    const float rho = static_cast<float>(static_cast<int8_t>(in.u8())) / 100.0F;  // |rho| up to 1.28
    const float cov[6] = {sh * sh, rho * sh * sh, 0.0F, sh * sh, 0.0F, sv * sv};
    for (size_t k = 0; k < 6; ++k) s.cov_pos_m2[k] = cov[k];
    s.rx_t_us = t_us + static_cast<uint64_t>(in.u8()) * 4000U;  // 0..1020 ms latency
    if ((who & 16U) == 0) {
      const float vx = p();
      const float vy = p();
      const float vz = p();
      s.vel_nav_mps = Vec3f{vx, vy, vz};
    }
  }
  return s;
}
#endif

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace uwbnav;
  ByteReader in(data, size);
  const uint8_t header = in.u8();
  SiteConfig site = fuzz::square_site((header & 1U) != 0, (header & 2U) != 0 ? Platform::kAir : Platform::kGround);
  if ((header & 4U) != 0) site.gnss_lever_body_m = Vec3f{0.5F, 0.0F, 1.2F};

  fuzz::VectorImuSource imu;
  fuzz::VectorUwbSource uwb;
  int64_t t_us = static_cast<int64_t>(kStartUs);
  fuzz::VectorGnssSource gnss;
#if UWBNAV_COOP
  fuzz::VectorNeighbourSource neighbours;
  const auto records = [&] { return imu.samples.size() + uwb.ranges.size() + gnss.fixes.size() + neighbours.states.size(); };
#else
  const auto records = [&] { return imu.samples.size() + uwb.ranges.size() + gnss.fixes.size(); };
#endif
  while (in.left() > 0 && records() < 4096) {
    const uint8_t tag = in.u8();
    const bool raw = (tag & 2U) != 0;
    int64_t dt_ms = tag >> 2;
    if (raw) dt_ms = static_cast<int8_t>(in.u8());
    t_us += dt_ms * 1000;
    if (t_us < 0) t_us = 0;
    const auto t = static_cast<uint64_t>(t_us);
    if ((tag & 1U) == 0) {
      ImuSample s;
      s.t_us = t;
      if (raw) {
        s.accel_body_mps2 = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
        s.gyro_body_radps = Vec3f{in.f32_bits(), in.f32_bits(), in.f32_bits()};
      } else {
        const auto a = [&] { return static_cast<float>(static_cast<int16_t>(in.u16())) / 2000.0F; };
        const auto g = [&] { return static_cast<float>(static_cast<int16_t>(in.u16())) / 20000.0F; };
        const float ax = a();
        const float ay = a();
        const float az = 9.80665F + a();
        s.accel_body_mps2 = Vec3f{ax, ay, az};
        const float gx = g();
        const float gy = g();
        const float gz = g();
        s.gyro_body_radps = Vec3f{gx, gy, gz};
      }
      imu.samples.push_back(s);
    } else {
      const uint8_t who = in.u8();
      if (who >= 192U) {
        gnss.fixes.push_back(gnss_record(in, t, raw, (who & 1U) != 0));
        continue;
      }
      UwbRange r;
      r.t_us = t;
      r.anchor_id = static_cast<uint16_t>(who % 6U);  // 1..4 known, 0 and 5 unknown
#if UWBNAV_COOP
      if (who >= 128U && who < 160U) {
        neighbours.states.push_back(neighbour_record(in, t, raw, who));
        continue;
      }
      if (who >= 160U) r.anchor_id = static_cast<uint16_t>(0x8001U + (who & 3U));  // a neighbour's tag
#endif
      r.tag_id = static_cast<uint8_t>((who >> 3) & 1U);  // 1 unknown
      if (raw) {
        r.range_m = in.f32_bits();
        r.fp_power_dbm = in.f32_bits();
        r.rx_power_dbm = in.f32_bits();
      } else {
        r.range_m = static_cast<float>(in.u16()) * 0.001F;
        const uint8_t fp = in.u8();
        const uint8_t rx = in.u8();
        r.fp_power_dbm = fp == 0 ? kNaNf : -static_cast<float>(fp) * 0.5F;
        r.rx_power_dbm = rx == 0 ? kNaNf : -static_cast<float>(rx) * 0.5F;
      }
      uwb.ranges.push_back(r);
    }
  }

  fuzz::SinkCanBus can;
  fuzz::StringSerial serial;
  fuzz::StepClock clock;
  fuzz::BlobParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site, &gnss};
#if UWBNAV_COOP
  board.neighbours = &neighbours;
#endif
  auto app = std::make_unique<App>(board);
  if (!ok(app->init())) return 0;
  uint64_t last_t = kStartUs;
  for (const auto& s : imu.samples) last_t = s.t_us > last_t ? s.t_us : last_t;
  for (const auto& r : uwb.ranges) last_t = r.t_us > last_t ? r.t_us : last_t;
  for (const auto& f : gnss.fixes) last_t = f.rx_t_us > last_t && f.rx_t_us < UINT64_MAX / 2 ? f.rx_t_us : last_t;
#if UWBNAV_COOP
  for (const auto& s : neighbours.states) last_t = s.rx_t_us > last_t && s.rx_t_us < UINT64_MAX / 2 ? s.rx_t_us : last_t;
#endif
  uint64_t now = (kStartUs / kCyclePeriodUs) * kCyclePeriodUs;
  size_t valid = 0;
  for (size_t tick = 0; tick < kMaxTicks && now <= last_t + 200000; ++tick, now += kCyclePeriodUs) {
    clock.sleep_until_us(now);
    app->tick(now);
    check_output(app->last_output());
    valid += app->last_output().status == NavStatus::kValid ? 1U : 0U;
  }
  // UWBNAV_FUZZ_VERBOSE=1 with an input file: shows that the checks had valid outputs to check.
  static const bool verbose = std::getenv("UWBNAV_FUZZ_VERBOSE") != nullptr;
  if (verbose) {
    std::fprintf(stderr, "fuzz_sequence: %zu valid outputs; %zu ranges, %zu IMU samples; last status %s mode %d\n",
                 valid, uwb.ranges.size(), imu.samples.size(), nav_status_name(app->last_output().status),
                 static_cast<int>(app->last_output().mode));
    const auto& st = app->stats();
    std::fprintf(stderr, "fuzz_sequence: imu accepted %u rejected %u, uwb accepted %u rejected %u\n",
                 st.imu.accepted, st.imu.rejected_total(), st.uwb.accepted, st.uwb.rejected_total());
    std::fprintf(stderr, "fuzz_sequence: gnss accepted %u rejected %u, fused %u\n", st.gnss.accepted,
                 st.gnss.rejected_total(), app->navigator().diagnostics().gnss_used);
#if UWBNAV_COOP
    std::fprintf(stderr, "fuzz_sequence: neighbour states accepted %u rejected %u, vehicle ranges %u fused %u\n",
                 st.neighbours.accepted, st.neighbours.rejected_total(), app->navigator().diagnostics().neighbour_ranges,
                 app->navigator().diagnostics().neighbour_used);
#endif
  }
  return 0;
}
