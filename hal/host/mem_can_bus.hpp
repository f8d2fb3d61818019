// In-memory CAN bus endpoint for tests and lockstep simulation: bounded
// transmit and receive queues with explicit overflow behaviour, optionally
// connected to a peer endpoint (frames sent on one arrive at the other), and a
// tap of everything sent. Storage is allocated once at construction: send and
// receive never touch the heap (the firmware's no-allocation test runs on it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hal/hal.hpp"

namespace uwbnav::hal {

// Fixed-capacity FIFO of frames.
class CanFrameRing {
 public:
  explicit CanFrameRing(size_t capacity) : buf_(capacity) {}
  bool push(const CanFrame& f);  // false when full (frame not stored)
  bool pop(CanFrame& out);       // false when empty
  void drop_oldest();
  size_t size() const { return size_; }
  size_t capacity() const { return buf_.size(); }
  bool full() const { return size_ == buf_.size(); }

 private:
  std::vector<CanFrame> buf_;
  size_t head_ = 0;
  size_t size_ = 0;
};

class MemCanBus : public CanBus {
 public:
  // tx_capacity: frames the "driver" holds before send() refuses (kWouldBlock,
  // counted in tx_dropped). rx_capacity: frames held for receive(); a frame
  // arriving at a full receive queue is lost and counted in rx_overflow.
  // sent_capacity: depth of the sent-frames tap (receive_sent); when full the
  // oldest tapped frame is discarded (counted in sent_discarded()), the bus
  // itself is unaffected.
  explicit MemCanBus(size_t tx_capacity = 64, size_t rx_capacity = 1024, size_t sent_capacity = 1024);
  ~MemCanBus() override;
  MemCanBus(const MemCanBus&) = delete;
  MemCanBus& operator=(const MemCanBus&) = delete;

  // Connects two endpoints (replacing earlier peers). Frames put on the wire
  // by one endpoint arrive in the other's receive queue.
  static void connect(MemCanBus& a, MemCanBus& b);
  void disconnect();

  // kOk: queued (and, in auto-flush mode, put on the wire at once).
  // kWouldBlock: transmit queue full, frame dropped and counted in tx_dropped.
  // kIoError: state is bus-off or down, frame dropped and counted in tx_dropped.
  // kInvalidArgument: len > 8 without kFlagFd, or > 64.
  [[nodiscard]] Status send(const CanFrame& frame) override;
  // kOk: oldest received frame popped. kEmpty: nothing pending.
  [[nodiscard]] Status receive(CanFrame& out) override;
  CanBusState state() const override { return state_; }
  const CanCounters& counters() const override { return counters_; }
  void reset_counters() override { counters_ = CanCounters{}; }

  // Pops the oldest frame this endpoint put on the wire. kEmpty when none.
  [[nodiscard]] Status receive_sent(CanFrame& out);
  uint64_t sent_discarded() const { return sent_discarded_; }

  // Auto flush (default on): send() puts the frame on the wire immediately, so
  // the transmit queue never fills. Off: frames wait in the transmit queue until flush().
  void set_auto_flush(bool on) { auto_flush_ = on; }
  // Puts up to max_frames queued frames on the wire (tx_ok counts them); returns how many.
  size_t flush(size_t max_frames = SIZE_MAX);
  size_t tx_pending() const { return tx_.size(); }
  size_t rx_pending() const { return rx_.size(); }

  // Injects a frame as if received from the wire (rx_capacity applies).
  void inject(const CanFrame& frame) { deliver(frame); }
  // Simulates controller states: kBusOff / kDown make send() fail; entering kBusOff counts bus_off.
  void set_state(CanBusState s);

 private:
  void deliver(const CanFrame& frame);

  CanFrameRing tx_;
  CanFrameRing rx_;
  CanFrameRing sent_;
  MemCanBus* peer_ = nullptr;
  bool auto_flush_ = true;
  uint64_t sent_discarded_ = 0;
  CanBusState state_ = CanBusState::kErrorActive;
  CanCounters counters_;
};

}  // namespace uwbnav::hal
