// MemCanBus: bounded, allocation-free in-memory CAN endpoints for tests and lockstep runs.
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::hal {

bool CanFrameRing::push(const CanFrame& f) {
  if (size_ == buf_.size()) return false;
  buf_[(head_ + size_) % buf_.size()] = f;
  ++size_;
  return true;
}

bool CanFrameRing::pop(CanFrame& out) {
  if (size_ == 0) return false;
  out = buf_[head_];
  head_ = (head_ + 1) % buf_.size();
  --size_;
  return true;
}

void CanFrameRing::drop_oldest() {
  if (size_ == 0) return;
  head_ = (head_ + 1) % buf_.size();
  --size_;
}

MemCanBus::MemCanBus(size_t tx_capacity, size_t rx_capacity, size_t sent_capacity)
    : tx_(tx_capacity), rx_(rx_capacity), sent_(sent_capacity) {}

MemCanBus::~MemCanBus() { disconnect(); }

void MemCanBus::connect(MemCanBus& a, MemCanBus& b) {
  a.disconnect();
  b.disconnect();
  a.peer_ = &b;
  b.peer_ = &a;
}

void MemCanBus::disconnect() {
  if (peer_ != nullptr) peer_->peer_ = nullptr;
  peer_ = nullptr;
}

Status MemCanBus::send(const CanFrame& frame) {
  const size_t max_len = (frame.flags & CanFrame::kFlagFd) != 0 ? 64 : 8;
  if (frame.len > max_len) return Status::kInvalidArgument;
  if (state_ == CanBusState::kBusOff || state_ == CanBusState::kDown) {
    ++counters_.tx_dropped;
    return Status::kIoError;
  }
  if (!tx_.push(frame)) {
    ++counters_.tx_dropped;
    return Status::kWouldBlock;
  }
  if (auto_flush_) flush();
  return Status::kOk;
}

size_t MemCanBus::flush(size_t max_frames) {
  size_t n = 0;
  CanFrame f;
  while (n < max_frames && tx_.pop(f)) {
    ++counters_.tx_ok;
    if (sent_.capacity() > 0) {
      if (sent_.full()) {
        sent_.drop_oldest();
        ++sent_discarded_;
      }
      sent_.push(f);
    }
    if (peer_ != nullptr) peer_->deliver(f);
    ++n;
  }
  return n;
}

void MemCanBus::deliver(const CanFrame& frame) {
  if (!rx_.push(frame)) ++counters_.rx_overflow;
}

Status MemCanBus::receive(CanFrame& out) {
  if (!rx_.pop(out)) return Status::kEmpty;
  ++counters_.rx_ok;
  return Status::kOk;
}

Status MemCanBus::receive_sent(CanFrame& out) { return sent_.pop(out) ? Status::kOk : Status::kEmpty; }

void MemCanBus::set_state(CanBusState s) {
  if (s == CanBusState::kBusOff && state_ != CanBusState::kBusOff) ++counters_.bus_off;
  state_ = s;
}

}  // namespace uwbnav::hal
