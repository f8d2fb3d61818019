// Console line discipline (see line_editor.hpp).
#include "firmware/console/line_editor.hpp"

#include <cstring>

namespace uwbnav {
namespace {

constexpr uint8_t kCtrlC = 0x03;
constexpr uint8_t kBackspace = 0x08;
constexpr uint8_t kTab = 0x09;
constexpr uint8_t kLf = 0x0A;
constexpr uint8_t kCr = 0x0D;
constexpr uint8_t kEsc = 0x1B;
constexpr uint8_t kDel = 0x7F;
constexpr size_t kMaxEscapeBytes = 8;  // longer CSI sequences are abandoned

constexpr char kEraseLine[] = "\r\x1b[K";

}  // namespace

void LineEditor::echo_append(const char* text, size_t len) {
  const size_t room = kEchoMax - echo_len_;
  const size_t n = len < room ? len : room;
  std::memcpy(echo_ + echo_len_, text, n);
  echo_len_ += n;
}

void LineEditor::reset_line() {
  len_ = 0;
  raw_len_ = 0;
  garbage_ = 0;
  overlong_ = false;
  esc_ = EscState::kNone;
  esc_len_ = 0;
  browse_ = 0;
  line_[0] = '\0';
}

LineEditor::Event LineEditor::end_line() {
  echo_append("\r\n", 2);
  Event e = Event::kLine;
  if (overlong_) {
    e = Event::kOverlong;
    last_overlong_ = raw_len_;
  } else if (garbage_ > 0) {
    e = Event::kGarbage;
    last_garbage_ = garbage_;
  }
  if (e == Event::kLine) std::memcpy(done_, line_, len_ + 1);
  done_len_ = e == Event::kLine ? len_ : 0;
  if (e != Event::kLine) done_[0] = '\0';
  reset_line();
  return e;
}

LineEditor::Event LineEditor::feed(uint8_t byte) {
  echo_len_ = 0;
  const bool after_cr = last_was_cr_;
  last_was_cr_ = byte == kCr;

  if (esc_ != EscState::kNone) {
    if (esc_ == EscState::kEsc) {
      esc_ = (byte == '[' || byte == 'O') ? EscState::kCsi : EscState::kNone;
      esc_len_ = 0;
      return Event::kNone;
    }
    if (byte >= 0x40 && byte <= 0x7E) {
      esc_ = EscState::kNone;
      const uint32_t held = history_newest() == 0 ? 0 : history_newest() - history_oldest() + 1;
      if (byte == 'A' && browse_ < held) {
        ++browse_;
        recall(history_newest() + 1 - browse_);
      } else if (byte == 'B' && browse_ > 0) {
        --browse_;
        recall(browse_ == 0 ? 0 : history_newest() + 1 - browse_);
      }
      return Event::kNone;
    }
    if (++esc_len_ > kMaxEscapeBytes || byte < 0x20 || byte > 0x3F) esc_ = EscState::kNone;
    return Event::kNone;
  }

  if (byte == kCr) return end_line();
  if (byte == kLf) {
    if (after_cr) return Event::kNone;  // CR LF is one line end
    return end_line();
  }
  if (byte == kCtrlC) {
    reset_line();
    echo_append("^C\r\n", 4);
    return Event::kCancel;
  }
  if (byte == kEsc) {
    esc_ = EscState::kEsc;
    return Event::kNone;
  }
  if (byte == kBackspace || byte == kDel) {
    if (!overlong_ && garbage_ == 0 && len_ > 0) {
      --len_;
      --raw_len_;
      line_[len_] = '\0';
      echo_append("\b \b", 3);
    }
    return Event::kNone;
  }

  ++raw_len_;
  if (raw_len_ > kMaxChars) overlong_ = true;
  const bool printable = (byte >= 0x20 && byte < kDel) || byte == kTab;
  if (!printable) {
    ++garbage_;
    return Event::kNone;
  }
  if (overlong_) return Event::kNone;
  const char c = byte == kTab ? ' ' : static_cast<char>(byte);
  line_[len_++] = c;
  line_[len_] = '\0';
  if (garbage_ == 0) echo_char(c);
  return Event::kNone;
}

void LineEditor::recall(uint32_t seq) {
  const char* text = seq == 0 ? "" : history_find(seq);
  if (text == nullptr) return;
  const size_t n = std::strlen(text);
  std::memcpy(line_, text, n + 1);
  len_ = n;
  raw_len_ = n;
  garbage_ = 0;
  overlong_ = false;
  echo_append(kEraseLine, sizeof kEraseLine - 1);
  echo_append(kPrompt, std::strlen(kPrompt));
  echo_append(line_, len_);
}

void LineEditor::history_add(const char* text) {
  const size_t n = std::strlen(text);
  if (n == 0 || n > kMaxChars) return;
  const char* newest = history_find(history_newest());
  if (newest != nullptr && std::strcmp(newest, text) == 0) return;  // no consecutive duplicates
  char* slot = history_[(next_seq_ - 1) % kHistoryDepth];
  std::memcpy(slot, text, n + 1);
  ++next_seq_;
}

uint32_t LineEditor::history_oldest() const {
  const uint32_t newest = history_newest();
  if (newest == 0) return 1;
  return newest > kHistoryDepth ? newest - static_cast<uint32_t>(kHistoryDepth) + 1 : 1;
}

const char* LineEditor::history_find(uint32_t seq) const {
  if (seq == 0 || seq > history_newest() || seq < history_oldest()) return nullptr;
  return history_[(seq - 1) % kHistoryDepth];
}

void LineEditor::history_clear() { next_seq_ = 1; }

}  // namespace uwbnav
