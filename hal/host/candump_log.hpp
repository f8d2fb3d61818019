// can-utils `candump -l` log files: writer, reader, line format/parse, and a
// CanBus decorator that tees the frames it sends (and optionally receives)
// into a log. Lines: "(1700000000.123456) can0 1A3#DEADBEEF",
// FD: "(…) can0 1A3##1DEADBEEF" (flags nibble: 1 = BRS, 2 = ESI), extended ids
// with 8 hex digits, error frames as 8 hex digits including CAN_ERR_FLAG 0x20000000.
// Readable by canplayer, log2asc and python-can's CanutilsLogReader.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "hal/hal.hpp"

namespace uwbnav::hal {

constexpr uint32_t kCanErrFlag = 0x20000000U;  // SocketCAN CAN_ERR_FLAG as written in logs
constexpr uint32_t kCanEffFlag = 0x80000000U;  // SocketCAN CAN_EFF_FLAG

// One log line without the newline. Timestamp = (epoch_offset_us + frame.t_us).
std::string format_candump_line(const CanFrame& frame, const std::string& ifname, uint64_t epoch_offset_us = 0);

// Parses one line. kOk: frame (t_us = timestamp in us) and ifname filled.
// kInvalidArgument: malformed. kUnsupported: remote (RTR) frame (no CanFrame form).
[[nodiscard]] Status parse_candump_line(const std::string& line, CanFrame& frame, std::string& ifname);

class CandumpLogWriter {
 public:
  CandumpLogWriter() = default;
  ~CandumpLogWriter();
  CandumpLogWriter(const CandumpLogWriter&) = delete;
  CandumpLogWriter& operator=(const CandumpLogWriter&) = delete;

  // epoch_offset_us is added to every frame's t_us (0: log shows the board's
  // time base, e.g. replay seconds; a wall-clock epoch makes logs look live).
  [[nodiscard]] Status open(const std::string& path, const std::string& ifname = "can0",
                            uint64_t epoch_offset_us = 0);
  [[nodiscard]] Status write(const CanFrame& frame);
  [[nodiscard]] Status close();
  bool is_open() const { return f_ != nullptr; }
  uint64_t lines() const { return lines_; }

 private:
  std::FILE* f_ = nullptr;
  std::string ifname_;
  uint64_t epoch_offset_us_ = 0;
  uint64_t lines_ = 0;
};

class CandumpLogReader {
 public:
  CandumpLogReader() = default;
  ~CandumpLogReader();
  CandumpLogReader(const CandumpLogReader&) = delete;
  CandumpLogReader& operator=(const CandumpLogReader&) = delete;

  [[nodiscard]] Status open(const std::string& path);
  // kOk: next frame. kEmpty: end of file. Malformed lines and RTR frames are
  // skipped and counted in skipped().
  [[nodiscard]] Status next(CanFrame& frame, std::string* ifname = nullptr);
  uint64_t skipped() const { return skipped_; }

 private:
  std::FILE* f_ = nullptr;
  uint64_t skipped_ = 0;
};

// Decorator: forwards to `inner`; every frame inner accepts (kOk) is written
// to the log, received frames too when log_rx. Log write errors are counted,
// never returned to the firmware.
class CanLogTee : public CanBus {
 public:
  CanLogTee(CanBus& inner, CandumpLogWriter& log, bool log_rx = false)
      : inner_(inner), log_(log), log_rx_(log_rx) {}

  [[nodiscard]] Status send(const CanFrame& frame) override;
  [[nodiscard]] Status receive(CanFrame& out) override;
  CanBusState state() const override { return inner_.state(); }
  const CanCounters& counters() const override { return inner_.counters(); }
  void reset_counters() override { inner_.reset_counters(); }
  uint32_t log_errors() const { return log_errors_; }

 private:
  CanBus& inner_;
  CandumpLogWriter& log_;
  bool log_rx_;
  uint32_t log_errors_ = 0;
};

}  // namespace uwbnav::hal
