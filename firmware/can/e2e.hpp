// E2E protection of uwbnav CAN frames in the style of AUTOSAR E2E profile 1:
// CRC-8 SAE J1850 over a 16-bit data ID and the payload, 4-bit alive counter 0..14.
#pragma once

#include <cstddef>
#include <cstdint>

namespace uwbnav::can {

// CRC-8 SAE J1850 (AUTOSAR Crc_CalculateCRC8): polynomial 0x1D, initial value
// 0xFF, final XOR 0xFF, no reflection. Check value over "123456789" is 0x4B.
uint8_t crc8_j1850(const uint8_t* data, size_t len);

// Byte offsets inside every protected frame (docs/can.md "E2E protection").
constexpr size_t kCrcByte = 0;        // byte 0: CRC-8
constexpr size_t kCounterByte = 1;    // byte 1 bits 0..3: alive counter
constexpr uint8_t kCounterMask = 0x0F;
constexpr uint8_t kAliveCounterMax = 14;   // counter runs 0..14; 15 is never sent
constexpr uint8_t kAliveCounterModulo = 15;

// CRC of one protected frame: crc8_j1850 over the byte string
//   [data_id & 0xFF, data_id >> 8, frame[1], frame[2], ..., frame[len-1]]
// i.e. the data ID low byte first, then the high byte, then every payload byte
// except the CRC byte itself (AUTOSAR profile 1, data ID mode "both bytes").
uint8_t e2e_crc(uint16_t data_id, const uint8_t* frame, size_t len);

// Writes the alive counter into byte 1 (low nibble) and the CRC into byte 0.
// Call after every other signal of the frame is packed. len >= 2.
void e2e_protect(uint16_t data_id, uint8_t counter, uint8_t* frame, size_t len);

constexpr uint8_t next_alive_counter(uint8_t counter) {
  return counter >= kAliveCounterMax ? 0 : static_cast<uint8_t>(counter + 1);
}

// Receiver verdict for one frame (AUTOSAR E2E_P01CheckStatusType analogue).
enum class E2eVerdict : uint8_t {
  kOk = 0,          // CRC good, counter advanced by exactly 1
  kInitial,         // CRC good, first frame after start/resync: accepted
  kOkSomeLost,      // CRC good, counter advanced by 2..max_delta: accepted, frames lost
  kRepeated,        // CRC good, counter unchanged: dropped
  kWrongSequence,   // CRC good, counter jumped more than max_delta: dropped, resync
  kWrongCrc,        // CRC mismatch: dropped
  kBadLength,       // DLC not the message's length: dropped
  kBadCounter,      // counter value 15 (never sent): dropped
};

constexpr bool e2e_accepted(E2eVerdict v) {
  return v == E2eVerdict::kOk || v == E2eVerdict::kInitial || v == E2eVerdict::kOkSomeLost;
}

const char* e2e_verdict_name(E2eVerdict v);

// Per-message receiver state: checks CRC and alive counter of consecutive frames.
class E2eReceiver {
 public:
  // max_delta: largest accepted counter step (1 = no frame may be lost).
  explicit E2eReceiver(uint8_t max_delta = 2) : max_delta_(max_delta) {}

  void set_max_delta(uint8_t max_delta) { max_delta_ = max_delta; }
  // Forgets the last counter: the next good frame is kInitial.
  void reset() { have_last_ = false; }

  // Checks a received frame of `len` bytes against `expected_len` and `data_id`.
  // A kWrongSequence frame becomes the new reference, so the stream resyncs
  // on the next consecutive frame.
  E2eVerdict check(uint16_t data_id, const uint8_t* frame, size_t len, size_t expected_len);

  uint8_t last_counter() const { return last_counter_; }

 private:
  uint8_t max_delta_;
  uint8_t last_counter_ = 0;
  bool have_last_ = false;
};

}  // namespace uwbnav::can
