// The hardware abstraction layer: the narrow interfaces a board implements and
// passes by reference into the firmware. `virtual` lives only at this edge.
// Every call is non-blocking unless stated; every call states its contract.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav::hal {

// IMU samples in sensor-timestamp order.
class ImuSource {
 public:
  virtual ~ImuSource() = default;
  // Pops the oldest pending sample whose t_us <= up_to_us into `out`.
  // kOk: `out` filled. kEmpty: no sample due yet (or source finished; see finished()).
  // kIoError: the device failed; the caller counts it and carries on.
  [[nodiscard]] virtual Status poll(uint64_t up_to_us, ImuSample& out) = 0;
  // True when a finite source (recording) has nothing left at all.
  virtual bool finished() const = 0;
};

// UWB ranges in sensor-timestamp order (per tag round-robin across anchors).
class UwbSource {
 public:
  virtual ~UwbSource() = default;
  // Same contract as ImuSource::poll.
  [[nodiscard]] virtual Status poll(uint64_t up_to_us, UwbRange& out) = 0;
  virtual bool finished() const = 0;
};

// GNSS fixes in arrival order (docs/dataset-format.md "gnss.csv").
class GnssSource {
 public:
  virtual ~GnssSource() = default;
  // Pops the oldest pending fix that has arrived by up_to_us (rx_t_us <= up_to_us).
  // Same status contract as ImuSource::poll.
  [[nodiscard]] virtual Status poll(uint64_t up_to_us, GnssFix& out) = 0;
  virtual bool finished() const = 0;
};

// Broadcast states of neighbour vehicles in arrival order (docs/dataset-format.md
// "neighbours.csv"); on a vehicle they arrive over CAN (UWBNAV_Coop*), which
// the firmware decodes itself: this source is for boards that have them otherwise.
class NeighbourSource {
 public:
  virtual ~NeighbourSource() = default;
  // Pops the oldest pending state that has arrived by up_to_us (rx_t_us <= up_to_us).
  // Same status contract as ImuSource::poll.
  [[nodiscard]] virtual Status poll(uint64_t up_to_us, NeighbourState& out) = 0;
  virtual bool finished() const = 0;
};

// Classical CAN / CAN FD frame as it crosses the bus.
struct CanFrame {
  static constexpr uint8_t kFlagExtended = 0x01;  // 29-bit identifier
  static constexpr uint8_t kFlagFd = 0x02;        // CAN FD frame (len up to 64)
  static constexpr uint8_t kFlagError = 0x04;     // error frame (SocketCAN CAN_ERR_FLAG)
  static constexpr uint8_t kFlagBrs = 0x08;       // CAN FD bit-rate switch

  uint64_t t_us = 0;   // timestamp: tx time (sender) or rx time (receiver) [us]
  uint32_t id = 0;     // 11- or 29-bit identifier (no flag bits)
  uint8_t len = 0;     // payload length in bytes (0..8 classic, 0..64 FD)
  uint8_t flags = 0;
  uint8_t data[64] = {};
};

enum class CanBusState : uint8_t { kErrorActive = 0, kErrorPassive = 1, kBusOff = 2, kDown = 3 };

struct CanCounters {
  uint32_t tx_ok = 0;
  uint32_t tx_dropped = 0;       // queue full / ENOBUFS: frame dropped (never blocks)
  uint32_t rx_ok = 0;
  uint32_t rx_overflow = 0;      // receive queue overflowed, frames lost
  uint32_t error_frames = 0;     // error frames seen
  uint32_t bus_off = 0;          // bus-off events
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  // Queues one frame for transmission. kOk: accepted by the driver.
  // kWouldBlock: driver queue full, frame dropped and counted (the caller does
  // not retry inside the cycle). kIoError: interface down / bus-off.
  [[nodiscard]] virtual Status send(const CanFrame& frame) = 0;
  // Pops one received frame. kOk: `out` filled. kEmpty: nothing pending.
  [[nodiscard]] virtual Status receive(CanFrame& out) = 0;
  virtual CanBusState state() const = 0;
  virtual const CanCounters& counters() const = 0;
  // Zeroes the counters (console `reset stats`); the bus state is untouched.
  virtual void reset_counters() = 0;
};

// Byte stream to a person or a script (UART on target, stdio/pty on host).
class SerialPort {
 public:
  virtual ~SerialPort() = default;
  // Reads up to `cap` pending bytes; returns how many (0 when none). Never blocks.
  virtual size_t read(uint8_t* buf, size_t cap) = 0;
  // Offers `len` bytes; returns how many were accepted (may be fewer when the
  // reader is slow: the caller drops or retries, it never blocks).
  virtual size_t write(const uint8_t* buf, size_t len) = 0;
};

// Monotonic clock in microseconds.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual uint64_t now_us() = 0;
  // Blocks until now_us() >= deadline_us (real-time boards) or advances the
  // simulated time to deadline_us (lockstep boards). Returns immediately when
  // the deadline has already passed.
  virtual void sleep_until_us(uint64_t deadline_us) = 0;
};

// Non-volatile parameter storage (flash page on target, a file on host).
class ParamStore {
 public:
  virtual ~ParamStore() = default;
  // Reads the stored blob into buf. kOk: *len set. kEmpty: nothing stored.
  // kIoError / kInvalidArgument: unreadable or too large.
  [[nodiscard]] virtual Status load(uint8_t* buf, size_t cap, size_t* len) = 0;
  // Stores the blob atomically (all or nothing).
  [[nodiscard]] virtual Status save(const uint8_t* buf, size_t len) = 0;
};

// Everything a board hands the firmware, wired once in one place per board.
struct Board {
  ImuSource& imu;
  UwbSource& uwb;
  CanBus& can;
  SerialPort& serial;
  Clock& clock;
  ParamStore& params;
  const SiteConfig& site;
  GnssSource* gnss = nullptr;  // optional: null on a vehicle without a GNSS receiver
  NeighbourSource* neighbours = nullptr;  // optional: null when neighbour states come only over CAN
};

}  // namespace uwbnav::hal
