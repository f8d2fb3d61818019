// Fixed-capacity byte FIFO for the console's transmit path: all-or-nothing
// pushes (a line is queued whole or not at all), contiguous peeks for the
// serial driver. Static memory only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace uwbnav {

template <size_t N>
class ByteRing {
  static_assert(N > 0, "ring capacity");

 public:
  static constexpr size_t capacity() { return N; }
  size_t size() const { return size_; }
  size_t free() const { return N - size_; }
  bool empty() const { return size_ == 0; }

  // Queues all `len` bytes, or none when they do not fit. Returns true when queued.
  bool push(const uint8_t* data, size_t len) {
    if (len > free()) return false;
    const size_t tail = (head_ + size_) % N;
    const size_t first = len < N - tail ? len : N - tail;
    std::memcpy(buf_ + tail, data, first);
    std::memcpy(buf_, data + first, len - first);
    size_ += len;
    return true;
  }
  bool push(const char* text, size_t len) { return push(reinterpret_cast<const uint8_t*>(text), len); }

  // The oldest queued bytes up to the end of the storage (may be fewer than size()).
  const uint8_t* peek(size_t* len) const {
    const size_t to_end = N - head_;
    *len = size_ < to_end ? size_ : to_end;
    return buf_ + head_;
  }
  // Drops the `len` oldest bytes (len <= size()).
  void consume(size_t len) {
    if (len > size_) len = size_;
    head_ = (head_ + len) % N;
    size_ -= len;
    if (size_ == 0) head_ = 0;
  }
  void clear() {
    head_ = 0;
    size_ = 0;
  }

 private:
  uint8_t buf_[N] = {};
  size_t head_ = 0;  // index of the oldest byte
  size_t size_ = 0;  // bytes queued
};

}  // namespace uwbnav
