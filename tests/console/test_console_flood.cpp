// Console flood: a torrent of input (commands, long replies, 100 Hz streams,
// garbage, over-long lines) with a fast and with a slow reader, ticked in
// lockstep. The console's work per cycle stays within its byte budgets, slow
// readers lose output with a counter and a marker instead of stalling, and the
// estimator sees exactly what it sees with a silent console.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "console_rig.hpp"
#include "firmware/console/console.hpp"

namespace uwbnav {
namespace {

using testing::ConsoleRig;
using testing::sim_recording;

std::string flood_input(size_t min_bytes) {
  static const char* const kPieces[] = {
      "status\r",          "stats\r",     "ekf -v\r",         "anchors\r",     "param list\r",
      "help\r",            "history\r",   "param get uwb.sigma\r", "!!\r",     "no such command\r",
      "stream pos 100\r",  "stream stats 100\r", "stream anchors 100\r", "version\r", "log level\r",
  };
  std::string in;
  size_t k = 0;
  while (in.size() < min_bytes) {
    in += kPieces[k % (sizeof kPieces / sizeof kPieces[0])];
    if (k % 7 == 3) in += std::string("\x01\x02\xfe\xff garbage\r", 14);
    if (k % 11 == 5) in += std::string(400, 'L') + "\r";
    ++k;
  }
  return in;
}

struct TickProfile {
  uint64_t max_read = 0;      // bytes read from the port in one cycle
  uint64_t max_written = 0;   // bytes written to the port in one cycle
  double max_work_us = 0.0;   // wall time of the whole cycle (informative only)
  double sum_work_us = 0.0;
  uint64_t ticks = 0;
  uint64_t max_work_tick = 0;
};

// Ticks the rig for `seconds`, measuring per-cycle port traffic and work time.
TickProfile run_profiled(ConsoleRig& rig, double seconds) {
  TickProfile p;
  const auto n = static_cast<uint64_t>(seconds * 1e6 / kCyclePeriodUs);
  for (uint64_t i = 0; i < n; ++i) {
    const uint64_t r0 = rig.serial.total_read;
    const uint64_t w0 = rig.serial.total_written;
    const auto t0 = std::chrono::steady_clock::now();
    rig.tick();
    const double work_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    rig.app.record_cycle_timing(static_cast<uint32_t>(work_us), 0, work_us > kCyclePeriodUs);
    p.max_read = std::max(p.max_read, rig.serial.total_read - r0);
    p.max_written = std::max(p.max_written, rig.serial.total_written - w0);
    if (work_us > p.max_work_us) p.max_work_tick = i;
    p.max_work_us = std::max(p.max_work_us, work_us);
    p.sum_work_us += work_us;
    ++p.ticks;
  }
  return p;
}

void expect_same_source_stats(const SourceStats& a, const SourceStats& b, const char* what) {
  EXPECT_EQ(a.received, b.received) << what;
  EXPECT_EQ(a.accepted, b.accepted) << what;
  EXPECT_EQ(a.io_errors, b.io_errors) << what;
  for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
    EXPECT_EQ(a.rejected[r], b.rejected[r]) << what << " " << reject_reason_name(static_cast<RejectReason>(r));
  }
}

void expect_same_output(const NavOutput& a, const NavOutput& b) {
  EXPECT_EQ(a.t_us, b.t_us);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(std::memcmp(&a.pos_nav_m, &b.pos_nav_m, sizeof a.pos_nav_m), 0);
  EXPECT_EQ(std::memcmp(&a.pos_sigma_m, &b.pos_sigma_m, sizeof a.pos_sigma_m), 0);
  EXPECT_EQ(a.resets, b.resets);
}

class ConsoleFlood : public ::testing::TestWithParam<size_t> {};

TEST_P(ConsoleFlood, WorkPerCycleStaysWithinBudgetAndTheEstimatorIsUndisturbed) {
  const size_t write_cap = GetParam();
  const dataset::Recording& rec = sim_recording();
  constexpr double kSeconds = 30.0;

  ConsoleRig quiet(rec);
  const TickProfile qp = run_profiled(quiet, kSeconds);

  ConsoleRig flooded(rec);
  flooded.serial.write_cap = write_cap;
  flooded.serial.type(flood_input(512 * 1024));
  const uint64_t written_before = flooded.serial.total_written;  // the banner
  const TickProfile fp = run_profiled(flooded, kSeconds);

  const ConsoleStats& cs = flooded.app.console().stats();
  std::printf("[ flood    ] write_cap=%zu ticks=%llu read=%llu B written=%llu B dropped=%llu B commands=%u errors=%u\n",
              write_cap, static_cast<unsigned long long>(fp.ticks),
              static_cast<unsigned long long>(flooded.serial.total_read),
              static_cast<unsigned long long>(flooded.serial.total_written),
              static_cast<unsigned long long>(cs.dropped_bytes), cs.commands, cs.errors);
  std::printf("[ flood    ] cycle work: quiet mean %.1f us max %.1f us; flooded mean %.1f us max %.1f us (cycle %llu)\n",
              qp.sum_work_us / static_cast<double>(qp.ticks), qp.max_work_us,
              fp.sum_work_us / static_cast<double>(fp.ticks), fp.max_work_us,
              static_cast<unsigned long long>(fp.max_work_tick));

  // Bounded work per cycle, measured at the port and by the console itself.
  EXPECT_LE(fp.max_read, Console::kRxBytesPerPoll);
  EXPECT_LE(fp.max_written, Console::kTxBytesPerPoll);
  EXPECT_LE(cs.max_rx_per_poll, Console::kRxBytesPerPoll);
  EXPECT_LE(cs.max_tx_per_poll, Console::kTxBytesPerPoll);
  EXPECT_EQ(cs.max_commands_per_poll, 1U);
  EXPECT_LE(flooded.app.console().tx_pending(), Console::kTxRingBytes);

  // The flood reached the shell and was answered (a slow reader throttles how much).
  if (write_cap >= Console::kTxBytesPerPoll) {
    EXPECT_GT(cs.commands, 300U);
    EXPECT_GT(cs.errors, 10U);
    EXPECT_GT(cs.overlong_lines, 0U);
    EXPECT_GT(cs.garbage_lines, 0U);
  } else {
    EXPECT_GE(cs.commands, 5U);
  }

  // Every sensor frame was drained, validated and fused exactly as without the flood.
  const AppStats& a = quiet.app.stats();
  const AppStats& b = flooded.app.stats();
  expect_same_source_stats(a.imu, b.imu, "imu");
  expect_same_source_stats(a.uwb, b.uwb, "uwb");
  EXPECT_EQ(a.loop.cycles, b.loop.cycles);
  expect_same_output(quiet.app.last_output(), flooded.app.last_output());
  EXPECT_EQ(quiet.app.navigator().diagnostics().ranges_used, flooded.app.navigator().diagnostics().ranges_used);

  if (write_cap < Console::kTxBytesPerPoll) {
    // A slow reader loses output, counted and announced, and holds the shell back
    // (input waits in the port) instead of the loop.
    EXPECT_GT(cs.dropped_bytes, 0U);
    EXPECT_NE(flooded.serial.output.find("[dropped "), std::string::npos);
    EXPECT_LE(flooded.serial.total_written - written_before, fp.ticks * write_cap);
  }
}

INSTANTIATE_TEST_SUITE_P(Readers, ConsoleFlood, ::testing::Values(SIZE_MAX, size_t{8}),
                         [](const ::testing::TestParamInfo<size_t>& p) {
                           return p.param == SIZE_MAX ? std::string("FastReader") : std::string("SlowReader");
                         });

}  // namespace
}  // namespace uwbnav
