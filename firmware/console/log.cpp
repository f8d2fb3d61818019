// Firmware logger: level filter, one-second per-site rate limit, line formatting.
#include "firmware/console/log.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "firmware/text_format.hpp"

namespace uwbnav {
namespace {

constexpr uint64_t kRateWindowUs = 1000000;  // rate-limit window [us]

Logger g_logger;

// Appends to a fixed buffer; keeps it NUL-terminated and reports the length used.
size_t append(char* buf, size_t cap, size_t n, const char* fmt, ...) __attribute__((format(printf, 4, 5)));
size_t append(char* buf, size_t cap, size_t n, const char* fmt, ...) {
  if (n + 1 >= cap) return n;
  va_list ap;
  va_start(ap, fmt);
  const int w = std::vsnprintf(buf + n, cap - n, fmt, ap);
  va_end(ap);
  if (w < 0) return n;
  const size_t used = n + static_cast<size_t>(w);
  return used < cap ? used : cap - 1;
}

}  // namespace

Logger& logger() { return g_logger; }

bool parse_log_level(const char* text, LogLevel* out) {
  static constexpr const char* kNames[] = {"error", "warn", "info", "debug"};
  for (uint8_t i = 0; i < 4; ++i) {
    const char digit[2] = {static_cast<char>('0' + i), '\0'};
    if (std::strcmp(text, kNames[i]) == 0 || std::strcmp(text, digit) == 0) {
      *out = static_cast<LogLevel>(i);
      return true;
    }
  }
  return false;
}

void Logger::write(LogSite& site, LogLevel level, const char* module, const char* fmt, ...) {
  if (!site.started || now_us_ < site.window_start_us || now_us_ - site.window_start_us >= kRateWindowUs) {
    site.started = true;
    site.window_start_us = now_us_;
    site.in_window = 0;
  }
  if (site.in_window >= rate_per_s_) {
    ++site.suppressed;
    ++counters_.suppressed;
    return;
  }
  ++site.in_window;

  char t_us[kU64TextMax];
  (void)format_u64(t_us, sizeof t_us, now_us_);
  size_t n = append(line_, sizeof line_, 0, "log t_us=%s level=%s mod=%s msg=", t_us, log_level_name(level), module);
  if (n + 1 < sizeof line_) {
    va_list ap;
    va_start(ap, fmt);
    const int w = std::vsnprintf(line_ + n, sizeof line_ - n, fmt, ap);
    va_end(ap);
    if (w > 0) n = n + static_cast<size_t>(w) < sizeof line_ ? n + static_cast<size_t>(w) : sizeof line_ - 1;
  }
  if (site.suppressed > 0) {
    n = append(line_, sizeof line_, n, " (suppressed %lu)", static_cast<unsigned long>(site.suppressed));
    site.suppressed = 0;
  }
  // A message must stay one line: control characters become spaces.
  for (size_t i = 0; i < n; ++i) {
    if (static_cast<unsigned char>(line_[i]) < 0x20U) line_[i] = ' ';
  }
  if (sink_ == nullptr) {
    ++counters_.no_sink;
    return;
  }
  ++counters_.emitted;
  sink_->log_line(level, line_, n);
}

}  // namespace uwbnav
