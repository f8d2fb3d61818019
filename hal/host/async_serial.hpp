// A SerialPort decorator that keeps terminal and pipe I/O out of the real-time
// cycle: read() and write() only move bytes between the caller and two bounded
// lock-free rings; an I/O thread outside the cycle moves them between the rings
// and the wrapped host port (stdio, pty). A system call on a pipe or terminal
// can sleep on a lock held by the process at the other end (a SCHED_FIFO loop
// would then wait for a SCHED_OTHER reader), so the cycle makes none. When the
// TX ring is full write() accepts fewer bytes: the console drops and counts
// them as for a slow reader.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <thread>
#include <vector>

#include "hal/hal.hpp"

namespace uwbnav::hal {

// Single-producer single-consumer byte ring (one thread writes, one reads).
class SpscByteRing {
 public:
  explicit SpscByteRing(size_t capacity) : buf_(capacity > 0 ? capacity : 1) {}
  // Copies up to len bytes in; returns how many fit.
  size_t push(const uint8_t* data, size_t len);
  // Copies up to cap bytes out; returns how many.
  size_t pop(uint8_t* out, size_t cap);
  size_t size() const { return static_cast<size_t>(head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire)); }
  size_t capacity() const { return buf_.size(); }

 private:
  std::vector<uint8_t> buf_;
  std::atomic<uint64_t> head_{0};
  std::atomic<uint64_t> tail_{0};
};

struct AsyncSerialCounters {
  uint64_t tx_refused = 0;    // bytes write() could not take (TX ring full)
  size_t tx_high_water = 0;   // most bytes queued for output at once
};

class AsyncSerialPort final : public SerialPort {
 public:
  // input_closed: asked by the I/O thread after each read of `inner` (e.g.
  // StdioSerialPort::input_closed); empty: the input never ends.
  AsyncSerialPort(SerialPort& inner, std::function<bool()> input_closed = {}, size_t tx_bytes = 16384,
                  size_t rx_bytes = 4096);
  ~AsyncSerialPort() override;
  AsyncSerialPort(const AsyncSerialPort&) = delete;
  AsyncSerialPort& operator=(const AsyncSerialPort&) = delete;

  // Starts the I/O thread (before the caller turns SCHED_FIFO: it stays SCHED_OTHER).
  void start(uint32_t poll_us = 2000);
  // Writes out what is queued (at most ~1 s of trying), then stops the thread.
  void stop();

  size_t read(uint8_t* buf, size_t cap) override { return rx_.pop(buf, cap); }
  size_t write(const uint8_t* buf, size_t len) override;

  // The input ended (EOF / Ctrl-D seen by the I/O thread) and everything read was handed out.
  bool input_closed() const { return eof_.load(std::memory_order_acquire) && rx_.size() == 0; }
  AsyncSerialCounters counters() const;
  // One round of the I/O thread's work, in the calling thread (tests). Returns bytes moved.
  size_t pump();

 private:
  void io_loop(uint32_t poll_us);

  SerialPort& inner_;
  std::function<bool()> inner_closed_;
  SpscByteRing tx_;
  SpscByteRing rx_;
  uint8_t pending_[256] = {};   // bytes popped from tx_ the inner port did not take yet (I/O thread only)
  size_t pending_len_ = 0;
  size_t pending_pos_ = 0;
  std::atomic<bool> eof_{false};
  std::atomic<uint64_t> tx_refused_{0};
  std::atomic<size_t> tx_high_water_{0};
  std::atomic<bool> running_{false};
  std::thread io_;
};

}  // namespace uwbnav::hal
