// CRC-8 SAE J1850 against the AUTOSAR check values, the alive counter
// sequence, and the receiver's detection of corrupted, repeated and lost frames.
#include <gtest/gtest.h>

#include <vector>

#include "firmware/can/e2e.hpp"

namespace uwbnav::can {
namespace {

uint8_t crc_of(std::vector<uint8_t> v) { return crc8_j1850(v.data(), v.size()); }

TEST(CanCrc8, MatchesAutosarSaeJ1850CheckValues) {
  // AUTOSAR SWS CRC Library, CRC8 (SAE J1850) test vectors.
  EXPECT_EQ(crc_of({0x00, 0x00, 0x00, 0x00}), 0x59);
  EXPECT_EQ(crc_of({0xF2, 0x01, 0x83}), 0x37);
  EXPECT_EQ(crc_of({0x0F, 0xAA, 0x00, 0x55}), 0x79);
  EXPECT_EQ(crc_of({0x00, 0xFF, 0x55, 0x11}), 0xB8);
  EXPECT_EQ(crc_of({0x33, 0x22, 0x55, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF}), 0xCB);
  EXPECT_EQ(crc_of({0x92, 0x6B, 0x55}), 0x8C);
  EXPECT_EQ(crc_of({0xFF, 0xFF, 0xFF, 0xFF}), 0x74);
  EXPECT_EQ(crc_of({'1', '2', '3', '4', '5', '6', '7', '8', '9'}), 0x4B);
}

TEST(CanE2e, CrcCoversDataIdLowHighThenBytesOneToSeven) {
  uint8_t frame[8] = {0x00, 0x05, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66};
  const uint16_t data_id = 0x1101;
  EXPECT_EQ(e2e_crc(data_id, frame, 8), crc_of({0x01, 0x11, 0x05, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66}));
  // The CRC byte itself does not enter the CRC.
  frame[0] = 0xA5;
  EXPECT_EQ(e2e_crc(data_id, frame, 8), crc_of({0x01, 0x11, 0x05, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66}));
  // A different data ID changes the CRC (masquerading frames are caught).
  EXPECT_NE(e2e_crc(0x1102, frame, 8), e2e_crc(data_id, frame, 8));
}

TEST(CanE2e, AliveCounterRunsZeroToFourteenAndWrapsSkippingFifteen) {
  uint8_t c = 0;
  std::vector<uint8_t> seen;
  for (int i = 0; i < 31; ++i) {
    seen.push_back(c);
    c = next_alive_counter(c);
  }
  for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i % 15) << i;
}

TEST(CanE2e, ProtectWritesCounterNibbleAndKeepsUpperNibble) {
  uint8_t frame[8] = {0, 0xF0, 1, 2, 3, 4, 5, 6};
  e2e_protect(0x1234, 9, frame, 8);
  EXPECT_EQ(frame[1], 0xF9);
  EXPECT_EQ(frame[0], e2e_crc(0x1234, frame, 8));
}

struct Sender {
  uint16_t data_id = 0x1100;
  uint8_t counter = 0;
  uint8_t frame[8] = {};
  const uint8_t* next() {
    frame[2] = static_cast<uint8_t>(frame[2] + 7);
    e2e_protect(data_id, counter, frame, 8);
    counter = next_alive_counter(counter);
    return frame;
  }
};

TEST(CanE2eReceiver, AcceptsAnUnbrokenSequenceAcrossTheWrap) {
  Sender tx;
  E2eReceiver rx(1);
  EXPECT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kInitial);
  for (int i = 0; i < 40; ++i) EXPECT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kOk) << i;
}

TEST(CanE2eReceiver, FlagsRepeatedLostAndJumpedCountersThenResyncs) {
  Sender tx;
  E2eReceiver rx(2);
  ASSERT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kInitial);
  uint8_t copy[8];
  const uint8_t* f = tx.next();
  std::copy(f, f + 8, copy);
  EXPECT_EQ(rx.check(tx.data_id, copy, 8, 8), E2eVerdict::kOk);
  EXPECT_EQ(rx.check(tx.data_id, copy, 8, 8), E2eVerdict::kRepeated);
  tx.next();  // one frame lost: step 2 <= max_delta
  EXPECT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kOkSomeLost);
  for (int i = 0; i < 3; ++i) tx.next();  // three lost: step 4 > max_delta
  EXPECT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kWrongSequence);
  EXPECT_EQ(rx.check(tx.data_id, tx.next(), 8, 8), E2eVerdict::kOk) << "resynchronised on the jumped frame";
}

TEST(CanE2eReceiver, DetectsEverySingleBitFlipAndWrongLengthAndCounterFifteen) {
  Sender tx;
  E2eReceiver rx(14);
  const uint8_t* f = tx.next();
  uint8_t good[8];
  std::copy(f, f + 8, good);
  for (int bit = 0; bit < 64; ++bit) {
    uint8_t bad[8];
    std::copy(good, good + 8, bad);
    bad[bit / 8] = static_cast<uint8_t>(bad[bit / 8] ^ (1U << (bit % 8)));
    EXPECT_EQ(rx.check(tx.data_id, bad, 8, 8), E2eVerdict::kWrongCrc) << "bit " << bit;
  }
  EXPECT_EQ(rx.check(tx.data_id, good, 7, 8), E2eVerdict::kBadLength);
  uint8_t fifteen[8];
  std::copy(good, good + 8, fifteen);
  e2e_protect(tx.data_id, 15, fifteen, 8);
  EXPECT_EQ(rx.check(tx.data_id, fifteen, 8, 8), E2eVerdict::kBadCounter);
  EXPECT_EQ(rx.check(tx.data_id, good, 8, 8), E2eVerdict::kInitial);
  EXPECT_FALSE(e2e_accepted(E2eVerdict::kWrongCrc));
  EXPECT_TRUE(e2e_accepted(E2eVerdict::kOkSomeLost));
}

}  // namespace
}  // namespace uwbnav::can
