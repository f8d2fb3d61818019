// libFuzzer target: console bytes, twice. (1) The line editor alone: echo,
// history and line buffers stay within their fixed sizes and NUL-terminated.
// (2) The running App's console (line editor + command parser + every command)
// typed the same bytes over ticks, until input and output drain.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "firmware/app.hpp"
#include "firmware/console/line_editor.hpp"
#include "tests/fuzz/fuzz_board.hpp"

namespace {

void check_editor(const uint8_t* data, size_t size) {
  using uwbnav::LineEditor;
  LineEditor ed;
  for (size_t i = 0; i < size; ++i) {
    const LineEditor::Event e = ed.feed(data[i]);
    if (ed.echo_len() > LineEditor::kEchoMax || ed.pending_len() > LineEditor::kMaxChars) std::abort();
    if (e == LineEditor::Event::kLine) {
      if (ed.line_len() > LineEditor::kMaxChars || std::strlen(ed.line()) != ed.line_len()) std::abort();
      ed.history_add(ed.line());
    }
  }
  for (uint32_t seq = ed.history_oldest(); seq != 0 && seq <= ed.history_newest(); ++seq) {
    const char* h = ed.history_find(seq);
    if (h != nullptr && std::strlen(h) > LineEditor::kMaxChars) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace uwbnav;
  if (size > 4096) return 0;
  check_editor(data, size);

  static const SiteConfig site = fuzz::square_site(true, Platform::kGround);
  fuzz::VectorImuSource imu;
  fuzz::VectorUwbSource uwb;
  fuzz::SinkCanBus can;
  fuzz::StringSerial serial;
  serial.input.assign(reinterpret_cast<const char*>(data), size);
  fuzz::StepClock clock;
  fuzz::BlobParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site};
  auto app = std::make_unique<App>(board);
  if (!ok(app->init())) std::abort();  // defaults on a good site always start
  uint64_t now = 1000000;
  const size_t max_ticks = size / Console::kRxBytesPerPoll + 400;
  for (size_t t = 0; t < max_ticks; ++t, now += kCyclePeriodUs) {
    clock.sleep_until_us(now);
    app->tick(now);
    if (serial.in_pos >= serial.input.size() && app->console().tx_pending() == 0 && t > 4) break;
  }
  if (app->console().tx_pending() > Console::kTxRingBytes) std::abort();
  return 0;
}
