// Console commands through an in-memory serial port on a simulated replay:
// every command's reply format, parameter changes applied live and
// bounds-checked, and bad input (unknown commands, wrong arguments, too-long
// lines, binary garbage) answered by one error line without side effects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "console_rig.hpp"
#include "estimator/params.hpp"
#include "firmware/console/console.hpp"
#include "firmware/param_text.hpp"
#include "firmware/console/log.hpp"

namespace uwbnav {
namespace {

using testing::ConsoleRig;
using testing::kv;
using testing::kv_num;
using testing::lines_with_prefix;
using testing::reply_lines;
using testing::sim_recording;

// The numbers of a comma-separated value ("1.5,2,-3e-4").
std::vector<double> csv_numbers(const std::string& v) {
  std::vector<double> out;
  for (size_t p = 0; p != std::string::npos && p <= v.size();) {
    out.push_back(std::strtod(v.c_str() + p, nullptr));
    const size_t c = v.find(',', p);
    p = c == std::string::npos ? c : c + 1;
  }
  return out;
}

bool params_equal(const Params& a, const Params& b) {
  for (size_t i = 0; i < kNumParams; ++i) {
    const auto id = static_cast<ParamId>(i);
    if (a.get(id) != b.get(id)) return false;
  }
  return true;
}

TEST(ConsoleCommands, BannerAndPromptAppearOnTheFirstCycle) {
  const dataset::Recording& rec = sim_recording();
  testing::MemSerialPort serial;
  hal::ReplaySources src(rec);
  hal::MemCanBus can;
  hal::LockstepClock clock;
  hal::EmptyParamStore store;
  hal::Board board{src.imu, src.uwb, can, serial, clock, store, rec.site};
  App app(board);
  ASSERT_TRUE(ok(app.init()));
  app.tick(testing::first_cycle_us(rec));
  EXPECT_EQ(serial.output.rfind("console ready fw=", 0), 0U) << serial.output;
  EXPECT_EQ(serial.output.substr(serial.output.size() - 2), "> ");
}

TEST(ConsoleCommands, HelpListsEveryCommandOnePerLine) {
  ConsoleRig rig(sim_recording());
  const auto lines = reply_lines(rig.command("help"));
  const auto help = lines_with_prefix(lines, "help ");
  EXPECT_EQ(help.size(), lines.size());
  for (const char* name : {"help", "version", "status", "stats", "anchors", "ekf", "param", "log", "stream", "reset",
                           "history", "echo"}) {
    bool found = false;
    for (const auto& l : help) found |= l.rfind(std::string("help ") + name, 0) == 0;
    EXPECT_TRUE(found) << name;
  }
}

TEST(ConsoleCommands, VersionShowsBuildGitHashAndChecksums) {
  ConsoleRig rig(sim_recording());
  const auto lines = reply_lines(rig.command("version"));
  ASSERT_EQ(lines.size(), 1U);
  const std::string& l = lines[0];
  EXPECT_EQ(l.rfind("version fw=", 0), 0U);
  EXPECT_FALSE(kv(l, "git").empty());
  EXPECT_EQ(kv(l, "params"), std::to_string(kNumParams));
  EXPECT_EQ(kv(l, "params_crc").size(), 10U);
  EXPECT_EQ(kv(l, "svm2_crc").size(), 10U);
  EXPECT_NE(kv(l, "svm2_crc"), "0x00000000");
}

TEST(ConsoleCommands, StatusReportsTheLastOutputAndSensorAges) {
  ConsoleRig rig(sim_recording());
  rig.run_s(20.0);
  // The reply describes the cycle that ran the command; its line (with every
  // reset counter) is longer than one cycle's TX budget, so it ends a cycle later.
  rig.serial.output.clear();
  rig.serial.type("status\r");
  rig.tick();
  const NavOutput o = rig.app.last_output();
  for (int i = 0; i < 5; ++i) rig.tick();
  const auto lines = reply_lines(rig.serial.output);
  ASSERT_EQ(lines.size(), 1U);
  const std::string& l = lines[0];
  EXPECT_EQ(kv(l, "mode"), nav_status_name(o.status));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", static_cast<double>(o.pos_nav_m.x));
  EXPECT_EQ(kv(l, "x_m"), buf);
  std::snprintf(buf, sizeof buf, "%.3f", static_cast<double>(o.pos_sigma_m.y));
  EXPECT_EQ(kv(l, "sy_m"), buf);
  EXPECT_LE(kv_num(l, "imu_age_ms"), 20.0);  // IMU at 100 Hz or more
  EXPECT_LE(kv_num(l, "uwb_age_ms"), 1000.0);
  EXPECT_GT(kv_num(l, "used_total"), 100.0);
}

TEST(ConsoleCommands, StatsShowsLoopSourcesRejectsCanNavAndConsoleCounters) {
  const dataset::Recording rec = testing::truncated(sim_recording(), 4.0);
  ConsoleRig rig(rec);
  rig.app.record_cycle_timing(120, 5, false);
  rig.app.record_cycle_timing(480, 9, true);
  rig.run_s(5.0);
  const uint32_t tx_before = rig.can.counters().tx_ok;  // the firmware keeps sending while the reply goes out
  const auto lines = reply_lines(rig.command("stats"));
  ASSERT_EQ(lines.size(), 12U);
  const AppStats& s = rig.app.stats();
  EXPECT_EQ(lines[0].rfind("stats loop ", 0), 0U);
  EXPECT_EQ(kv(lines[0], "overruns"), "1");
  EXPECT_EQ(kv(lines[0], "cycle_min_us"), "120");
  EXPECT_EQ(kv(lines[0], "cycle_avg_us"), "300");
  EXPECT_EQ(kv(lines[0], "cycle_max_us"), "480");
  // Cycle latency = start lateness + work: 125 us and 489 us, both in the le500 bin.
  EXPECT_EQ(lines[1].rfind("stats latency ", 0), 0U);
  EXPECT_EQ(kv(lines[1], "max_us"), "489");
  EXPECT_EQ(kv(lines[1], "le200"), "1");
  EXPECT_EQ(kv(lines[1], "le500"), "1");
  EXPECT_EQ(kv(lines[1], "le50"), "0");
  EXPECT_EQ(kv(lines[1], "gt50000"), "0");
  EXPECT_EQ(kv(lines[2], "src"), "imu");
  EXPECT_EQ(kv(lines[3], "src"), "uwb");
  EXPECT_EQ(kv(lines[4], "src"), "can_rx");
  EXPECT_EQ(kv(lines[3], "received"), std::to_string(s.uwb.received));
  EXPECT_EQ(kv(lines[3], "accepted"), std::to_string(s.uwb.accepted));
  for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
    const char* name = reject_reason_name(static_cast<RejectReason>(r));
    EXPECT_EQ(kv(lines[3], name), std::to_string(s.uwb.rejected[r])) << name;
  }
  EXPECT_EQ(lines[5].rfind("stats can ", 0), 0U);
  EXPECT_GE(kv_num(lines[5], "tx_ok"), tx_before);
  EXPECT_LE(kv_num(lines[5], "tx_ok"), rig.can.counters().tx_ok);
  EXPECT_EQ(kv(lines[5], "bus_off"), std::to_string(rig.can.counters().bus_off));
  EXPECT_EQ(lines[6].rfind("stats nav ", 0), 0U);
  EXPECT_EQ(kv(lines[6], "ranges_used"), std::to_string(rig.app.navigator().diagnostics().ranges_used));
  // GNSS: the validator's view (no receiver on this board: all zero), then the estimator's.
  EXPECT_EQ(kv(lines[7], "src"), "gnss");
  EXPECT_EQ(kv(lines[7], "received"), "0");
  EXPECT_EQ(lines[8].rfind("stats gnss ", 0), 0U);
  EXPECT_EQ(kv(lines[8], "fused"), "0");
  EXPECT_EQ(kv(lines[8], "gate"), "0");
  // Neighbour vehicles: their states through validation (none here), then the ranges to them.
  EXPECT_EQ(kv(lines[9], "src"), "neighbours");
  EXPECT_EQ(kv(lines[9], "received"), "0");
  EXPECT_EQ(lines[10].rfind("stats coop ", 0), 0U);
  EXPECT_EQ(kv(lines[10], "ranges"), "0");
  EXPECT_EQ(kv(lines[10], "stale"), "0");
  EXPECT_EQ(lines[11].rfind("stats console ", 0), 0U);
}

TEST(ConsoleCommands, StatsShowsCanBusOffFromTheBoard) {
  ConsoleRig rig(sim_recording());
  rig.can.set_state(hal::CanBusState::kBusOff);
  const auto lines = reply_lines(rig.command("stats"));
  ASSERT_EQ(lines.size(), 12U);
  EXPECT_EQ(kv(lines[5], "state"), "bus_off");
  EXPECT_EQ(kv(lines[5], "bus_off"), "1");
}

TEST(ConsoleCommands, AnchorsListsEverySiteAnchorWithItsCounters) {
  const dataset::Recording rec = testing::truncated(sim_recording(), 20.0);
  ConsoleRig rig(rec);
  rig.run_s(20.5);
  const auto lines = reply_lines(rig.command("anchors"));
  ASSERT_EQ(lines.size(), rec.site.num_anchors + 1);
  EXPECT_EQ(kv(lines[0], "count"), std::to_string(rec.site.num_anchors));
  for (size_t i = 0; i < rec.site.num_anchors; ++i) {
    const std::string& l = lines[i + 1];
    const AnchorStatus& a = rig.app.navigator().anchor_status(i);
    EXPECT_EQ(kv(l, "id"), std::to_string(a.anchor_id));
    EXPECT_TRUE(kv(l, "state") == "los" || kv(l, "state") == "nlos") << l;
    EXPECT_EQ(kv(l, "los"), std::to_string(a.los_count));
    EXPECT_EQ(kv(l, "nlos"), std::to_string(a.nlos_count));
    EXPECT_GT(kv_num(l, "range_m"), 0.0);
    EXPECT_LE(kv_num(l, "age_ms"), 2500.0);
  }
}

TEST(ConsoleCommands, EkfPrintsStateAndDiagonalAndVerboseStreamsTheFullCovarianceOverSeveralCycles) {
  // Sensors stop after 10 s, so the covariance holds still while the test compares.
  const dataset::Recording rec = testing::truncated(sim_recording(), 10.0);
  ConsoleRig rig(rec);
  rig.run_s(11.0);
  const auto brief = reply_lines(rig.command("ekf"));
  ASSERT_EQ(brief.size(), 2U);
  EXPECT_EQ(brief[0].rfind("ekf state p_m=", 0), 0U);
  EXPECT_EQ(brief[1].rfind("ekf pdiag p_m2=", 0), 0U);

  uint64_t ticks = 0;
  const auto full = reply_lines(rig.command("ekf -v", &ticks));
  ASSERT_EQ(full.size(), 2U + Navigator::kErrorStateSize);
  for (size_t r = 0; r < Navigator::kErrorStateSize; ++r) {
    const std::string& l = full[2 + r];
    EXPECT_EQ(kv(l, "row"), std::to_string(r));
    const std::vector<double> row = csv_numbers(kv(l, "v"));
    ASSERT_EQ(row.size(), Navigator::kErrorStateSize) << l;
    // The diagonal printed here is the navigator's (3 significant digits).
    const double want = static_cast<double>(rig.app.navigator().covariance(r, r));
    EXPECT_NEAR(row[r], want, std::fabs(want) * 1e-2) << l;
  }
  EXPECT_GT(ticks, 1U) << "the 15x15 covariance exceeds one cycle's TX budget and must be paced";
  EXPECT_LE(rig.app.console().stats().max_tx_per_poll, Console::kTxBytesPerPoll);
  EXPECT_EQ(rig.app.console().stats().dropped_bytes, 0U);
}

// The stats, anchors and ekf replies share one snapshot storage (a union, to
// save RAM on the M4F): each reply must show what its own command copied, also
// right after another kind of reply filled that storage.
TEST(ConsoleCommands, MultiLineRepliesInTurnEachShowTheirOwnSnapshotThoughTheyShareItsStorage) {
  const dataset::Recording rec = testing::truncated(sim_recording(), 10.0);
  ConsoleRig rig(rec);
  rig.run_s(11.0);
  const Navigator& nav = rig.app.navigator();
  const auto check_ekf = [&](const char* after) {
    const auto full = reply_lines(rig.command("ekf -v"));
    ASSERT_EQ(full.size(), 2U + Navigator::kErrorStateSize) << "after " << after;
    for (size_t r = 0; r < Navigator::kErrorStateSize; ++r) {
      const std::vector<double> row = csv_numbers(kv(full[2 + r], "v"));
      ASSERT_EQ(row.size(), Navigator::kErrorStateSize) << full[2 + r];
      const double want = static_cast<double>(nav.covariance(r, r));
      EXPECT_NEAR(row[r], want, std::fabs(want) * 1e-2) << "after " << after << ": " << full[2 + r];
    }
  };
  const auto check_anchors = [&](const char* after) {
    const auto lines = reply_lines(rig.command("anchors"));
    ASSERT_EQ(lines.size(), rec.site.num_anchors + 1) << "after " << after;
    for (size_t i = 0; i < rec.site.num_anchors; ++i) {
      EXPECT_EQ(kv(lines[i + 1], "id"), std::to_string(nav.anchor_status(i).anchor_id)) << "after " << after;
      EXPECT_EQ(kv(lines[i + 1], "los"), std::to_string(nav.anchor_status(i).los_count)) << "after " << after;
    }
  };
  const auto check_stats = [&](const char* after) {
    const auto nav_lines = lines_with_prefix(reply_lines(rig.command("stats")), "stats nav ");
    ASSERT_EQ(nav_lines.size(), 1U) << "after " << after;
    EXPECT_EQ(kv(nav_lines[0], "ranges_received"), std::to_string(rig.app.nav_counters().ranges_received))
        << "after " << after;
  };
  check_ekf("start");
  check_anchors("ekf");
  check_ekf("anchors");
  check_stats("ekf");
  check_anchors("stats");
  check_stats("anchors");
  check_ekf("stats");
}

TEST(ConsoleCommands, ParamListShowsEveryParameterWithBounds) {
  ConsoleRig rig(sim_recording());
  const auto lines = reply_lines(rig.command("param list"));
  ASSERT_EQ(lines.size(), kNumParams + 1);
  EXPECT_EQ(kv(lines[0], "count"), std::to_string(kNumParams));
  for (size_t i = 0; i < kNumParams; ++i) {
    EXPECT_EQ(kv(lines[i + 1], "name"), kParamDefs[i].name);
    EXPECT_FALSE(kv(lines[i + 1], "min").empty());
    EXPECT_FALSE(kv(lines[i + 1], "max").empty());
  }
}

TEST(ConsoleCommands, ParamGetAndSetApplyLiveAndReplyWithOldAndNewValue) {
  ConsoleRig rig(sim_recording());
  auto lines = reply_lines(rig.command("param get gate.innov_sigma"));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(kv(lines[0], "value"), "5");
  EXPECT_NE(lines[0].find("doc=\""), std::string::npos);

  lines = lines_with_prefix(reply_lines(rig.command("param set gate.innov_sigma 7.5")), "param ");
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "param name=gate.innov_sigma value=7.5 old=5");
  EXPECT_EQ(rig.app.params().get(ParamId::kGateInnovSigma), 7.5F);

  lines = reply_lines(rig.command("param reset gate.innov_sigma"));
  EXPECT_EQ(lines.at(0), "param name=gate.innov_sigma value=5 old=7.5");
  EXPECT_EQ(rig.app.params().get(ParamId::kGateInnovSigma), 5.0F);
}

TEST(ConsoleCommands, SettingAParameterChangesValidationOfTheNextFrames) {
  ConsoleRig rig(sim_recording());
  rig.run_s(2.0);
  (void)rig.command("param set uwb.max_range 1");
  const uint32_t accepted = rig.app.stats().uwb.accepted;
  const uint32_t out_of_range = rig.app.stats().uwb.rejected[static_cast<size_t>(RejectReason::kOutOfRange)];
  rig.run_s(2.0);
  EXPECT_EQ(rig.app.stats().uwb.accepted, accepted);
  EXPECT_GT(rig.app.stats().uwb.rejected[static_cast<size_t>(RejectReason::kOutOfRange)], out_of_range + 50);
}

TEST(ConsoleCommands, BadParamValuesAreRejectedWithOneErrorLineAndLeaveTheParameterUnchanged) {
  ConsoleRig rig(sim_recording());
  const Params before = rig.app.params();
  for (const char* cmd : {"param set can.tx_enable 2", "param set can.tx_enable -1", "param set uwb.sigma 0",
                          "param set uwb.sigma 1e9", "param set uwb.sigma nan", "param set uwb.sigma inf",
                          "param set uwb.sigma 0.5x", "param set uwb.sigma abc", "param set uwb.sigma",
                          "param set no.such 1", "param get no.such", "param reset no.such", "param frobnicate",
                          "param", "param set uwb.sigma 0.2 extra"}) {
    const auto lines = reply_lines(rig.command(cmd));
    ASSERT_EQ(lines.size(), 1U) << cmd;
    EXPECT_EQ(lines[0].rfind("error: param: ", 0), 0U) << cmd << " -> " << lines[0];
    EXPECT_TRUE(params_equal(rig.app.params(), before)) << cmd;
  }
  const auto lines = reply_lines(rig.command("param set can.tx_enable 2"));
  EXPECT_EQ(lines.at(0), "error: param: can.tx_enable=2 out of range [0, 1]; unchanged");
}

// The console and the CLI (--param, tests/scripts/cli_errors.cmake) refuse with the
// same words (firmware/param_text.hpp): which parameter, which value, why.
TEST(ConsoleCommands, FractionsOfWholeKindParametersAreRefusedInTheCliWording) {
  ConsoleRig rig(sim_recording());
  const Params before = rig.app.params();
  EXPECT_EQ(reply_lines(rig.command("param set can.tx_enable 0.5")).at(0),
            "error: param: can.tx_enable=0.5 is not a whole number (bool parameter); unchanged");
  EXPECT_EQ(reply_lines(rig.command("param set gate.policy 3.5")).at(0),
            "error: param: gate.policy=3.5 is not a whole number (enum parameter); unchanged");
  EXPECT_EQ(reply_lines(rig.command("param set uwb.sigma abc")).at(0),
            "error: param: uwb.sigma=abc is not a finite number; unchanged");
  EXPECT_EQ(reply_lines(rig.command("param set uwb.sigma 9")).at(0),
            "error: param: uwb.sigma=9 out of range [0.01, 5]; unchanged");
  EXPECT_TRUE(params_equal(rig.app.params(), before));
  char why[kParamErrorMax];
  const ParamDef* def = nullptr;
  float value = 0.0F;
  ASSERT_FALSE(ok(parse_param_value("gate.policy", "3.5", &def, &value, why, sizeof why)));
  EXPECT_STREQ(why, "gate.policy=3.5 is not a whole number (enum parameter)");
  ASSERT_TRUE(ok(parse_param_value("gate.policy", "3", &def, &value, why, sizeof why)));
  EXPECT_EQ(def->index, ParamId::kGatePolicy);
  EXPECT_EQ(value, 3.0F);
}

TEST(ConsoleCommands, ParamSaveAndLoadGoThroughTheParameterStore) {
  const std::string path = (std::filesystem::temp_directory_path() / "uwbnav_console_params.bin").string();
  std::filesystem::remove(path);
  hal::FileParamStore store(path);
  ConsoleRig rig(sim_recording(), &store);
  EXPECT_EQ(reply_lines(rig.command("param load")).at(0), "error: param: load failed (empty); values unchanged");
  (void)rig.command("param set gate.innov_sigma 9");
  EXPECT_EQ(reply_lines(rig.command("param save")).at(0), "param saved=ok count=" + std::to_string(kNumParams));
  EXPECT_TRUE(std::filesystem::exists(path));
  (void)rig.command("param set gate.innov_sigma 3");
  EXPECT_EQ(reply_lines(rig.command("param load")).at(0), "param loaded=ok count=" + std::to_string(kNumParams));
  EXPECT_EQ(rig.app.params().get(ParamId::kGateInnovSigma), 9.0F);
  // Reset of all parameters returns to the table defaults.
  EXPECT_EQ(reply_lines(rig.command("param reset")).at(0), "param reset=all count=" + std::to_string(kNumParams));
  EXPECT_EQ(rig.app.params().get(ParamId::kGateInnovSigma), 5.0F);
  std::filesystem::remove(path);
}

TEST(ConsoleCommands, ParamSaveOnABoardWithoutStoreSaysSo) {
  ConsoleRig rig(sim_recording());
  EXPECT_EQ(reply_lines(rig.command("param save")).at(0), "error: param: save failed (unsupported)");
}

TEST(ConsoleCommands, LogLevelShowsAndSetsTheThresholdThroughTheParameter) {
  ConsoleRig rig(sim_recording());
  EXPECT_EQ(kv(reply_lines(rig.command("log level")).at(0), "level"), "info");
  EXPECT_EQ(kv(reply_lines(rig.command("log level debug")).at(0), "level"), "debug");
  EXPECT_EQ(rig.app.params().get(ParamId::kConsoleLogLevel), 3.0F);
  EXPECT_EQ(logger().level(), LogLevel::kDebug);
  EXPECT_EQ(reply_lines(rig.command("log level loud")).at(0), "error: log: unknown level 'loud' (error|warn|info|debug)");
  EXPECT_EQ(reply_lines(rig.command("log")).at(0).rfind("error: log: usage", 0), 0U);
  EXPECT_EQ(logger().level(), LogLevel::kDebug);
}

TEST(ConsoleCommands, LogLinesFromTheFirmwareReachTheConsole) {
  ConsoleRig rig(sim_recording());
  const auto lines = reply_lines(rig.command("param set gate.innov_sigma 6"));
  const auto logs = lines_with_prefix(lines, "log ");
  ASSERT_EQ(logs.size(), 1U);
  EXPECT_EQ(kv(logs[0], "level"), "info");
  EXPECT_EQ(kv(logs[0], "mod"), "console");
  (void)rig.command("log level warn");
  EXPECT_TRUE(lines_with_prefix(reply_lines(rig.command("param set gate.innov_sigma 7")), "log ").empty());
}

TEST(ConsoleCommands, StreamPosEmitsAtTheRequestedRateUntilStopped) {
  ConsoleRig rig(sim_recording());
  auto lines = reply_lines(rig.command("stream pos 10"));
  EXPECT_EQ(lines.at(0), "stream pos_hz=10 stats_hz=0 anchors_hz=0");
  rig.serial.output.clear();
  rig.run_s(2.0);
  const auto pos = lines_with_prefix(testing::split_lines(rig.serial.output), "$pos ");
  EXPECT_GE(pos.size(), 19U);
  EXPECT_LE(pos.size(), 21U);
  EXPECT_FALSE(kv(pos.back(), "x_m").empty());
  EXPECT_FALSE(kv(pos.back(), "mode").empty());

  (void)rig.command("stream stats 5");
  (void)rig.command("stream anchors 1");
  rig.serial.output.clear();
  rig.run_s(1.0);
  const auto out = testing::split_lines(rig.serial.output);
  EXPECT_GE(lines_with_prefix(out, "$stats ").size(), 4U);
  EXPECT_GE(lines_with_prefix(out, "$anchor ").size(), sim_recording().site.num_anchors);

  lines = reply_lines(rig.command("stream off"));
  EXPECT_EQ(lines_with_prefix(lines, "stream ").at(0), "stream pos_hz=0 stats_hz=0 anchors_hz=0");
  rig.serial.output.clear();
  rig.run_s(1.0);
  EXPECT_EQ(rig.serial.output, "");
}

TEST(ConsoleCommands, StreamRejectsUnknownStreamsAndRates) {
  ConsoleRig rig(sim_recording());
  EXPECT_EQ(reply_lines(rig.command("stream gps 10")).at(0), "error: stream: unknown stream 'gps' (pos|stats|anchors)");
  EXPECT_EQ(reply_lines(rig.command("stream pos 1000")).at(0), "error: stream: rate '1000' not in 0..100 Hz (or off)");
  EXPECT_EQ(reply_lines(rig.command("stream pos -5")).at(0), "error: stream: rate '-5' not in 0..100 Hz (or off)");
  EXPECT_EQ(reply_lines(rig.command("stream pos")).at(0), "error: stream: usage: stream [pos|stats|anchors RATE_HZ|off]");
  EXPECT_EQ(rig.app.console().stream_rate_hz(StreamKind::kPos), 0U);
}

TEST(ConsoleCommands, ResetStatsZeroesTheCountersAndResetFilterRestartsTheEstimator) {
  ConsoleRig rig(sim_recording());
  rig.run_s(15.0);
  ASSERT_GT(rig.app.stats().uwb.received, 0U);
  EXPECT_EQ(reply_lines(rig.command("reset stats")).at(0), "reset stats=ok");
  EXPECT_LT(rig.app.stats().uwb.received, 5U);  // the cycles after the reset only
  ASSERT_NE(rig.app.last_output().status, NavStatus::kInitialising);
  const auto lines = reply_lines(rig.command("reset filter"));
  EXPECT_EQ(lines_with_prefix(lines, "reset ").at(0), "reset filter=ok");
  rig.tick();  // the output of the cycle after the reset
  EXPECT_EQ(rig.app.last_output().status, NavStatus::kInitialising);
  EXPECT_EQ(reply_lines(rig.command("reset everything")).at(0), "error: reset: usage: reset filter|stats");
}

TEST(ConsoleCommands, StatusCountsEveryKindOfResetIncludingTheOperatorsResetFilter) {
  ConsoleRig rig(sim_recording());
  rig.run_s(10.0);
  const NavDiagnostics& dg = rig.app.navigator().diagnostics();
  auto status = [&]() { return reply_lines(rig.command("status")).at(0); };
  std::string l = status();
  EXPECT_EQ(kv(l, "operator_resets"), "0");
  EXPECT_EQ(kv(l, "resets"), std::to_string(dg.resets));
  EXPECT_EQ(kv(l, "inflations"), std::to_string(dg.inflations));
  EXPECT_EQ(kv(l, "reanchors"), std::to_string(dg.reanchors));
  EXPECT_EQ(kv(l, "reinits"), std::to_string(dg.reinits));
  EXPECT_EQ(kv(l, "integrity_fails"), std::to_string(dg.integrity_fails));
  EXPECT_EQ(kv(l, "short_fails"), std::to_string(dg.short_range_fails));
  (void)rig.command("reset filter");
  (void)rig.command("reset filter");
  l = status();
  EXPECT_EQ(kv(l, "operator_resets"), "2");
  const auto stats = reply_lines(rig.command("stats"));
  EXPECT_EQ(kv(lines_with_prefix(stats, "stats nav ").at(0), "operator_resets"), "2");
}

TEST(ConsoleCommands, ResetStatsZeroesInputCanNavigatorAndConsoleCounters) {
  ConsoleRig rig(sim_recording());
  rig.run_s(15.0);
  (void)rig.command("reset filter");
  auto stats = reply_lines(rig.command("stats"));
  const std::string nav_before = lines_with_prefix(stats, "stats nav ").at(0);
  const std::string can_before = lines_with_prefix(stats, "stats can ").at(0);
  ASSERT_GT(kv_num(nav_before, "ranges_used"), 100.0);
  ASSERT_GT(kv_num(can_before, "tx_ok"), 500.0);
  const uint32_t published_before = rig.app.can_tx_stats().sent;
  ASSERT_GT(published_before, 500U);
  EXPECT_EQ(kv(nav_before, "operator_resets"), "1");
  EXPECT_EQ(reply_lines(rig.command("reset stats")).at(0), "reset stats=ok");
  stats = reply_lines(rig.command("stats"));  // runs a few cycles: counts since the reset only
  const std::string nav = lines_with_prefix(stats, "stats nav ").at(0);
  const std::string can = lines_with_prefix(stats, "stats can ").at(0);
  EXPECT_LT(kv_num(nav, "ranges_used"), 20.0);
  EXPECT_LT(kv_num(nav, "imu_samples"), 100.0);
  EXPECT_EQ(kv(nav, "operator_resets"), "0");
  EXPECT_LT(kv_num(can, "tx_ok"), 100.0);
  EXPECT_LT(rig.app.can_tx_stats().sent, 100U);  // the publisher's counters too
  EXPECT_LT(kv_num(lines_with_prefix(stats, "stats src=").at(0), "received"), 100.0);
  EXPECT_EQ(kv(reply_lines(rig.command("status")).at(0), "operator_resets"), "0");
  // The estimator and the bus keep counting monotonically (CAN diagnostics carry those).
  EXPECT_EQ(rig.app.navigator().diagnostics().operator_resets, 1U);
}

TEST(ConsoleCommands, ParamListFiltersByGlobAndByChangedFromDefault) {
  ConsoleRig rig(sim_recording());
  size_t gate = 0;
  for (const ParamDef& d : kParamDefs) gate += std::string(d.name).rfind("gate.", 0) == 0 ? 1U : 0U;
  ASSERT_GT(gate, 2U);
  auto lines = reply_lines(rig.command("param list gate.*"));
  ASSERT_EQ(lines.size(), gate + 1);
  EXPECT_EQ(kv(lines[0], "count"), std::to_string(gate));
  for (size_t i = 1; i < lines.size(); ++i) EXPECT_EQ(kv(lines[i], "name").rfind("gate.", 0), 0U) << lines[i];
  lines = reply_lines(rig.command("param list -c"));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "param count=0");
  (void)rig.command("param set uwb.sigma 0.3");
  (void)rig.command("param set gate.innov_sigma 9");
  lines = reply_lines(rig.command("param list -c"));
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(kv(lines[1], "name"), "uwb.sigma");
  EXPECT_EQ(kv(lines[2], "name"), "gate.innov_sigma");
  lines = reply_lines(rig.command("param list -c gate.*"));
  ASSERT_EQ(lines.size(), 2U);
  EXPECT_EQ(kv(lines[1], "name"), "gate.innov_sigma");
  lines = reply_lines(rig.command("param list uwb.sig?a"));
  ASSERT_EQ(lines.size(), 2U);
  EXPECT_EQ(kv(lines[1], "value"), "0.3");
  EXPECT_EQ(reply_lines(rig.command("param list no.such.*")).at(0), "param count=0");
  EXPECT_EQ(reply_lines(rig.command("param list -x")).at(0).rfind("error: param: usage: param list [-c] [GLOB]", 0),
            0U);
  EXPECT_EQ(reply_lines(rig.command("param list")).size(), kNumParams + 1);  // no filter left behind
}

TEST(ConsoleCommands, HistoryListsAndBangBangRepeats) {
  ConsoleRig rig(sim_recording());
  (void)rig.command("version");
  (void)rig.command("log level");
  auto lines = reply_lines(rig.command("history"));
  ASSERT_EQ(lines.size(), 4U);
  EXPECT_EQ(lines[0], "history count=3");
  EXPECT_EQ(lines[1], "history n=1 line=version");
  EXPECT_EQ(lines[3], "history n=3 line=history");
  lines = reply_lines(rig.command("!1"));
  EXPECT_EQ(lines.at(0).rfind("version fw=", 0), 0U);
  lines = reply_lines(rig.command("!!"));
  EXPECT_EQ(lines.at(0).rfind("version fw=", 0), 0U);
  EXPECT_EQ(reply_lines(rig.command("!99")).at(0), "error: history: no entry '!99' (see history)");
  // Cursor-up recalls the previous line as if typed.
  lines = reply_lines(rig.command("\x1b[A"));
  EXPECT_EQ(lines_with_prefix(lines, "version fw=").size(), 1U);
}

TEST(ConsoleCommands, UnknownCommandsAndWrongArgumentsGetOneErrorLine) {
  ConsoleRig rig(sim_recording());
  EXPECT_EQ(reply_lines(rig.command("frobnicate")).at(0), "error: unknown command 'frobnicate' (try help)");
  EXPECT_EQ(reply_lines(rig.command("status now")).at(0), "error: status: takes no arguments");
  EXPECT_EQ(reply_lines(rig.command("ekf -x")).at(0), "error: ekf: usage: ekf [-v]");
  EXPECT_EQ(reply_lines(rig.command("a b c d e f g h i")).at(0), "error: too many arguments (max 8 words)");
  EXPECT_EQ(reply_lines(rig.command("echo maybe")).at(0), "error: echo: usage: echo [on|off]");
  // An empty line just gives the prompt back.
  EXPECT_EQ(rig.command(""), "\r\n> ");
  EXPECT_EQ(rig.app.console().stats().errors, 5U);
}

TEST(ConsoleCommands, OverlongLineAndBinaryGarbageGetOneErrorLineEach) {
  ConsoleRig rig(sim_recording());
  const Params before = rig.app.params();
  auto lines = reply_lines(rig.command("param set uwb.sigma 0.3 " + std::string(300, 'x')));
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0], "error: line too long (324 bytes, max 127), ignored");
  lines = testing::split_lines(rig.command(std::string("param set uwb.sigma 0.3\x01\xff", 25)));
  ASSERT_EQ(lines.size(), 2U);
  EXPECT_EQ(lines[1], "error: non-printable input (2 bytes), line ignored");
  EXPECT_TRUE(params_equal(rig.app.params(), before));
}

TEST(ConsoleCommands, RandomBytesNeverCrashNeverChangeParametersAndTheShellStillAnswers) {
  ConsoleRig rig(sim_recording());
  const Params before = rig.app.params();
  std::mt19937 rng(12345);
  std::string junk;
  for (int i = 0; i < 200000; ++i) junk.push_back(static_cast<char>(rng() & 0xFF));
  rig.serial.type(junk);
  while (rig.serial.pending_input() > 0) rig.tick();
  rig.run_s(1.0);
  EXPECT_TRUE(params_equal(rig.app.params(), before));
  EXPECT_GT(rig.app.console().stats().errors, 0U);
  EXPECT_LE(rig.app.console().stats().max_rx_per_poll, Console::kRxBytesPerPoll);
  EXPECT_LE(rig.app.console().stats().max_commands_per_poll, 1U);
  // Ctrl-C clears whatever partial line the junk left behind.
  const auto lines = reply_lines(rig.command("\x03version"));
  EXPECT_EQ(lines_with_prefix(lines, "version fw=").size(), 1U);
}

TEST(ConsoleCommands, EchoOffSilencesEchoAndPrompt) {
  ConsoleRig rig(sim_recording());
  rig.serial.type("echo off\r");
  rig.run_s(0.05);
  EXPECT_EQ(testing::split_lines(rig.serial.output).back(), "echo off");
  rig.serial.output.clear();
  rig.serial.type("version\r");
  rig.run_s(0.05);
  const auto lines = testing::split_lines(rig.serial.output);
  ASSERT_EQ(lines.size(), 1U);
  EXPECT_EQ(lines[0].rfind("version fw=", 0), 0U);
  EXPECT_EQ(rig.serial.output.find("> "), std::string::npos);
}

}  // namespace
}  // namespace uwbnav
