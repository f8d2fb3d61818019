// Replay outputs (estimates.csv, ranges.csv, can.log) formatted and written,
// and the epochs handed to a ReplaySink (the result table built on the fly),
// on a thread of their own, so the lockstep loop uses the second core instead
// of waiting for number formatting, file I/O and the evaluation. Records travel in fixed-size
// batches (kBatchRecords each, kBatches in all, allocated once): the memory is
// fixed, nothing is ever dropped (the loop waits when all batches are in
// flight), and each file receives its records in the order they were produced.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "hal/hal.hpp"
#include "hal/host/candump_log.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/eval/replay.hpp"

namespace uwbnav::eval {

class AsyncOutputWriter {
 public:
  static constexpr size_t kBatchRecords = 1024;
  static constexpr size_t kBatches = 4;

  AsyncOutputWriter() = default;
  ~AsyncOutputWriter();
  AsyncOutputWriter(const AsyncOutputWriter&) = delete;
  AsyncOutputWriter& operator=(const AsyncOutputWriter&) = delete;

  // Creates dir/estimates.csv, dir/ranges.csv and dir/can.log (interface
  // `can_ifname`; no files when `dir` is empty), remembers `sink` (may be
  // null; it receives every epoch on the writer thread) and starts the thread.
  [[nodiscard]] Status open(const std::string& dir, const char* can_ifname, ReplaySink* sink);
  void estimate(const NavOutput& out);
  void range(const RangeReport& report);
  void can(const hal::CanFrame& frame);
  // Writes what is pending, stops the thread and closes the files; kIoError
  // when any write failed. Idempotent.
  [[nodiscard]] Status close();

 private:
  enum class Kind : uint8_t { kEstimate, kRange, kCan };
  struct Record {
    Kind kind = Kind::kEstimate;
    NavOutput est;
    RangeReport range;
    hal::CanFrame frame;
  };
  using Batch = std::vector<Record>;

  Record& next_slot();
  void hand_over();
  void run();

  bool files_ = false;
  ReplaySink* sink_ = nullptr;
  dataset::EstimatesWriter est_;
  dataset::RangesWriter rng_;
  hal::CandumpLogWriter can_;
  std::vector<std::unique_ptr<Batch>> storage_;
  Batch* current_ = nullptr;        // being filled by the loop
  std::deque<Batch*> full_, free_;  // guarded by mutex_ (at most kBatches each)
  std::mutex mutex_;
  std::condition_variable changed_;
  bool stop_ = false;
  bool write_failed_ = false;  // writer thread only until joined
  std::thread thread_;
};

// CAN bus decorator: every frame the inner bus accepted also goes to can.log
// through the asynchronous writer (as hal::CanLogTee does synchronously).
class AsyncCanLogTee final : public hal::CanBus {
 public:
  AsyncCanLogTee(hal::CanBus& inner, AsyncOutputWriter& log) : inner_(inner), log_(log) {}
  [[nodiscard]] Status send(const hal::CanFrame& frame) override {
    const Status s = inner_.send(frame);
    if (s == Status::kOk) log_.can(frame);
    return s;
  }
  [[nodiscard]] Status receive(hal::CanFrame& out) override { return inner_.receive(out); }
  hal::CanBusState state() const override { return inner_.state(); }
  const hal::CanCounters& counters() const override { return inner_.counters(); }
  void reset_counters() override { inner_.reset_counters(); }

 private:
  hal::CanBus& inner_;
  AsyncOutputWriter& log_;
};

}  // namespace uwbnav::eval
