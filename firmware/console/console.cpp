// Console core: input budget, line handling, command dispatch, paced replies,
// streams and the bounded TX path (see console.hpp; commands in console_commands.cpp).
#include "firmware/console/console.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include "estimator/params.hpp"
#include "firmware/app.hpp"
#include "firmware/text_format.hpp"

namespace uwbnav {
namespace {

constexpr size_t kMarkerMax = 40;      // "[dropped N bytes]\r\n" [bytes]
constexpr size_t kMaxJobLinesPerPoll = 16;
constexpr size_t kLineCap = Console::kOutLineMax - 2;  // reply text without CR LF [bytes]

}  // namespace

Console::Console(App& app) : app_(app) { logger().set_sink(this); }

Console::~Console() {
  if (logger().sink() == this) logger().set_sink(nullptr);
}

void Console::apply_log_params() {
  const Params& p = app_.params();
  logger().set_level(static_cast<LogLevel>(static_cast<uint8_t>(p.get(ParamId::kConsoleLogLevel))));
  logger().set_rate_per_s(static_cast<uint32_t>(p.get(ParamId::kConsoleLogRate)));
  logger().set_time_us(now_us_);
}

void Console::poll(uint64_t now_us) {
  now_us_ = now_us;
  apply_log_params();
  poll_commands_ = 0;
  if (!banner_done_) {
    banner_done_ = true;
    banner();
  }
  if (job_ == Job::kNone) process_input();
  run_job();
  run_streams();
  redraw_prompt();
  flush();
  if (poll_commands_ > stats_.max_commands_per_poll) stats_.max_commands_per_poll = poll_commands_;
}

// Reads and handles at most kRxBytesPerPoll bytes and at most one line. Input
// waits in the port while a long reply is being paced out or while the TX ring
// is short of room for a reply (a slow reader slows the console, not the loop).
void Console::process_input() {
  size_t read_this_poll = 0;
  size_t fed = 0;
  hal::SerialPort& port = app_.board().serial;
  while (poll_commands_ == 0 && fed < kRxBytesPerPoll && tx_.free() >= kReplyReserve) {
    if (rx_pos_ == rx_len_) {
      rx_pos_ = 0;
      rx_len_ = 0;
      if (read_this_poll >= kRxBytesPerPoll) break;
      const size_t n = port.read(rx_buf_, kRxBytesPerPoll - read_this_poll);
      if (n == 0) break;
      rx_len_ = n <= kRxBytesPerPoll - read_this_poll ? n : kRxBytesPerPoll - read_this_poll;
      read_this_poll += rx_len_;
      stats_.rx_bytes += rx_len_;
    }
    const LineEditor::Event e = editor_.feed(rx_buf_[rx_pos_++]);
    ++fed;
    if (e != LineEditor::Event::kNone) prompt_visible_ = false;  // the cursor moved to a new line
    if (echo_ && editor_.echo_len() > 0) queue_raw(editor_.echo(), editor_.echo_len());
    switch (e) {
      case LineEditor::Event::kNone:
        break;
      case LineEditor::Event::kLine:
        ++stats_.lines;
        handle_line(editor_.line());
        break;
      case LineEditor::Event::kOverlong:
        ++stats_.lines;
        ++stats_.overlong_lines;
        ++poll_commands_;
        error("line too long (%lu bytes, max %lu), ignored", static_cast<unsigned long>(editor_.overlong_count()),
              static_cast<unsigned long>(LineEditor::kMaxChars));
        prompt();
        break;
      case LineEditor::Event::kGarbage:
        ++stats_.lines;
        ++stats_.garbage_lines;
        ++poll_commands_;
        error("non-printable input (%lu bytes), line ignored", static_cast<unsigned long>(editor_.garbage_count()));
        prompt();
        break;
      case LineEditor::Event::kCancel:
        prompt();
        break;
    }
  }
  if (read_this_poll > stats_.max_rx_per_poll) stats_.max_rx_per_poll = static_cast<uint32_t>(read_this_poll);
}

// History expansion (!! and !N), then execution of one line.
void Console::handle_line(const char* line) {
  while (*line == ' ') ++line;
  if (*line == '\0') {
    prompt();
    return;
  }
  ++poll_commands_;
  const char* text = line;
  if (line[0] == '!') {
    uint32_t seq = 0;
    if (std::strcmp(line, "!!") == 0) {
      seq = editor_.history_newest();
    } else {
      char* endp = nullptr;
      const unsigned long v = std::strtoul(line + 1, &endp, 10);
      if (endp != line + 1 && *endp == '\0') seq = static_cast<uint32_t>(v);
    }
    text = editor_.history_find(seq);
    if (text == nullptr) {
      error("history: no entry '%s' (see history)", line);
      prompt();
      return;
    }
  }
  std::strncpy(cmd_, text, sizeof cmd_ - 1);
  cmd_[sizeof cmd_ - 1] = '\0';
  editor_.history_add(cmd_);
  execute(cmd_);
}

void Console::execute(char* line) {
  ++stats_.commands;
  char* argv[kMaxArgs];
  size_t argc = 0;
  char* p = line;
  for (;;) {
    while (*p == ' ') ++p;
    if (*p == '\0') break;
    if (argc == kMaxArgs) {
      error("too many arguments (max %lu words)", static_cast<unsigned long>(kMaxArgs));
      prompt();
      return;
    }
    argv[argc++] = p;
    while (*p != '\0' && *p != ' ') ++p;
    if (*p == ' ') *p++ = '\0';
  }
  for (size_t i = 0; i < kNumCommands; ++i) {
    if (std::strcmp(argv[0], kCommands[i].name) == 0) {
      (this->*kCommands[i].handler)(argc, argv);
      if (job_ == Job::kNone) prompt();
      return;
    }
  }
  error("unknown command '%s' (try help)", argv[0]);
  prompt();
}

void Console::start_job(Job job, bool verbose) {
  job_ = job;
  job_step_ = 0;
  job_verbose_ = verbose;
  take_snapshot(job);
}

void Console::take_snapshot(Job job) {
  snap_.t_us = app_.last_tick_us();
  const Navigator& nav = app_.navigator();
  if (job == Job::kStats) {
    StatsPart& part = *::new (&snap_.part.stats) StatsPart();
    part.app = app_.stats();
    part.nav = app_.nav_counters();
    part.can = app_.board().can.counters();
    part.can_state = app_.board().can.state();
  } else if (job == Job::kAnchors) {
    AnchorsPart& part = *::new (&snap_.part.anchors) AnchorsPart();
    const size_t n = nav.num_anchors();
    part.num_anchors = n < kMaxAnchors ? n : kMaxAnchors;
    for (size_t i = 0; i < part.num_anchors; ++i) part.anchors[i] = nav.anchor_status(i);
  } else if (job == Job::kEkf) {
    EkfPart& part = *::new (&snap_.part.ekf) EkfPart();
    nav.state_vector(part.state);
    for (size_t r = 0; r < Navigator::kErrorStateSize; ++r) {
      for (size_t c = 0; c < Navigator::kErrorStateSize; ++c) part.cov[r][c] = nav.covariance(r, c);
    }
  }
}

bool Console::job_step() {
  const size_t step = job_step_++;
  switch (job_) {
    case Job::kNone: return false;
    case Job::kHelp: return step_help(step);
    case Job::kParamList: return step_param_list(step);
    case Job::kAnchors: return step_anchors(step);
    case Job::kEkf: return step_ekf(step);
    case Job::kStats: return step_stats(step);
    case Job::kHistory: return step_history(step);
    case Job::kCal: return step_cal(step);
  }
  return false;
}

// Paces a long reply: a line is produced only when it is sure to fit.
void Console::run_job() {
  size_t lines = 0;
  while (job_ != Job::kNone && lines < kMaxJobLinesPerPoll && tx_.free() >= kOutLineMax + kMarkerMax) {
    ++lines;
    if (!job_step()) {
      job_ = Job::kNone;
      prompt();
    }
  }
}

void Console::run_streams() {
  for (size_t k = 0; k < static_cast<size_t>(StreamKind::kCount); ++k) {
    const uint32_t rate = stream_rate_hz_[k];
    if (rate == 0 || now_us_ < stream_next_us_[k]) continue;
    const uint64_t period_us = 1000000U / rate;
    stream_next_us_[k] += period_us;
    if (stream_next_us_[k] <= now_us_) stream_next_us_[k] = now_us_ + period_us;  // late start or a gap
    switch (static_cast<StreamKind>(k)) {
      case StreamKind::kPos:
        begin_async("$pos");
        add_pos_fields();
        end_async();
        break;
      case StreamKind::kStats: {
        const AppStats& s = app_.stats();
        const hal::CanCounters& c = app_.board().can.counters();
        begin_async("$stats");
        add_u64(" t_us=", now_us_);
        add(" imu_rx=%lu imu_ok=%lu uwb_rx=%lu uwb_ok=%lu uwb_rej=%lu", static_cast<unsigned long>(s.imu.received),
            static_cast<unsigned long>(s.imu.accepted), static_cast<unsigned long>(s.uwb.received),
            static_cast<unsigned long>(s.uwb.accepted), static_cast<unsigned long>(s.uwb.rejected_total()));
        add_u64(" cycles=", s.loop.cycles);
        add_u64(" overruns=", s.loop.overruns);
        add(" cycle_max_us=%lu can_tx_ok=%lu can_tx_dropped=%lu", static_cast<unsigned long>(s.loop.cycle_max_us),
            static_cast<unsigned long>(c.tx_ok), static_cast<unsigned long>(c.tx_dropped));
        add_u64(" dropped_bytes=", stats_.dropped_bytes);
        end_async();
        break;
      }
      case StreamKind::kAnchors:
        stream_anchor_lines();
        break;
      case StreamKind::kCount:
        break;
    }
  }
}

void Console::flush() {
  hal::SerialPort& port = app_.board().serial;
  size_t written = 0;
  while (written < kTxBytesPerPoll && !tx_.empty()) {
    size_t avail = 0;
    const uint8_t* data = tx_.peek(&avail);
    const size_t want = avail < kTxBytesPerPoll - written ? avail : kTxBytesPerPoll - written;
    size_t n = port.write(data, want);
    if (n > want) n = want;
    tx_.consume(n);
    written += n;
    if (n < want) break;  // the reader is slow: the rest waits for the next poll
  }
  stats_.tx_bytes += written;
  if (written > stats_.max_tx_per_poll) stats_.max_tx_per_poll = static_cast<uint32_t>(written);
}

void Console::begin(const char* tag) {
  out_len_ = 0;
  out_[0] = '\0';
  add("%s", tag);
}

void Console::add(const char* fmt, ...) {
  if (out_len_ + 1 >= kLineCap) return;
  va_list ap;
  va_start(ap, fmt);
  const int w = std::vsnprintf(out_ + out_len_, kLineCap - out_len_, fmt, ap);
  va_end(ap);
  if (w < 0) return;
  advance(static_cast<size_t>(w));
}

// Accounts for `written` characters stored snprintf-style at out_ + out_len_
// (a longer text was cut at the end of the line).
void Console::advance(size_t written) {
  out_len_ = out_len_ + written < kLineCap ? out_len_ + written : kLineCap - 1;
}

void Console::add_u64(const char* key, uint64_t v) {
  add("%s", key);
  if (out_len_ + 1 >= kLineCap) return;
  advance(format_u64(out_ + out_len_, kLineCap - out_len_, v));
}

void Console::add_fixed(const char* key, const float* v, size_t n, int decimals) {
  add("%s", key);
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) add(",");
    if (out_len_ + 1 >= kLineCap) return;
    advance(format_fixed(out_ + out_len_, kLineCap - out_len_, v[i], decimals));
  }
}

void Console::add_general(const char* key, const float* v, size_t n, int precision) {
  add("%s", key);
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) add(",");
    if (out_len_ + 1 >= kLineCap) return;
    advance(format_general(out_ + out_len_, kLineCap - out_len_, v[i], precision));
  }
}

void Console::end_line(size_t reserve) {
  out_[out_len_++] = '\r';
  out_[out_len_++] = '\n';
  (void)queue(out_, out_len_, reserve);
  out_len_ = 0;
}

void Console::begin_error() {
  ++stats_.errors;
  out_len_ = 0;
  add("error: ");
}

void Console::error(const char* fmt, ...) {
  begin_error();
  va_list ap;
  va_start(ap, fmt);
  const int w = std::vsnprintf(out_ + out_len_, kLineCap - out_len_, fmt, ap);
  va_end(ap);
  if (w > 0) advance(static_cast<size_t>(w));
  end_line(0);
}

// Queues a whole line (preceded by the drop marker when output was lost), or
// drops it and counts it. `reserve` bytes must stay free afterwards.
bool Console::queue(const char* text, size_t len, size_t reserve) {
  static constexpr char kMarkerHead[] = "[dropped ";
  static constexpr char kMarkerTail[] = " bytes]\r\n";
  char marker[kMarkerMax];
  size_t marker_len = 0;
  if (pending_drop_bytes_ > 0) {
    std::memcpy(marker, kMarkerHead, sizeof kMarkerHead - 1);
    marker_len = sizeof kMarkerHead - 1;
    marker_len += format_u64(marker + marker_len, kU64TextMax, pending_drop_bytes_);
    std::memcpy(marker + marker_len, kMarkerTail, sizeof kMarkerTail - 1);
    marker_len += sizeof kMarkerTail - 1;
  }
  static_assert(sizeof kMarkerHead - 1 + kU64TextMax - 1 + sizeof kMarkerTail - 1 <= kMarkerMax,
                "the drop marker holds any count");
  if (tx_.free() < marker_len + len + reserve) {
    pending_drop_bytes_ += len;
    stats_.dropped_bytes += len;
    return false;
  }
  if (marker_len > 0) {
    (void)tx_.push(marker, marker_len);
    pending_drop_bytes_ = 0;
  }
  (void)tx_.push(text, len);
  return true;
}

// Echo bytes: queued when they fit, otherwise dropped and counted like lines.
void Console::queue_raw(const char* text, size_t len) { (void)queue(text, len, 0); }

void Console::prompt() {
  if (!echo_) return;
  queue_raw(LineEditor::kPrompt, std::strlen(LineEditor::kPrompt));
  prompt_visible_ = true;
}

// Streams and logs are asynchronous: with echo on, each first erases the
// prompt line (and what is typed on it), which is then drawn again once.
void Console::begin_async(const char* tag) {
  async_erase_ = echo_ && prompt_visible_;
  begin(async_erase_ ? "\r\x1b[K" : "");
  add("%s", tag);
}

void Console::end_async() {
  out_[out_len_++] = '\r';
  out_[out_len_++] = '\n';
  if (queue(out_, out_len_, kReplyReserve) && async_erase_) {
    redraw_ = true;
    prompt_visible_ = false;
  }
  out_len_ = 0;
}

void Console::redraw_prompt() {
  if (!redraw_) return;
  redraw_ = false;
  if (!echo_ || job_ != Job::kNone) return;
  prompt();
  if (editor_.pending_len() > 0) queue_raw(editor_.pending(), editor_.pending_len());
}

void Console::log_line(LogLevel level, const char* text, size_t len) {
  static constexpr char kErase[] = "\r\x1b[K";
  size_t n = 0;
  const bool erase = echo_ && prompt_visible_;
  if (erase) {
    std::memcpy(out_log_, kErase, sizeof kErase - 1);
    n = sizeof kErase - 1;
  }
  if (len > kOutLineMax - 2 - n) len = kOutLineMax - 2 - n;
  std::memcpy(out_log_ + n, text, len);
  len += n;
  out_log_[len++] = '\r';
  out_log_[len++] = '\n';
  // Errors and warnings may use the reply reserve; info and debug leave it free.
  const bool urgent = level == LogLevel::kError || level == LogLevel::kWarn;
  if (queue(out_log_, len, urgent ? 0 : kReplyReserve) && erase) {
    redraw_ = true;
    prompt_visible_ = false;
  }
}

}  // namespace uwbnav
