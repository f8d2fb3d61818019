// Firmware logging: printf-style macros with a module name and a level,
// rate-limited per call site, written as one console line each through a
// LogSink (the console's TX ring on a board, a capture buffer in tests).
// Static memory only; a message that does not fit the line is truncated.
// Formats take strings and integers up to 32 bits: the board's printf is
// integer-only, so floats and 64-bit values are passed as text made by
// firmware/text_format.hpp ("%s").
#pragma once

#include <cstddef>
#include <cstdint>

namespace uwbnav {

enum class LogLevel : uint8_t { kError = 0, kWarn = 1, kInfo = 2, kDebug = 3 };

constexpr const char* log_level_name(LogLevel l) {
  switch (l) {
    case LogLevel::kError: return "error";
    case LogLevel::kWarn: return "warn";
    case LogLevel::kInfo: return "info";
    case LogLevel::kDebug: return "debug";
  }
  return "unknown";
}

// Parses "error|warn|info|debug" (or "0".."3"). Returns false for anything else.
bool parse_log_level(const char* text, LogLevel* out);

// Where finished lines go. `text` has no line terminator; must not block.
class LogSink {
 public:
  virtual ~LogSink() = default;
  virtual void log_line(LogLevel level, const char* text, size_t len) = 0;
};

// Rate-limit state of one call site (one static instance per macro expansion).
struct LogSite {
  uint64_t window_start_us = 0;  // start of the current one-second window [us]
  uint32_t in_window = 0;        // messages emitted in the window
  uint32_t suppressed = 0;       // messages dropped by the limit since the last emitted one
  bool started = false;
};

struct LogCounters {
  uint32_t emitted = 0;      // lines handed to the sink
  uint32_t suppressed = 0;   // dropped by the per-site rate limit
  uint32_t filtered = 0;     // below the level threshold
  uint32_t no_sink = 0;      // emitted while no sink was attached
};

class Logger {
 public:
  static constexpr size_t kLineMax = 192;  // formatted line incl. prefix [bytes]

  void set_sink(LogSink* sink) { sink_ = sink; }
  LogSink* sink() const { return sink_; }
  void set_level(LogLevel level) { level_ = level; }
  LogLevel level() const { return level_; }
  // Messages per second per call site (>= 1).
  void set_rate_per_s(uint32_t rate) { rate_per_s_ = rate == 0 ? 1 : rate; }
  // Loop time stamped on each line and used by the rate limit [us].
  void set_time_us(uint64_t t_us) { now_us_ = t_us; }
  uint64_t time_us() const { return now_us_; }

  bool enabled(LogLevel level) const { return static_cast<uint8_t>(level) <= static_cast<uint8_t>(level_); }
  // Counts a message below the threshold (the macros call this instead of write()).
  void count_filtered() { ++counters_.filtered; }

  // Formats "log t_us=<t> level=<l> mod=<module> msg=<text>[ (suppressed N)]".
  void write(LogSite& site, LogLevel level, const char* module, const char* fmt, ...)
      __attribute__((format(printf, 5, 6)));

  const LogCounters& counters() const { return counters_; }
  void reset_counters() { counters_ = LogCounters{}; }

 private:
  LogSink* sink_ = nullptr;
  LogLevel level_ = LogLevel::kInfo;
  uint32_t rate_per_s_ = 5;
  uint64_t now_us_ = 0;
  LogCounters counters_;
  char line_[kLineMax] = {};
};

// The firmware's one logger (static storage).
Logger& logger();

}  // namespace uwbnav

#define UWBNAV_LOG(level, module, ...)                                   \
  do {                                                                   \
    static ::uwbnav::LogSite uwbnav_log_site_;                           \
    ::uwbnav::Logger& uwbnav_logger_ = ::uwbnav::logger();               \
    if (uwbnav_logger_.enabled(level)) {                                 \
      uwbnav_logger_.write(uwbnav_log_site_, level, module, __VA_ARGS__); \
    } else {                                                             \
      uwbnav_logger_.count_filtered();                                   \
    }                                                                    \
  } while (0)

#define UWBNAV_LOG_ERROR(module, ...) UWBNAV_LOG(::uwbnav::LogLevel::kError, module, __VA_ARGS__)
#define UWBNAV_LOG_WARN(module, ...) UWBNAV_LOG(::uwbnav::LogLevel::kWarn, module, __VA_ARGS__)
#define UWBNAV_LOG_INFO(module, ...) UWBNAV_LOG(::uwbnav::LogLevel::kInfo, module, __VA_ARGS__)
#define UWBNAV_LOG_DEBUG(module, ...) UWBNAV_LOG(::uwbnav::LogLevel::kDebug, module, __VA_ARGS__)
