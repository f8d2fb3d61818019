// Serial I/O moved out of the real-time cycle (see async_serial.hpp).
#include "hal/host/async_serial.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace uwbnav::hal {

size_t SpscByteRing::push(const uint8_t* data, size_t len) {
  const uint64_t head = head_.load(std::memory_order_relaxed);
  const uint64_t tail = tail_.load(std::memory_order_acquire);
  const size_t room = buf_.size() - static_cast<size_t>(head - tail);
  const size_t n = std::min(len, room);
  for (size_t i = 0; i < n; ++i) buf_[static_cast<size_t>((head + i) % buf_.size())] = data[i];
  head_.store(head + n, std::memory_order_release);
  return n;
}

size_t SpscByteRing::pop(uint8_t* out, size_t cap) {
  const uint64_t tail = tail_.load(std::memory_order_relaxed);
  const uint64_t head = head_.load(std::memory_order_acquire);
  const size_t n = std::min(cap, static_cast<size_t>(head - tail));
  for (size_t i = 0; i < n; ++i) out[i] = buf_[static_cast<size_t>((tail + i) % buf_.size())];
  tail_.store(tail + n, std::memory_order_release);
  return n;
}

AsyncSerialPort::AsyncSerialPort(SerialPort& inner, std::function<bool()> input_closed, size_t tx_bytes,
                                 size_t rx_bytes)
    : inner_(inner), inner_closed_(std::move(input_closed)), tx_(tx_bytes), rx_(rx_bytes) {}

AsyncSerialPort::~AsyncSerialPort() { stop(); }

void AsyncSerialPort::start(uint32_t poll_us) {
  if (running_.exchange(true)) return;
  io_ = std::thread([this, poll_us] { io_loop(poll_us); });
}

void AsyncSerialPort::stop() {
  if (running_.exchange(false) && io_.joinable()) io_.join();
  for (int i = 0; i < 500 && (tx_.size() > 0 || pending_pos_ < pending_len_); ++i) {
    if (pump() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

size_t AsyncSerialPort::write(const uint8_t* buf, size_t len) {
  const size_t n = tx_.push(buf, len);
  if (n < len) tx_refused_.fetch_add(len - n, std::memory_order_relaxed);
  const size_t queued = tx_.size();
  if (queued > tx_high_water_.load(std::memory_order_relaxed)) tx_high_water_.store(queued, std::memory_order_relaxed);
  return n;
}

size_t AsyncSerialPort::pump() {
  size_t moved = 0;
  // Output: what the inner port takes now; the rest waits in pending_ for the next round.
  for (;;) {
    if (pending_pos_ == pending_len_) {
      pending_len_ = tx_.pop(pending_, sizeof pending_);
      pending_pos_ = 0;
      if (pending_len_ == 0) break;
    }
    const size_t w = inner_.write(pending_ + pending_pos_, pending_len_ - pending_pos_);
    pending_pos_ += w;
    moved += w;
    if (w == 0) break;  // reader slow: try again next round
  }
  // Input: as much as the RX ring has room for.
  uint8_t buf[256];
  while (!eof_.load(std::memory_order_relaxed)) {
    const size_t room = rx_.capacity() - rx_.size();
    if (room == 0) break;
    const size_t r = inner_.read(buf, std::min(room, sizeof buf));
    if (r > 0) {
      (void)rx_.push(buf, r);
      moved += r;
    }
    if (inner_closed_ && inner_closed_()) eof_.store(true, std::memory_order_release);
    if (r == 0) break;
  }
  return moved;
}

void AsyncSerialPort::io_loop(uint32_t poll_us) {
  while (running_.load(std::memory_order_acquire)) {
    if (pump() == 0) std::this_thread::sleep_for(std::chrono::microseconds(poll_us));
  }
}

AsyncSerialCounters AsyncSerialPort::counters() const {
  AsyncSerialCounters c;
  c.tx_refused = tx_refused_.load();
  c.tx_high_water = tx_high_water_.load();
  return c;
}

}  // namespace uwbnav::hal
