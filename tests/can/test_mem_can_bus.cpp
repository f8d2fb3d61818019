// MemCanBus: bounded queues with counted overflow, two connected endpoints, sent-frame tap.
#include <gtest/gtest.h>

#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::hal {
namespace {

CanFrame frame(uint32_t id, uint8_t b0) {
  CanFrame f;
  f.id = id;
  f.len = 1;
  f.data[0] = b0;
  return f;
}

TEST(MemCanBus, ConnectedEndpointsDeliverInOrder) {
  MemCanBus a, b;
  MemCanBus::connect(a, b);
  for (uint8_t i = 0; i < 5; ++i) ASSERT_EQ(a.send(frame(0x100 + i, i)), Status::kOk);
  ASSERT_EQ(b.send(frame(0x200, 9)), Status::kOk);
  CanFrame f;
  for (uint8_t i = 0; i < 5; ++i) {
    ASSERT_EQ(b.receive(f), Status::kOk);
    EXPECT_EQ(f.id, 0x100U + i);
  }
  EXPECT_EQ(b.receive(f), Status::kEmpty);
  ASSERT_EQ(a.receive(f), Status::kOk);
  EXPECT_EQ(f.id, 0x200U);
  EXPECT_EQ(a.counters().tx_ok, 5U);
  EXPECT_EQ(b.counters().rx_ok, 5U);
}

TEST(MemCanBus, FullTransmitQueueRefusesWithWouldBlockAndCounts) {
  MemCanBus a(3, 8);
  a.set_auto_flush(false);
  for (uint8_t i = 0; i < 3; ++i) EXPECT_EQ(a.send(frame(1, i)), Status::kOk);
  EXPECT_EQ(a.send(frame(1, 3)), Status::kWouldBlock);
  EXPECT_EQ(a.counters().tx_dropped, 1U);
  EXPECT_EQ(a.flush(2), 2U);
  EXPECT_EQ(a.send(frame(1, 4)), Status::kOk);
  EXPECT_EQ(a.tx_pending(), 2U);
}

TEST(MemCanBus, FullReceiveQueueLosesNewFramesAndCountsOverflow) {
  MemCanBus a, b(64, 4);
  MemCanBus::connect(a, b);
  for (uint8_t i = 0; i < 6; ++i) ASSERT_EQ(a.send(frame(1, i)), Status::kOk);
  EXPECT_EQ(b.counters().rx_overflow, 2U);
  CanFrame f;
  for (uint8_t i = 0; i < 4; ++i) {
    ASSERT_EQ(b.receive(f), Status::kOk);
    EXPECT_EQ(f.data[0], i) << "oldest frames kept, newest lost (as a hardware FIFO)";
  }
}

TEST(MemCanBus, SentTapKeepsNewestAndBusOffRefusesSends) {
  MemCanBus a(4, 4, 2);
  for (uint8_t i = 0; i < 3; ++i) ASSERT_EQ(a.send(frame(1, i)), Status::kOk);
  EXPECT_EQ(a.sent_discarded(), 1U);
  CanFrame f;
  ASSERT_EQ(a.receive_sent(f), Status::kOk);
  EXPECT_EQ(f.data[0], 1);
  a.set_state(CanBusState::kBusOff);
  EXPECT_EQ(a.send(frame(1, 9)), Status::kIoError);
  EXPECT_EQ(a.counters().bus_off, 1U);
  EXPECT_EQ(a.state(), CanBusState::kBusOff);
  CanFrame fd = frame(1, 0);
  fd.len = 12;
  a.set_state(CanBusState::kErrorActive);
  EXPECT_EQ(a.send(fd), Status::kInvalidArgument) << "12 bytes need the FD flag";
  fd.flags = CanFrame::kFlagFd;
  EXPECT_EQ(a.send(fd), Status::kOk);
}

}  // namespace
}  // namespace uwbnav::hal
