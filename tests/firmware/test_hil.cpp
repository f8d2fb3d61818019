// HIL path in-process: rig encoder -> SOCK_SEQPACKET link pair -> App with
// can.hil_rx_enable -> CanPublisher -> link -> rig monitor, in lockstep. The
// firmware must receive the same samples as a direct replay, its output frames
// must decode without counter gaps, and the rig monitor must see real losses.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "firmware/app.hpp"
#include "firmware/can/publisher.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/idle_sources.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "hal/host/socketcan_bus.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/replay.hpp"
#include "tools/hil/clock_mapped_sources.hpp"
#include "tools/hil/hil_rig.hpp"
#include "tools/hil/output_monitor.hpp"
#include "tools/hil/sensor_stream.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

dataset::Recording short_parking_nlos(double duration_s) {
  sim::Scenario sc;
  std::string err;
  const std::string text = "base = parking_nlos\n[scenario]\nduration_s = " + std::to_string(duration_s) + "\n";
  EXPECT_TRUE(ok(sim::parse_scenario(text, "test", sc, &err))) << err;
  sim::SimOptions opt;
  opt.seed = 3;
  sim::SimOutput out;
  EXPECT_TRUE(ok(sim::simulate_scenario(sc, opt, out, &err))) << err;
  return out.rec;
}

// The recording as the firmware sees it over CAN: every sample through the
// rig encoder and the firmware decoder (input quantisation, 32-bit stamps).
dataset::Recording can_quantised(const dataset::Recording& rec) {
  dataset::Recording q = rec;
  can::CanSensorEncoder enc;
  can::CanSensorDecoder dec;
  Params p;
  p.reset_all();
  dec.configure(p);
  for (auto& s : q.imu) {
    hal::CanFrame f[can::kImuFrames];
    ignore_result(enc.encode_imu(s, f));
    can::CanSensorSample out;
    Status st = Status::kEmpty;
    for (const auto& frame : f) st = dec.on_frame(frame, s.t_us, out);
    EXPECT_TRUE(ok(st));
    s = out.imu;
  }
  for (auto& row : q.uwb) {
    hal::CanFrame f[can::kUwbFrames];
    ignore_result(enc.encode_uwb(row.range, f));
    can::CanSensorSample out;
    Status st = Status::kEmpty;
    for (const auto& frame : f) st = dec.on_frame(frame, row.range.t_us, out);
    EXPECT_TRUE(ok(st));
    row.range = out.uwb;
  }
  return q;
}

struct HilRun {
  uint64_t cycles = 0;
  AppStats stats;
  can::CanSensorStats rx;
  can::CanTxStats tx;
  std::unique_ptr<hil::SensorStream> stream;
  std::unique_ptr<hil::OutputMonitor> monitor;
};

// Lockstep HIL: each cycle the rig sends the samples due up to t, the App
// ticks at t, the rig reads the output frames (arrival = t).
HilRun run_hil_lockstep(const dataset::Recording& rec) {
  HilRun run;
  int fd_rig = -1;
  int fd_fw = -1;
  EXPECT_TRUE(ok(hal::can_link_pair(fd_rig, fd_fw)));
  hal::LockstepClock clock;
  hal::SocketCanOptions opt;
  opt.clock = &clock;
  hal::SocketCanBus rig_bus;
  hal::SocketCanBus fw_bus;
  EXPECT_TRUE(ok(rig_bus.adopt_fd(fd_rig, opt)));
  EXPECT_TRUE(ok(fw_bus.adopt_fd(fd_fw, opt)));

  hal::IdleImuSource imu;
  hal::IdleUwbSource uwb;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, fw_bus, serial, clock, store, rec.site};
  auto app = std::make_unique<App>(board);
  EXPECT_TRUE(ok(app->init()));
  EXPECT_TRUE(ok(app->set_param(ParamId::kCanHilRxEnable, 1.0F)));

  // Identity map (clock = recording time) so the outputs compare 1:1 with the replay.
  const uint64_t t0 = hil::first_sensor_time_us(rec);
  run.stream = std::make_unique<hil::SensorStream>(rec, hil::map_recording_to_clock(rec, t0, 1.0));
  run.monitor = std::make_unique<hil::OutputMonitor>(run.stream.get());
  EXPECT_EQ(run.stream->map().clock_origin_us, t0);

  can::CanSensorEncoder encoder;
  hal::CanFrame frames[can::kImuFrames];
  size_t next = 0;
  uint64_t t = (t0 / kCyclePeriodUs + 1) * kCyclePeriodUs;  // the replay's first cycle
  for (;;) {
    clock.sleep_until_us(t);
    while (next < run.stream->size() && (*run.stream)[next].t_clock_us <= t) {
      const size_t n = run.stream->encode(next++, encoder, frames);
      for (size_t k = 0; k < n; ++k) EXPECT_TRUE(ok(rig_bus.send(frames[k])));
    }
    app->tick(t);
    ++run.cycles;
    hal::CanFrame f;
    while (ok(rig_bus.receive(f))) run.monitor->on_frame(f, t);
    if (next >= run.stream->size()) break;
    t += kCyclePeriodUs;
  }
  run.stats = app->stats();
  run.rx = app->can_rx_stats();
  run.tx = app->can_tx_stats();
  return run;
}

TEST(Hil, FirmwareReceivesTheSameSamplesOverCanAsInDirectReplay) {
  const dataset::Recording rec = short_parking_nlos(15.0);
  ASSERT_GT(rec.imu.size(), 1000U);
  eval::ReplayResult direct;
  std::string err;
  ASSERT_TRUE(ok(eval::run_replay(rec, eval::ReplayOptions{}, direct, &err))) << err;
  const HilRun hil = run_hil_lockstep(rec);

  EXPECT_EQ(hil.cycles, direct.cycles);
  EXPECT_EQ(hil.rx.imu_samples, rec.imu.size());
  EXPECT_EQ(hil.rx.uwb_ranges, rec.uwb.size());
  EXPECT_EQ(hil.rx.crc_errors + hil.rx.counter_errors + hil.rx.length_errors + hil.rx.incomplete +
                hil.rx.frames_lost + hil.rx.saturated,
            0U);
  EXPECT_EQ(hil.stats.can_rx.received, direct.stats.imu.received + direct.stats.uwb.received);
  EXPECT_EQ(hil.stats.can_rx.accepted, direct.stats.imu.accepted + direct.stats.uwb.accepted);
  EXPECT_EQ(hil.stats.can_rx.rejected_total(), direct.stats.imu.rejected_total() + direct.stats.uwb.rejected_total());
  EXPECT_EQ(hil.stats.imu.received + hil.stats.uwb.received, 0U) << "no local sensors on a HIL board";
}

TEST(Hil, OutputFramesDecodeWithoutGapsAndEqualADirectReplayOfTheCanQuantisedInputs) {
  // 25 s: the vehicle leaves its 12 s parking start, the filter reports valid solutions.
  const dataset::Recording rec = short_parking_nlos(25.0);
  eval::ReplayResult direct;
  std::string err;
  ASSERT_TRUE(ok(eval::run_replay(rec, eval::ReplayOptions{}, direct, &err))) << err;
  const HilRun hil = run_hil_lockstep(rec);
  const hil::OutputMonitor& m = *hil.monitor;

  EXPECT_EQ(m.total_missing(), 0U);
  EXPECT_EQ(m.total_e2e_failures(), 0U);
  EXPECT_EQ(m.group_mismatches(), 0U);
  EXPECT_EQ(m.other_frames(), 0U);
  for (const auto& c : m.messages()) {
    EXPECT_EQ(c.received, c.accepted) << c.name;
    EXPECT_EQ(c.repeated, 0U) << c.name;
    EXPECT_GT(c.received, 0U) << c.name;
  }
  EXPECT_EQ(hil.tx.sent, m.messages()[0].received + m.messages()[1].received + m.messages()[2].received +
                             m.messages()[3].received + m.messages()[4].received + m.messages()[5].received +
                             m.messages()[6].received);
  ASSERT_EQ(m.solutions().size(), direct.estimates.size());

  // Same solution times and statuses; positions equal a direct replay of the
  // recording quantised exactly as the CAN inputs quantise it (encoder ->
  // decoder), within the 1 mm output resolution; against the unquantised
  // recording they differ by the effect of the input quantisation
  // (IMU 0.005 m/s^2, 0.001 rad/s; ranges 1 mm): a few cm.
  eval::ReplayResult quantised;
  ASSERT_TRUE(ok(eval::run_replay(can_quantised(rec), eval::ReplayOptions{}, quantised, &err))) << err;
  ASSERT_EQ(quantised.estimates.size(), m.solutions().size());
  double max_dxy_raw_m = 0.0;
  double max_dxy_q_m = 0.0;
  size_t compared = 0;
  for (size_t i = 0; i < m.solutions().size(); ++i) {
    const auto& s = m.solutions()[i];
    const auto& e = direct.estimates[i];
    const auto& q = quantised.estimates[i];
    ASSERT_EQ(s.nav_t_us, e.t_us) << i;
    EXPECT_EQ(s.status, q.status) << "epoch " << i;
    if (q.status == 1 || q.status == 2) {
      ++compared;
      max_dxy_q_m = std::max(max_dxy_q_m, std::hypot(s.pos_nav_m[0] - q.pos_nav_m[0], s.pos_nav_m[1] - q.pos_nav_m[1]));
      max_dxy_raw_m = std::max(max_dxy_raw_m, std::hypot(s.pos_nav_m[0] - e.pos_nav_m[0], s.pos_nav_m[1] - e.pos_nav_m[1]));
    }
  }
  EXPECT_GT(compared, 500U);
  EXPECT_LT(max_dxy_q_m, 0.0008);  // 1 mm steps: at most half a step per axis
  // Quantised vs raw inputs: the filter's response to the CAN input resolution
  // (largest around initialisation); 0.156 m seen under qemu-aarch64 (FMA contraction).
  EXPECT_LT(max_dxy_raw_m, 0.30);
  const auto hil_rows = hil::solutions_to_estimates(m.solutions(), hil.stream->map());
  const auto a_hil = eval::accuracy(eval::compare_with_truth(hil_rows, rec.truth), hil_rows.size());
  const auto a_direct = eval::accuracy(eval::compare_with_truth(direct.estimates, rec.truth), direct.estimates.size());
  EXPECT_EQ(a_hil.epochs, a_direct.epochs);
  EXPECT_NEAR(a_hil.rmse_h_m, a_direct.rmse_h_m, 0.02);
  // Lockstep: every output arrives in the cycle of its NavTime and the newest
  // sample it could include is at most 10 ms older (IMU on the grid: 0).
  ASSERT_FALSE(m.latencies_us().empty());
  for (double l : m.latencies_us()) {
    EXPECT_GE(l, 0.0);
    EXPECT_LT(l, 10000.0);
  }
}

// Publisher output for `cycles` cycles as the rig would receive it.
std::vector<hal::CanFrame> published_frames(int cycles) {
  can::CanPublisher pub;
  Params p;
  p.reset_all();
  pub.configure(p);
  hal::MemCanBus bus(64, 1024, 4096);
  can::CanDiag diag;
  for (int k = 0; k < cycles; ++k) {
    NavOutput o;
    o.t_us = 1000000 + static_cast<uint64_t>(k) * kCyclePeriodUs;
    o.status = NavStatus::kValid;
    o.pos_nav_m = {1.0F + 0.01F * static_cast<float>(k), 2.0F, 0.5F};
    pub.on_cycle(o.t_us, o, diag, bus);
  }
  std::vector<hal::CanFrame> frames;
  hal::CanFrame f;
  while (ok(bus.receive_sent(f))) frames.push_back(f);
  return frames;
}

TEST(Hil, MonitorCountsALostFrameAndACorruptedCrc) {
  std::vector<hal::CanFrame> frames = published_frames(40);
  size_t pos_seen = 0;
  size_t lost_index = 0;
  size_t corrupt_index = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].id != can::id_of(can::MsgId::kPosXY)) continue;
    ++pos_seen;
    if (pos_seen == 10) lost_index = i;
    if (pos_seen == 20) corrupt_index = i;
  }
  frames[corrupt_index].data[3] ^= 0x10;
  frames.erase(frames.begin() + static_cast<std::ptrdiff_t>(lost_index));
  hil::OutputMonitor m;
  for (const auto& f : frames) m.on_frame(f, f.t_us);
  const hil::MessageCheck& pos = m.messages()[1];
  ASSERT_EQ(pos.id, can::id_of(can::MsgId::kPosXY));
  EXPECT_EQ(pos.crc_errors, 1U);
  EXPECT_EQ(pos.missing, 2U);  // the dropped frame and the one rejected for its CRC
  EXPECT_EQ(m.total_missing(), 2U);
  EXPECT_EQ(m.total_e2e_failures(), 1U);
  EXPECT_EQ(m.solutions().size(), 38U);
  EXPECT_NEAR(m.solutions().front().pos_nav_m[0], 1.0, 0.001);
}

TEST(Hil, LatencyIsPosXYArrivalMinusNewestSampleAtOrBeforeNavTime) {
  dataset::Recording rec;
  for (uint64_t k = 0; k < 10; ++k) {
    ImuSample s;
    s.t_us = 2000000 + k * 10000;  // IMU on the grid
    rec.imu.push_back(s);
  }
  dataset::UwbRow r;
  r.range.t_us = 2023000;  // a range between two IMU samples
  rec.uwb.push_back(r);
  const hil::SensorStream stream(rec, hil::map_recording_to_clock(rec, 5000000, 1.0));
  EXPECT_EQ(stream.map().clock_origin_us, 5000000U);
  EXPECT_EQ(stream[2].kind, hil::StreamKind::kImu);
  EXPECT_EQ(stream[2].t_clock_us, 5020000U);
  EXPECT_EQ(stream[3].kind, hil::StreamKind::kUwb);
  EXPECT_EQ(stream[3].t_clock_us, 5023000U);
  EXPECT_EQ(stream[4].t_clock_us, 5030000U);

  hil::OutputMonitor m(&stream);
  can::CanPublisher pub;
  Params p;
  p.reset_all();
  pub.configure(p);
  hal::MemCanBus bus;
  NavOutput o;
  o.t_us = 5025000;  // newest sample at or before: the range at 5023000
  pub.on_cycle(o.t_us, o, can::CanDiag{}, bus);
  hal::CanFrame f;
  while (ok(bus.receive_sent(f))) m.on_frame(f, 5026500);
  ASSERT_EQ(m.latencies_us().size(), 1U);
  EXPECT_DOUBLE_EQ(m.latencies_us()[0], 3500.0);
}

TEST(Hil, ClockMappedReplaySourcesReleaseSamplesAtTheirClockTime) {
  const dataset::Recording rec = short_parking_nlos(2.0);
  const hil::TimeMap map = hil::map_recording_to_clock(rec, 9000000000ULL, 1.0);
  hal::ReplaySources src(rec);
  hil::ClockMappedImuSource imu(src.imu, map);
  const uint64_t t_first = map.to_clock_us(rec.imu.front().t_us);
  EXPECT_EQ(t_first % kCyclePeriodUs, rec.imu.front().t_us % kCyclePeriodUs) << "grid phase kept";
  ImuSample s;
  EXPECT_EQ(imu.poll(t_first - 1, s), Status::kEmpty);
  ASSERT_TRUE(ok(imu.poll(t_first, s)));
  EXPECT_EQ(s.t_us, t_first);
  EXPECT_EQ(s.accel_body_mps2.x, rec.imu.front().accel_body_mps2.x);
  uint64_t t_rec = 0;
  ASSERT_TRUE(map.to_rec_us(t_first, &t_rec));
  EXPECT_EQ(t_rec, rec.imu.front().t_us);
}

TEST(Hil, ClockMappedGnssFixesAreDueAtTheirArrivalAndKeepTheirLatency) {
  dataset::Recording rec = short_parking_nlos(2.0);
  GnssFix f;
  f.t_us = rec.imu.front().t_us + 500000;
  f.rx_t_us = f.t_us + 120000;  // 120 ms latency
  f.pos_nav_m = {3.0F, 4.0F, 1.5F};
  f.pos_sigma_m = {0.5F, 0.5F, 1.0F};
  rec.gnss.push_back(f);
  const hil::TimeMap map = hil::map_recording_to_clock(rec, 9000000000ULL, 1.0);
  hal::ReplaySources src(rec);
  hil::ClockMappedGnssSource gnss(src.gnss, map);
  const uint64_t rx_clock = map.to_clock_us(f.rx_t_us);
  GnssFix out;
  // Not due at its time of validity: a fix is handed over when it arrives.
  EXPECT_EQ(gnss.poll(map.to_clock_us(f.t_us), out), Status::kEmpty);
  EXPECT_EQ(gnss.poll(rx_clock - 1, out), Status::kEmpty);
  ASSERT_TRUE(ok(gnss.poll(rx_clock, out)));
  EXPECT_EQ(out.rx_t_us, rx_clock);
  EXPECT_EQ(out.rx_t_us - out.t_us, 120000U) << "both times mapped: the latency is kept";
  EXPECT_EQ(out.pos_nav_m.y, 4.0F);
  EXPECT_TRUE(gnss.finished());
}

TEST(Hil, ClockMappedNeighbourStatesAreDueAtTheirArrivalAndKeepTheirLatency) {
  dataset::Recording rec = short_parking_nlos(2.0);
  NeighbourState n;
  n.t_us = rec.imu.front().t_us + 500000;
  n.rx_t_us = n.t_us + 40000;  // 40 ms latency
  n.vehicle_id = kFirstVehicleId + 1;
  n.pos_nav_m = {30.0F, 4.0F, 1.2F};
  for (float& c : n.cov_pos_m2) c = 0.0F;
  n.cov_pos_m2[0] = n.cov_pos_m2[3] = 0.01F;
  n.cov_pos_m2[5] = 0.04F;
  rec.neighbours.push_back(n);
  const hil::TimeMap map = hil::map_recording_to_clock(rec, 9000000000ULL, 1.0);
  hal::ReplaySources src(rec);
  hil::ClockMappedNeighbourSource neighbours(src.neighbours, map);
  const uint64_t rx_clock = map.to_clock_us(n.rx_t_us);
  NeighbourState out;
  EXPECT_EQ(neighbours.poll(map.to_clock_us(n.t_us), out), Status::kEmpty);
  EXPECT_EQ(neighbours.poll(rx_clock - 1, out), Status::kEmpty);
  ASSERT_TRUE(ok(neighbours.poll(rx_clock, out)));
  EXPECT_EQ(out.rx_t_us, rx_clock);
  EXPECT_EQ(out.rx_t_us - out.t_us, 40000U) << "both times mapped: the latency is kept";
  EXPECT_EQ(out.vehicle_id, kFirstVehicleId + 1);
  EXPECT_EQ(out.pos_nav_m.x, 30.0F);
  EXPECT_TRUE(neighbours.finished());
}

// issue 18: `uwbnav hil --max-latency-ms 5` passed a run whose largest latency
// was 27.5 ms because it checked the p99. The max and the p99 are separate checks.
TEST(HilChecks, MaxLatencyBoundsTheLargestLatencyAndP99IsASeparateCheck) {
  hil::HilReport r;
  r.latency_ms.n = 2000;
  r.latency_ms.p99 = 4.1;
  r.latency_ms.max = 27.5;
  int failures = 0;
  hil::HilLimits limits;
  limits.max_latency_ms = 5.0;
  auto lines = hil::check_report(r, limits, &failures);
  EXPECT_EQ(failures, 1);
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "CHECK FAILED: latency max [ms] = 27.5000 exceeds 5.0000");
  failures = 0;
  limits = hil::HilLimits{};
  limits.max_latency_p99_ms = 5.0;
  lines = hil::check_report(r, limits, &failures);
  EXPECT_EQ(failures, 0);
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "CHECK passed: latency p99 [ms] = 4.1000 <= 5.0000");
  failures = 0;
  limits.max_latency_ms = 30.0;
  lines = hil::check_report(r, limits, &failures);
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(lines.size(), 2U);
  r.latency_ms = hil::SeriesStats{};  // no latency measured: a requested check cannot pass
  failures = 0;
  (void)hil::check_report(r, limits, &failures);
  EXPECT_EQ(failures, 2);
}

}  // namespace
}  // namespace uwbnav
