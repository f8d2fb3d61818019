// MPS2-AN386 board port (qemu-system-arm -M mps2-an386): replay sources over
// the recording in flash, a lockstep clock, an in-memory CAN bus, a null
// parameter store and serial port, the SysTick instruction/cycle counter and
// the stack high-water mark. Static memory only.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hal/hal.hpp"
#include "hal/mps2/flash_recording.hpp"

namespace uwbnav::mps2 {

// IMU samples of a flash recording in order.
class FlashImuSource final : public hal::ImuSource {
 public:
  explicit FlashImuSource(const FlashRecording& rec) : rec_(rec) {}
  // kOk with the next sample when its t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, ImuSample& out) override;
  bool finished() const override { return next_ >= rec_.num_imu; }

 private:
  const FlashRecording& rec_;
  size_t next_ = 0;
};

// UWB ranges of a flash recording in order (the NLOS label is not stored).
class FlashUwbSource final : public hal::UwbSource {
 public:
  explicit FlashUwbSource(const FlashRecording& rec) : rec_(rec) {}
  // kOk with the next range when its t_us <= up_to_us, kEmpty otherwise.
  [[nodiscard]] Status poll(uint64_t up_to_us, UwbRange& out) override;
  bool finished() const override { return next_ >= rec_.num_uwb; }

 private:
  const FlashRecording& rec_;
  size_t next_ = 0;
};

// Time follows the loop (replay): deterministic whatever the emulator's speed.
class LockstepClock final : public hal::Clock {
 public:
  uint64_t now_us() override { return now_us_; }
  // Advances the time to deadline_us; never moves it backwards.
  void sleep_until_us(uint64_t deadline_us) override {
    if (deadline_us > now_us_) now_us_ = deadline_us;
  }

 private:
  uint64_t now_us_ = 0;  // [us]
};

// Transmit-only in-memory CAN controller: send() queues into a fixed ring the
// board drains after each cycle (pop_sent); nothing is ever received.
class RingCanBus final : public hal::CanBus {
 public:
  // Frames per cycle before kWouldBlock: the publisher sends at most its six
  // output messages in one cycle; a drop shows in the digest (can dropped=).
  static constexpr size_t kCapacity = 8;

  // Defined out of line (board.cpp): a global ring is then zero-initialised
  // (.bss) and constructed at start-up, instead of a 680 B initial image of
  // mostly zeros in flash (.data) for the one non-zero word, the vtable.
  RingCanBus();

  // kOk: queued. kWouldBlock: ring full, dropped and counted. kInvalidArgument: bad length.
  [[nodiscard]] Status send(const hal::CanFrame& frame) override;
  // Always kEmpty: no peer on this bus.
  [[nodiscard]] Status receive(hal::CanFrame& out) override;
  hal::CanBusState state() const override { return hal::CanBusState::kErrorActive; }
  const hal::CanCounters& counters() const override { return counters_; }
  void reset_counters() override { counters_ = hal::CanCounters{}; }

  // kOk: the oldest queued frame moved to `out`. kEmpty: ring empty.
  [[nodiscard]] Status pop_sent(hal::CanFrame& out);

 private:
  hal::CanFrame ring_[kCapacity];
  size_t head_ = 0;   // oldest frame
  size_t count_ = 0;
  hal::CanCounters counters_;
};

// No non-volatile storage: defaults every start, saving is unsupported.
class NullParamStore final : public hal::ParamStore {
 public:
  [[nodiscard]] Status load(uint8_t*, size_t, size_t*) override { return Status::kEmpty; }
  [[nodiscard]] Status save(const uint8_t*, size_t) override { return Status::kUnsupported; }
};

// Serial port with nobody attached (the digest goes out over semihosting).
class NullSerialPort final : public hal::SerialPort {
 public:
  size_t read(uint8_t*, size_t) override { return 0; }
  size_t write(const uint8_t*, size_t len) override { return len; }
};

// SysTick as a free-running 24-bit down-counter clocked by the core clock
// (qemu mps2: 25 MHz of virtual time; under -icount shift=0 one instruction
// advances virtual time by 1 ns, so one tick = 40 instructions). No interrupt:
// a measured span must stay below 2^24 ticks.
class CycleCounter {
 public:
  static constexpr uint32_t kMask = 0xFFFFFFU;
  static void start();
  static uint32_t now();
  // Ticks from `begin` to `end` (two now() readings), modulo 2^24.
  static uint32_t elapsed(uint32_t begin, uint32_t end) { return (begin - end) & kMask; }
};

// Runs a loop of exactly `instructions` Thumb instructions (2 per iteration;
// `instructions` even, >= 2) and returns the SysTick ticks it took.
uint32_t calibrate_ticks(uint32_t instructions);

// Stack painting (startup.cpp): the pattern, the reserved size and the deepest use so far.
constexpr uint32_t kStackPaint = 0x5AC3A55CU;
uint32_t stack_size_bytes();
uint32_t stack_used_bytes();

}  // namespace uwbnav::mps2
