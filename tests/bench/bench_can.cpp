// Cost of the CAN path per 10 ms cycle: CRC-8, one publisher cycle, HIL decoding.
#include <benchmark/benchmark.h>

#include "firmware/can/e2e.hpp"
#include "firmware/can/publisher.hpp"
#include "firmware/can/sensor_decoder.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace {

using namespace uwbnav;

void BM_CanCrc8Frame(benchmark::State& state) {
  uint8_t frame[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  for (auto _ : state) {
    frame[2] = static_cast<uint8_t>(frame[2] + 1);
    benchmark::DoNotOptimize(can::e2e_crc(0x1101, frame, 8));
  }
}
BENCHMARK(BM_CanCrc8Frame);

void BM_CanPublisherCycle(benchmark::State& state) {
  Params params;
  can::CanPublisher pub;
  pub.configure(params);
  hal::MemCanBus bus(64, 1, 0);
  can::CanDiag diag;
  NavOutput nav;
  nav.status = NavStatus::kValid;
  nav.pos_nav_m = Vec3f{12.3F, -45.6F, 0.7F};
  uint64_t t = 1000000;
  for (auto _ : state) {
    nav.t_us = t;
    pub.on_cycle(t, nav, diag, bus);
    t += can::kCanTickUs;
  }
  state.counters["frames/cycle"] = benchmark::Counter(static_cast<double>(pub.stats().sent) /
                                                      static_cast<double>(state.iterations()));
}
BENCHMARK(BM_CanPublisherCycle);

void BM_CanSensorDecodeImuSample(benchmark::State& state) {
  Params params;
  can::CanSensorEncoder enc;
  can::CanSensorDecoder dec;
  dec.configure(params);
  ImuSample s;
  s.accel_body_mps2.z = 9.81F;
  can::CanSensorSample out;
  for (auto _ : state) {
    s.t_us += 10000;
    hal::CanFrame f[can::kImuFrames];
    enc.encode_imu(s, f);
    for (const auto& frame : f) benchmark::DoNotOptimize(dec.on_frame(frame, s.t_us, out));
  }
}
BENCHMARK(BM_CanSensorDecodeImuSample);

}  // namespace
