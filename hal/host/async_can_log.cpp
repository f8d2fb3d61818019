// Bounded, lock-free CAN log queue drained by a writer thread (see async_can_log.hpp).
#include "hal/host/async_can_log.hpp"

#include <chrono>

namespace uwbnav::hal {

AsyncCanLog::AsyncCanLog(CanBus& inner, CandumpLogWriter& log, bool log_rx, size_t capacity_frames)
    : inner_(inner), log_(log), log_rx_(log_rx), ring_(capacity_frames > 0 ? capacity_frames : 1) {}

AsyncCanLog::~AsyncCanLog() { stop(); }

void AsyncCanLog::start(uint32_t poll_us) {
  if (running_.exchange(true)) return;
  writer_ = std::thread([this, poll_us] { writer_loop(poll_us); });
}

void AsyncCanLog::stop() {
  if (running_.exchange(false) && writer_.joinable()) writer_.join();
  (void)drain();
}

void AsyncCanLog::push(const CanFrame& frame) {
  const uint64_t head = head_.load(std::memory_order_relaxed);
  const uint64_t tail = tail_.load(std::memory_order_acquire);
  const size_t queued = static_cast<size_t>(head - tail);
  if (queued >= ring_.size()) {
    overflow_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  ring_[static_cast<size_t>(head % ring_.size())] = frame;
  head_.store(head + 1, std::memory_order_release);
  if (queued + 1 > high_water_.load(std::memory_order_relaxed)) {
    high_water_.store(queued + 1, std::memory_order_relaxed);
  }
}

Status AsyncCanLog::send(const CanFrame& frame) {
  const Status s = inner_.send(frame);
  if (ok(s)) push(frame);
  return s;
}

Status AsyncCanLog::receive(CanFrame& out) {
  const Status s = inner_.receive(out);
  if (ok(s) && log_rx_) push(out);
  return s;
}

size_t AsyncCanLog::drain() {
  size_t n = 0;
  uint64_t tail = tail_.load(std::memory_order_relaxed);
  const uint64_t head = head_.load(std::memory_order_acquire);
  while (tail != head) {
    if (!ok(log_.write(ring_[static_cast<size_t>(tail % ring_.size())]))) {
      write_errors_.fetch_add(1, std::memory_order_relaxed);
    } else {
      written_.fetch_add(1, std::memory_order_relaxed);
    }
    ++tail;
    ++n;
    tail_.store(tail, std::memory_order_release);
  }
  return n;
}

void AsyncCanLog::writer_loop(uint32_t poll_us) {
  while (running_.load(std::memory_order_acquire)) {
    if (drain() == 0) std::this_thread::sleep_for(std::chrono::microseconds(poll_us));
  }
}

AsyncLogCounters AsyncCanLog::log_counters() const {
  AsyncLogCounters c;
  c.written = written_.load();
  c.overflow = overflow_.load();
  c.write_errors = write_errors_.load();
  c.queued = head_.load();
  c.high_water = high_water_.load();
  c.capacity = ring_.size();
  return c;
}

}  // namespace uwbnav::hal
