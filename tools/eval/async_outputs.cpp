// Asynchronous writer of the replay outputs (see async_outputs.hpp).
#include "tools/eval/async_outputs.hpp"

namespace uwbnav::eval {

AsyncOutputWriter::~AsyncOutputWriter() { ignore_status(close()); }

Status AsyncOutputWriter::open(const std::string& dir, const char* can_ifname, ReplaySink* sink) {
  ignore_status(close());
  files_ = !dir.empty();
  sink_ = sink;
  if (files_ && (!ok(est_.open(dir + "/estimates.csv")) || !ok(rng_.open(dir + "/ranges.csv")) ||
                 !ok(can_.open(dir + "/can.log", can_ifname)))) {
    return Status::kIoError;
  }
  storage_.clear();
  full_.clear();
  free_.clear();
  for (size_t i = 0; i < kBatches; ++i) {
    storage_.push_back(std::make_unique<Batch>());
    storage_.back()->reserve(kBatchRecords);
    free_.push_back(storage_.back().get());
  }
  current_ = free_.front();
  free_.pop_front();
  stop_ = false;
  write_failed_ = false;
  thread_ = std::thread([this] { run(); });
  return Status::kOk;
}

AsyncOutputWriter::Record& AsyncOutputWriter::next_slot() {
  if (current_->size() >= kBatchRecords) hand_over();
  current_->emplace_back();
  return current_->back();
}

// Queues the filled batch for the writer and takes an empty one (waiting
// while the writer holds them all).
void AsyncOutputWriter::hand_over() {
  std::unique_lock<std::mutex> lock(mutex_);
  full_.push_back(current_);
  changed_.notify_all();
  changed_.wait(lock, [this] { return !free_.empty(); });
  current_ = free_.front();
  free_.pop_front();
}

void AsyncOutputWriter::estimate(const NavOutput& out) {
  Record& r = next_slot();
  r.kind = Kind::kEstimate;
  r.est = out;
}

void AsyncOutputWriter::range(const RangeReport& report) {
  Record& r = next_slot();
  r.kind = Kind::kRange;
  r.range = report;
}

void AsyncOutputWriter::can(const hal::CanFrame& frame) {
  Record& r = next_slot();
  r.kind = Kind::kCan;
  r.frame = frame;
}

void AsyncOutputWriter::run() {
  for (;;) {
    Batch* batch = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return !full_.empty() || stop_; });
      if (full_.empty()) return;  // stopped and drained
      batch = full_.front();
      full_.pop_front();
    }
    for (const Record& r : *batch) {
      Status s = Status::kOk;
      switch (r.kind) {
        case Kind::kEstimate:
          if (sink_ != nullptr) sink_->on_estimate(to_estimate_row(r.est));
          if (files_) s = est_.write(r.est);
          break;
        case Kind::kRange:
          if (files_) s = rng_.write(r.range);
          break;
        case Kind::kCan:
          if (files_) s = can_.write(r.frame);
          break;
      }
      if (!ok(s)) write_failed_ = true;
    }
    batch->clear();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(batch);
    }
    changed_.notify_all();
  }
}

Status AsyncOutputWriter::close() {
  if (!thread_.joinable()) return Status::kOk;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!current_->empty()) full_.push_back(current_);
    current_ = nullptr;
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
  const Status a = est_.close();
  const Status b = rng_.close();
  const Status c = can_.close();
  return ok(a) && ok(b) && ok(c) && !write_failed_ ? Status::kOk : Status::kIoError;
}

}  // namespace uwbnav::eval
