// Console line discipline: assembles bytes into a fixed-size line buffer with
// echo, backspace, Ctrl-C, up/down history recall (ANSI cursor keys) and a
// small numbered history; classifies bad lines (too long, non-printable bytes).
// Static memory only; one byte in, at most one event out, bounded work per byte.
#pragma once

#include <cstddef>
#include <cstdint>

namespace uwbnav {

class LineEditor {
 public:
  static constexpr size_t kLineMax = 128;            // buffer incl. NUL [bytes]
  static constexpr size_t kMaxChars = kLineMax - 1;  // longest accepted line [chars]
  static constexpr size_t kHistoryDepth = 8;         // lines kept for recall
  static constexpr const char* kPrompt = "> ";
  static constexpr size_t kEchoMax = kLineMax + 16;  // echo bytes one feed() can produce

  enum class Event : uint8_t {
    kNone,      // byte consumed; nothing to run
    kLine,      // a line ended; line() holds it (possibly empty)
    kOverlong,  // a line ended after more than kMaxChars bytes; discarded
    kGarbage,   // a line ended that held non-printable bytes; discarded
    kCancel,    // Ctrl-C: the line was discarded
  };

  // Consumes one input byte. Echo for it is in echo()/echo_len() until the next feed().
  Event feed(uint8_t byte);

  // The line that ended with the last kLine event (NUL-terminated).
  const char* line() const { return done_; }
  size_t line_len() const { return done_len_; }
  // The line being typed.
  const char* pending() const { return line_; }
  size_t pending_len() const { return len_; }
  // Non-printable bytes in the line that ended with kGarbage.
  size_t garbage_count() const { return last_garbage_; }
  // Bytes in the line that ended with kOverlong.
  size_t overlong_count() const { return last_overlong_; }

  const char* echo() const { return echo_; }
  size_t echo_len() const { return echo_len_; }

  // History: entries are numbered 1, 2, ... in the order they were added.
  void history_add(const char* text);
  uint32_t history_newest() const { return next_seq_ - 1; }
  uint32_t history_oldest() const;
  // Entry `seq`, or nullptr when it is not (or no longer) held.
  const char* history_find(uint32_t seq) const;
  void history_clear();

  // Drops the line being typed (and any escape sequence in progress).
  void reset_line();

 private:
  enum class EscState : uint8_t { kNone, kEsc, kCsi };

  void echo_append(const char* text, size_t len);
  void echo_char(char c) { echo_append(&c, 1); }
  void recall(uint32_t seq);
  Event end_line();

  char line_[kLineMax] = {};  // being typed
  char done_[kLineMax] = {};  // last completed line
  size_t done_len_ = 0;
  size_t len_ = 0;             // printable chars in line_
  size_t raw_len_ = 0;         // all bytes of the line so far (printable and not)
  size_t garbage_ = 0;         // non-printable bytes in the line so far
  bool overlong_ = false;
  size_t last_garbage_ = 0;
  size_t last_overlong_ = 0;
  bool last_was_cr_ = false;
  EscState esc_ = EscState::kNone;
  size_t esc_len_ = 0;
  uint32_t browse_ = 0;        // history entries stepped back with cursor-up (0 = editing)

  char history_[kHistoryDepth][kLineMax] = {};
  uint32_t next_seq_ = 1;

  char echo_[kEchoMax] = {};
  size_t echo_len_ = 0;
};

}  // namespace uwbnav
