// A CanBus decorator that logs frames without file I/O in the caller's thread:
// send()/receive() copy each frame into a bounded single-producer ring (no
// lock, no heap, no system call), and a writer thread outside the real-time
// cycle drains the ring into a candump log. A full ring drops the frame from
// the log (never from the bus) and counts it.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

#include "hal/hal.hpp"
#include "hal/host/candump_log.hpp"

namespace uwbnav::hal {

struct AsyncLogCounters {
  uint64_t queued = 0;      // frames put into the ring
  uint64_t written = 0;     // frames the writer wrote to the log
  uint64_t overflow = 0;    // frames not logged: the ring was full
  uint64_t write_errors = 0;
  size_t high_water = 0;    // most frames queued at once
  size_t capacity = 0;
};

class AsyncCanLog final : public CanBus {
 public:
  // capacity_frames: ring size, allocated here (start-up). At 100 Hz with ~25
  // frames per cycle, 16384 frames hold 6.5 s of writer stall.
  AsyncCanLog(CanBus& inner, CandumpLogWriter& log, bool log_rx, size_t capacity_frames = 16384);
  ~AsyncCanLog() override;
  AsyncCanLog(const AsyncCanLog&) = delete;
  AsyncCanLog& operator=(const AsyncCanLog&) = delete;

  // Starts the writer thread (call before raising the caller's priority: the
  // writer inherits the scheduling policy of the thread that starts it).
  void start(uint32_t poll_us = 5000);
  // Drains what is queued, stops the writer and flushes the log.
  void stop();

  [[nodiscard]] Status send(const CanFrame& frame) override;
  [[nodiscard]] Status receive(CanFrame& out) override;
  CanBusState state() const override { return inner_.state(); }
  const CanCounters& counters() const override { return inner_.counters(); }
  void reset_counters() override { inner_.reset_counters(); }

  AsyncLogCounters log_counters() const;
  // Writes everything queued now, in the calling thread (tests; the writer does this).
  size_t drain();

 private:
  void push(const CanFrame& frame);
  void writer_loop(uint32_t poll_us);

  CanBus& inner_;
  CandumpLogWriter& log_;
  bool log_rx_;
  std::vector<CanFrame> ring_;
  std::atomic<uint64_t> head_{0};  // next slot the producer writes (producer only)
  std::atomic<uint64_t> tail_{0};  // next slot the writer reads (writer only)
  std::atomic<uint64_t> overflow_{0};
  std::atomic<uint64_t> written_{0};
  std::atomic<uint64_t> write_errors_{0};
  std::atomic<size_t> high_water_{0};
  std::atomic<bool> running_{false};
  std::thread writer_;
};

}  // namespace uwbnav::hal
