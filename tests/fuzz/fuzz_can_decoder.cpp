// libFuzzer target: the firmware's CAN sensor-frame decoder (HIL IMU/UWB input,
// V2X_Neighbour states with UWBNAV_COOP, GNSS_Fix groups with UWBNAV_GNSS,
// E2E checks, multi-frame grouping,
// 32-bit time unwrap) on arbitrary frames.
// Input: records of [id selector, len, flags, dt, payload (len bytes, max 64)];
// flags bit 7 toggles the decoder's HIL input (set_hil_enabled) before the frame.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "estimator/params.hpp"
#include "firmware/can/message_table.hpp"
#include "firmware/can/sensor_decoder.hpp"
#include "tests/fuzz/fuzz_board.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace uwbnav;
  // Selectors 0..6 as before (HIL inputs, two outputs); then the V2X_Neighbour
  // parts, our own UWBNAV_CoopTime (not an input) and the GNSS_Fix parts.
  static constexpr uint32_t kIds[] = {0x0A0, 0x0A1, 0x0A2, 0x0B0, 0x0B1, 0x100, 0x105,
                                      0x0C0, 0x0C1, 0x0C2, 0x0C3, 0x0C4, 0x0C5, 0x110,
                                      0x0D0, 0x0D1, 0x0D2, 0x0D3, 0x0D4};
  fuzz::ByteReader in(data, size);
  Params params;
  can::CanSensorDecoder dec;
  dec.configure(params);
  uint64_t now_us = 1000000;
  uint32_t delivered = 0;
  while (in.left() > 0) {
    hal::CanFrame f;
    const uint8_t sel = in.u8();
    f.id = (sel & 0x80U) != 0 ? (static_cast<uint32_t>(sel & 0x7FU) << 4) : kIds[sel % (sizeof kIds / sizeof kIds[0])];
    f.len = static_cast<uint8_t>(in.u8() % 65U);
    const uint8_t flags = in.u8();
    f.flags = static_cast<uint8_t>(flags & 0x0FU);
#if UWBNAV_COOP || UWBNAV_GNSS
    if ((flags & 0x80U) != 0) dec.set_hil_enabled(!dec.hil_enabled());
#endif
    now_us += static_cast<uint64_t>(in.u8()) * 1000U;
    f.t_us = now_us;
    for (uint8_t i = 0; i < f.len; ++i) f.data[i] = in.u8();
    can::CanSensorSample out;
    const Status st = dec.on_frame(f, now_us, out);
    if (st == Status::kOk) {
      ++delivered;
      if (out.kind == can::SensorKind::kImu) {
        const ImuSample& s = out.imu;
        if (!std::isfinite(s.accel_body_mps2.x) || !std::isfinite(s.accel_body_mps2.y) ||
            !std::isfinite(s.accel_body_mps2.z) || !std::isfinite(s.gyro_body_radps.x) ||
            !std::isfinite(s.gyro_body_radps.y) || !std::isfinite(s.gyro_body_radps.z)) {
          std::abort();  // the CAN encoding is integer: a decoded sample is always finite
        }
      } else if (out.kind == can::SensorKind::kUwb) {
        if (!std::isfinite(out.uwb.range_m)) std::abort();
#if UWBNAV_COOP
      } else if (out.kind == can::SensorKind::kNeighbour) {
        // Integer encoding: position, covariance and (reported) velocity are finite.
        const NeighbourState& n = out.neighbour;
        if (!std::isfinite(n.pos_nav_m.x) || !std::isfinite(n.pos_nav_m.y) || !std::isfinite(n.pos_nav_m.z)) {
          std::abort();
        }
        for (float c : n.cov_pos_m2) {
          if (!std::isfinite(c)) std::abort();
        }
        if (std::isinf(n.vel_nav_mps.x) || std::isinf(n.vel_nav_mps.y) || std::isinf(n.vel_nav_mps.z)) std::abort();
        if (n.rx_t_us != now_us) std::abort();
        if (n.cov_pos_m2[0] < 0.0F || n.cov_pos_m2[3] < 0.0F || n.cov_pos_m2[5] < 0.0F) std::abort();
#endif
#if UWBNAV_GNSS
      } else if (out.kind == can::SensorKind::kGnss) {
        // Integer encoding, flagged groups dropped: position and sigmas finite,
        // sigmas within the signal, a known fix type, the receiver's clock.
        const GnssFix& g = out.gnss;
        if (!std::isfinite(g.pos_nav_m.x) || !std::isfinite(g.pos_nav_m.y) || !std::isfinite(g.pos_nav_m.z)) {
          std::abort();
        }
        const float sig[3] = {g.pos_sigma_m.x, g.pos_sigma_m.y, g.pos_sigma_m.z};
        for (float v : sig) {
          if (!(v >= 0.0F && v <= 20.475F)) std::abort();
        }
        if (std::isinf(g.vel_nav_mps.x) || std::isinf(g.vel_nav_mps.y) || std::isinf(g.vel_nav_mps.z)) std::abort();
        if (std::isinf(g.vel_sigma_mps)) std::abort();
        if (g.fix == GnssFixType::kNone || g.rx_t_us != now_us) std::abort();
#endif
      } else {
        std::abort();  // kOk without a sample
      }
    } else if (st != Status::kEmpty && st != Status::kNotFound && st != Status::kRejected) {
      std::abort();  // undocumented status
    }
  }
  const can::CanSensorStats& s = dec.stats();
  uint32_t counted = s.imu_samples + s.uwb_ranges;
#if UWBNAV_COOP
  counted += s.neighbour_states;
#endif
#if UWBNAV_GNSS
  counted += s.gnss_fixes;
#endif
  if (counted != delivered) std::abort();
  return 0;
}
