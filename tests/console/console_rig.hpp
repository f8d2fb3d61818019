// Console test rig: an in-memory serial port (typed input, captured output,
// optional slow reader) and an App on a lockstep replay board, plus helpers to
// type a command and split the reply into lines / key=value fields.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "firmware/app.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::testing {

// Serial port backed by strings. At most `write_cap` bytes are accepted per
// cycle (a slow reader); read() hands out what was typed.
class MemSerialPort final : public hal::SerialPort {
 public:
  std::string input;
  size_t in_pos = 0;
  std::string output;
  size_t write_cap = SIZE_MAX;  // bytes the reader takes per cycle (ConsoleRig::tick refills)
  size_t write_room = SIZE_MAX;
  uint64_t total_read = 0;
  uint64_t total_written = 0;

  void type(const std::string& s) { input += s; }
  size_t pending_input() const { return input.size() - in_pos; }
  size_t read(uint8_t* buf, size_t cap) override {
    const size_t n = std::min(cap, input.size() - in_pos);
    std::copy(input.begin() + static_cast<std::ptrdiff_t>(in_pos),
              input.begin() + static_cast<std::ptrdiff_t>(in_pos + n), buf);
    in_pos += n;
    total_read += n;
    return n;
  }
  size_t write(const uint8_t* buf, size_t len) override {
    const size_t n = std::min(len, write_room);
    write_room -= n;
    output.append(reinterpret_cast<const char*>(buf), n);
    total_written += n;
    return n;
  }
};

// One simulated recording per seed, generated once per test process.
inline const dataset::Recording& sim_recording(uint64_t seed = 7) {
  static std::vector<std::pair<uint64_t, dataset::Recording>> cache;
  for (const auto& [s, rec] : cache) {
    if (s == seed) return rec;
  }
  cache.emplace_back(seed, dataset::Recording{});
  std::string err;
  const Status st = sim::simulate("parking_nlos", seed, cache.back().second, &err);
  EXPECT_TRUE(ok(st)) << err;
  return cache.back().second;
}

inline uint64_t first_cycle_us(const dataset::Recording& rec) {
  uint64_t t0 = UINT64_MAX;
  if (!rec.imu.empty()) t0 = rec.imu.front().t_us;
  if (!rec.uwb.empty()) t0 = std::min(t0, rec.uwb.front().range.t_us);
  if (t0 == UINT64_MAX) t0 = 0;
  return (t0 / kCyclePeriodUs + 1) * kCyclePeriodUs;
}

// The first `seconds` of a recording: after that the sensors fall silent and
// the firmware's counters and filter hold still (stable values to compare with).
inline dataset::Recording truncated(const dataset::Recording& full, double seconds) {
  dataset::Recording rec = full;
  const uint64_t t_end = first_cycle_us(rec) + static_cast<uint64_t>(seconds * 1e6);
  rec.imu.erase(std::remove_if(rec.imu.begin(), rec.imu.end(), [&](const ImuSample& s) { return s.t_us > t_end; }),
                rec.imu.end());
  rec.uwb.erase(std::remove_if(rec.uwb.begin(), rec.uwb.end(),
                               [&](const dataset::UwbRow& r) { return r.range.t_us > t_end; }),
                rec.uwb.end());
  return rec;
}

// An App on a replay board whose serial port is a MemSerialPort.
class ConsoleRig {
 public:
  // The rig replays the recording by reference: it must outlive the rig.
  explicit ConsoleRig(dataset::Recording&&, hal::ParamStore* = nullptr) = delete;
  explicit ConsoleRig(const dataset::Recording& rec, hal::ParamStore* store = nullptr)
      : sources_(rec),
        board_{sources_.imu, sources_.uwb, can, serial, clock_, store != nullptr ? *store : empty_, rec.site},
        app(board_),
        t_us(first_cycle_us(rec)) {
    // The logger is process-wide (one per boot on a board); a rig is a fresh
    // boot, so counters left by an earlier rig in the same process go.
    logger().reset_counters();
    EXPECT_TRUE(ok(app.init()));
    tick();  // banner and first prompt
    serial.output.clear();
  }

  void tick() {
    serial.write_room = serial.write_cap;
    clock_.sleep_until_us(t_us);
    app.tick(t_us);
    hal::CanFrame f;
    while (ok(can.receive_sent(f))) {
    }
    t_us += kCyclePeriodUs;
    ++ticks;
  }
  void run_s(double seconds) {
    const auto n = static_cast<uint64_t>(seconds * 1e6 / kCyclePeriodUs);
    for (uint64_t i = 0; i < n; ++i) tick();
  }

  // Types `line` + CR and ticks until the prompt is back and the TX ring is
  // empty. Returns everything the console wrote meanwhile; *ticks_used gets
  // how many cycles that took.
  std::string command(const std::string& line, uint64_t* ticks_used = nullptr, uint64_t max_ticks = 1000) {
    serial.output.clear();
    serial.type(line + "\r");
    uint64_t n = 0;
    while (n < max_ticks) {
      tick();
      ++n;
      if (serial.pending_input() == 0 && app.console().tx_pending() == 0 &&
          serial.output.find("\r\n> ") != std::string::npos) {
        break;
      }
    }
    if (ticks_used != nullptr) *ticks_used = n;
    return serial.output;
  }

  hal::MemCanBus can;
  MemSerialPort serial;

 private:
  hal::ReplaySources sources_;
  hal::LockstepClock clock_;
  hal::EmptyParamStore empty_;
  hal::Board board_;

 public:
  App app;
  uint64_t t_us;
  uint64_t ticks = 0;
};

// Splits console output into lines as a terminal shows them: CR LF ends a
// line, a bare CR returns to its start and ESC[K erases it (prompt redraws).
// The unfinished last line (the prompt) is dropped.
inline std::vector<std::string> split_lines(const std::string& out) {
  std::vector<std::string> lines;
  size_t pos = 0;
  for (;;) {
    const size_t e = out.find("\r\n", pos);
    if (e == std::string::npos) break;
    std::string line = out.substr(pos, e - pos);
    const size_t cr = line.rfind('\r');
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (line.rfind("\x1b[K", 0) == 0) line = line.substr(3);
    lines.push_back(line);
    pos = e + 2;
  }
  return lines;
}

// Reply lines of a command: all lines after the echoed command line, with the
// "> " prompt that precedes the next line stripped.
inline std::vector<std::string> reply_lines(const std::string& out) {
  std::vector<std::string> lines = split_lines(out);
  if (!lines.empty()) lines.erase(lines.begin());
  for (auto& l : lines) {
    if (l.rfind("> ", 0) == 0) l = l.substr(2);
  }
  return lines;
}

inline std::vector<std::string> lines_with_prefix(const std::vector<std::string>& lines, const std::string& prefix) {
  std::vector<std::string> out;
  for (const auto& l : lines) {
    if (l.rfind(prefix, 0) == 0) out.push_back(l);
  }
  return out;
}

// Value of `key` in a "tag key=value key=value" line; empty when absent.
inline std::string kv(const std::string& line, const std::string& key) {
  const std::string pat = " " + key + "=";
  const size_t p = line.find(pat);
  if (p == std::string::npos) return "";
  const size_t b = p + pat.size();
  const size_t e = line.find(' ', b);
  return line.substr(b, e == std::string::npos ? std::string::npos : e - b);
}

inline double kv_num(const std::string& line, const std::string& key) {
  const std::string v = kv(line, key);
  EXPECT_FALSE(v.empty()) << "no " << key << " in: " << line;
  return std::strtod(v.c_str(), nullptr);
}

}  // namespace uwbnav::testing
