// The diagnostics shell on the board's serial port (docs/console.md): polled
// once per 100 Hz cycle, never blocking. Per poll it reads at most
// kRxBytesPerPoll bytes, runs at most one command and writes at most
// kTxBytesPerPoll bytes; replies queue in a fixed TX ring, long replies are
// paced over several polls, and output that finds the ring full (slow reader)
// is dropped, counted and announced by a "[dropped N bytes]" marker line.
// Static memory only.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/navigator.hpp"
#include "estimator/types.hpp"
#include "firmware/app_stats.hpp"
#include "firmware/console/byte_ring.hpp"
#include "firmware/console/line_editor.hpp"
#include "firmware/console/log.hpp"
#include "hal/hal.hpp"

namespace uwbnav {

class App;
struct ParamDef;

// Console counters (`stats`, flood test). Monotonic until `reset stats`.
struct ConsoleStats {
  uint64_t rx_bytes = 0;            // bytes read from the port
  uint64_t tx_bytes = 0;            // bytes accepted by the port
  uint64_t dropped_bytes = 0;       // output dropped because the TX ring was full
  uint32_t lines = 0;               // input lines ended (any kind)
  uint32_t commands = 0;            // commands run (known or not)
  uint32_t errors = 0;              // "error:" replies
  uint32_t overlong_lines = 0;      // lines longer than LineEditor::kMaxChars
  uint32_t garbage_lines = 0;       // lines holding non-printable bytes
  uint32_t max_rx_per_poll = 0;     // most bytes read in one poll (<= kRxBytesPerPoll)
  uint32_t max_tx_per_poll = 0;     // most bytes written in one poll (<= kTxBytesPerPoll)
  uint32_t max_commands_per_poll = 0;  // most commands run in one poll (<= 1)
};

// Periodic machine-readable outputs (`stream <what> <rate_hz>`).
enum class StreamKind : uint8_t { kPos = 0, kStats, kAnchors, kCount };

class Console final : public LogSink {
 public:
  static constexpr size_t kRxBytesPerPoll = 64;    // input budget per cycle [bytes]
  static constexpr size_t kTxBytesPerPoll = 256;   // output budget per cycle [bytes]
#ifndef UWBNAV_CONSOLE_TX_RING_BYTES
#define UWBNAV_CONSOLE_TX_RING_BYTES 2048
#endif
  static constexpr size_t kTxRingBytes = UWBNAV_CONSOLE_TX_RING_BYTES;  // queued output [bytes]
  static constexpr size_t kOutLineMax = 320;       // longest reply line incl. CR LF [bytes]
  static constexpr size_t kReplyReserve = 512;     // TX room kept free of streams/logs for replies [bytes]
  static constexpr size_t kMaxArgs = 8;            // words per command line
  static constexpr uint32_t kMaxStreamRateHz = 100;
  static constexpr int kGeneralPrecision = 6;      // significant digits of parameter values ("%g")

  // Registers itself as the logger's sink. The App must outlive the console.
  explicit Console(App& app);
  ~Console() override;
  Console(const Console&) = delete;
  Console& operator=(const Console&) = delete;

  // One cycle of console work at loop time now_us (called at the end of App::tick).
  void poll(uint64_t now_us);

  // Echo of typed characters and the "> " prompt (on: UART / pty terminal;
  // off: a line-buffered host terminal that echoes itself, or a script).
  void set_echo(bool on) { echo_ = on; }
  bool echo() const { return echo_; }

  const ConsoleStats& stats() const { return stats_; }
  void reset_stats() { stats_ = ConsoleStats{}; }
  // Bytes queued for the port.
  size_t tx_pending() const { return tx_.size(); }
  // Input read but not yet handled, a multi-line reply in progress, or output queued.
  bool busy() const { return rx_pos_ < rx_len_ || job_ != Job::kNone || !tx_.empty(); }
  uint32_t stream_rate_hz(StreamKind kind) const { return stream_rate_hz_[static_cast<size_t>(kind)]; }

  void log_line(LogLevel level, const char* text, size_t len) override;

 private:
  using Handler = void (Console::*)(size_t argc, char** argv);
  struct Command {
    const char* name;
    const char* usage;
    const char* summary;
    Handler handler;
  };
  enum class Job : uint8_t { kNone, kHelp, kParamList, kAnchors, kEkf, kStats, kHistory, kCal };

  // What a multi-line reply reports, copied when the command runs, so that all
  // its lines describe the same cycle although they go out over several. One
  // job runs at a time, so the parts share their storage (a union: RAM is the
  // M4F image's tightest budget, docs/footprint.md): take_snapshot() begins the
  // lifetime of the part its job reads, and the job's steps read only that part.
  struct StatsPart {
    AppStats app;
    NavDiagnostics nav;
    hal::CanCounters can;
    hal::CanBusState can_state = hal::CanBusState::kDown;
  };
  struct AnchorsPart {
    size_t num_anchors = 0;
    AnchorStatus anchors[kMaxAnchors];
  };
  struct EkfPart {
    float state[16] = {};
    float cov[Navigator::kErrorStateSize][Navigator::kErrorStateSize] = {};
  };
  union SnapshotPart {
    SnapshotPart() : ekf() {}
    StatsPart stats;      // Job::kStats
    AnchorsPart anchors;  // Job::kAnchors
    EkfPart ekf;          // Job::kEkf
  };
  struct Snapshot {
    uint64_t t_us = 0;  // cycle the snapshot was taken in [us]
    SnapshotPart part;
  };

  static const Command kCommands[];
  static const size_t kNumCommands;

  void banner();
  void apply_log_params();
  void process_input();
  void handle_line(const char* line);
  void execute(char* line);
  void start_job(Job job, bool verbose);
  void take_snapshot(Job job);
  void run_job();
  bool job_step();
  void run_streams();
  void flush();

  // Output. Every line is queued whole with CR LF, or dropped whole.
  // add() takes strings and integers up to 32 bits only: floats and 64-bit
  // counts go through the add_* fields below (firmware/text_format.hpp), as the
  // board's printf has neither.
  void begin(const char* tag);
  void add(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  void add_u64(const char* key, uint64_t v);
  // `key` then n floats, comma-separated, as "%.<decimals>f" / "%.<precision>g".
  void add_fixed(const char* key, const float* v, size_t n, int decimals);
  void add_fixed(const char* key, float v, int decimals) { add_fixed(key, &v, 1, decimals); }
  void add_general(const char* key, const float* v, size_t n, int precision);
  void add_general(const char* key, float v) { add_general(key, &v, 1, kGeneralPrecision); }
  void advance(size_t written);
  void end_line(size_t reserve);
  void reply_end() { end_line(0); }
  void error(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  void begin_error();
  bool queue(const char* text, size_t len, size_t reserve);
  void queue_raw(const char* text, size_t len);
  void prompt();
  void begin_async(const char* tag);
  void end_async();
  void redraw_prompt();

  // Commands (console_commands.cpp).
  void cmd_help(size_t argc, char** argv);
  void cmd_version(size_t argc, char** argv);
  void cmd_status(size_t argc, char** argv);
  void cmd_stats(size_t argc, char** argv);
  void cmd_anchors(size_t argc, char** argv);
  void cmd_ekf(size_t argc, char** argv);
  void cmd_param(size_t argc, char** argv);
  void cmd_log(size_t argc, char** argv);
  void cmd_stream(size_t argc, char** argv);
  void cmd_reset(size_t argc, char** argv);
  void cmd_history(size_t argc, char** argv);
  void cmd_echo(size_t argc, char** argv);
  void cmd_cal(size_t argc, char** argv);

  // Job steps: emit line `step`, return true while more lines follow.
  bool step_help(size_t step);
  bool step_param_list(size_t step);
  bool step_anchors(size_t step);
  bool step_ekf(size_t step);
  bool step_stats(size_t step);
  bool step_history(size_t step);
  bool step_cal(size_t step);
  void add_param(size_t index, bool with_doc);
  bool param_listed(size_t index) const;
  size_t next_listed(size_t from) const;  // first listed index >= from (kNumParams: none)
  void add_param_change(const ParamDef& p, float old);
  void add_pos_fields();
  void add_reset_fields(const NavDiagnostics& dg);
  void add_anchor_fields(const AnchorStatus& a);
  void stream_anchor_lines();

  App& app_;
  LineEditor editor_;
  ByteRing<kTxRingBytes> tx_;
  ConsoleStats stats_;
  bool echo_ = true;
  bool banner_done_ = false;
  bool prompt_visible_ = false;  // the last thing shown is the prompt (and the line being typed)
  bool redraw_ = false;          // an async line erased the prompt: draw it again
  bool async_erase_ = false;     // the async line being built starts by erasing the prompt line
  uint64_t now_us_ = 0;

  uint8_t rx_buf_[kRxBytesPerPoll] = {};  // read from the port, not yet fed to the editor
  size_t rx_len_ = 0;
  size_t rx_pos_ = 0;
  uint32_t poll_commands_ = 0;

  char cmd_[LineEditor::kLineMax] = {};   // the line being executed (tokenised in place)
  char out_[kOutLineMax] = {};            // the reply line being built
  char out_log_[kOutLineMax] = {};        // a log line (may arrive while out_ is being built)
  size_t out_len_ = 0;
  uint64_t pending_drop_bytes_ = 0;       // dropped since the last marker

  Snapshot snap_;
  // `param list [-c] [GLOB]`, set by the command before the list job runs.
  char list_glob_[48];                    // GLOB ("" lists all)
  bool list_changed_only_;                // -c: only values differing from the default
  size_t list_cursor_;                    // next parameter index the list job looks at
  Job job_ = Job::kNone;
  size_t job_step_ = 0;
  bool job_verbose_ = false;

  uint32_t stream_rate_hz_[static_cast<size_t>(StreamKind::kCount)] = {};
  uint64_t stream_next_us_[static_cast<size_t>(StreamKind::kCount)] = {};
};

}  // namespace uwbnav
