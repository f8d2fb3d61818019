// CRC-8 SAE J1850 and alive counter checking for the uwbnav CAN E2E protection.
#include "firmware/can/e2e.hpp"

namespace uwbnav::can {
namespace {

// Table of the MSB-first CRC register update for polynomial 0x1D.
struct Crc8Table {
  uint8_t v[256];
};

constexpr Crc8Table make_crc8_table() {
  Crc8Table t{};
  for (int i = 0; i < 256; ++i) {
    uint8_t crc = static_cast<uint8_t>(i);
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 0x80U) != 0 ? static_cast<uint8_t>((crc << 1) ^ 0x1DU) : static_cast<uint8_t>(crc << 1);
    }
    t.v[i] = crc;
  }
  return t;
}

constexpr Crc8Table kCrc8Table = make_crc8_table();

uint8_t crc8_update(uint8_t crc, uint8_t byte) { return kCrc8Table.v[crc ^ byte]; }

}  // namespace

uint8_t crc8_j1850(const uint8_t* data, size_t len) {
  uint8_t crc = 0xFF;
  for (size_t i = 0; i < len; ++i) crc = crc8_update(crc, data[i]);
  return static_cast<uint8_t>(crc ^ 0xFFU);
}

uint8_t e2e_crc(uint16_t data_id, const uint8_t* frame, size_t len) {
  uint8_t crc = 0xFF;
  crc = crc8_update(crc, static_cast<uint8_t>(data_id & 0xFFU));
  crc = crc8_update(crc, static_cast<uint8_t>(data_id >> 8));
  for (size_t i = kCrcByte + 1; i < len; ++i) crc = crc8_update(crc, frame[i]);
  return static_cast<uint8_t>(crc ^ 0xFFU);
}

void e2e_protect(uint16_t data_id, uint8_t counter, uint8_t* frame, size_t len) {
  frame[kCounterByte] = static_cast<uint8_t>((frame[kCounterByte] & ~kCounterMask) | (counter & kCounterMask));
  frame[kCrcByte] = e2e_crc(data_id, frame, len);
}

const char* e2e_verdict_name(E2eVerdict v) {
  switch (v) {
    case E2eVerdict::kOk: return "ok";
    case E2eVerdict::kInitial: return "initial";
    case E2eVerdict::kOkSomeLost: return "ok_some_lost";
    case E2eVerdict::kRepeated: return "repeated";
    case E2eVerdict::kWrongSequence: return "wrong_sequence";
    case E2eVerdict::kWrongCrc: return "wrong_crc";
    case E2eVerdict::kBadLength: return "bad_length";
    case E2eVerdict::kBadCounter: return "bad_counter";
  }
  return "unknown";
}

E2eVerdict E2eReceiver::check(uint16_t data_id, const uint8_t* frame, size_t len, size_t expected_len) {
  if (len != expected_len || len < 2) return E2eVerdict::kBadLength;
  if (e2e_crc(data_id, frame, len) != frame[kCrcByte]) return E2eVerdict::kWrongCrc;
  const uint8_t counter = frame[kCounterByte] & kCounterMask;
  if (counter > kAliveCounterMax) return E2eVerdict::kBadCounter;
  if (!have_last_) {
    have_last_ = true;
    last_counter_ = counter;
    return E2eVerdict::kInitial;
  }
  const uint8_t delta =
      static_cast<uint8_t>((counter + kAliveCounterModulo - last_counter_) % kAliveCounterModulo);
  if (delta == 0) return E2eVerdict::kRepeated;
  last_counter_ = counter;
  if (delta == 1) return E2eVerdict::kOk;
  if (delta <= max_delta_) return E2eVerdict::kOkSomeLost;
  return E2eVerdict::kWrongSequence;
}

}  // namespace uwbnav::can
