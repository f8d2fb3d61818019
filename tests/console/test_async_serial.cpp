// AsyncSerialPort: the console's terminal/pipe I/O leaves the real-time cycle.
// The cycle's read()/write() touch only bounded rings (no system call that could
// sleep on a lock held by the reader at the other end); the I/O thread moves the
// bytes; a full ring refuses bytes (counted) instead of blocking.
#include <gtest/gtest.h>

#include <string>

#include "console_rig.hpp"
#include "hal/host/async_serial.hpp"

namespace uwbnav {
namespace {

using testing::MemSerialPort;

TEST(AsyncSerialPort, TheCycleOnlyTouchesTheRingsTheIoThreadMovesTheBytes) {
  MemSerialPort inner;
  bool closed = false;
  hal::AsyncSerialPort port(inner, [&closed] { return closed; }, 64, 64);
  const std::string reply = "status t_us=1\r\n";
  EXPECT_EQ(port.write(reinterpret_cast<const uint8_t*>(reply.data()), reply.size()), reply.size());
  EXPECT_TRUE(inner.output.empty());  // nothing reached the port from the caller's thread
  inner.type("help\r");
  uint8_t buf[16];
  EXPECT_EQ(port.read(buf, sizeof buf), 0U);  // input arrives through the I/O thread only
  EXPECT_GT(port.pump(), 0U);
  EXPECT_EQ(inner.output, reply);
  ASSERT_EQ(port.read(buf, sizeof buf), 5U);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(buf), 5), "help\r");
  EXPECT_FALSE(port.input_closed());
  closed = true;  // end of input seen by the I/O thread
  (void)port.pump();
  EXPECT_TRUE(port.input_closed());
}

TEST(AsyncSerialPort, AFullTxRingRefusesBytesAndCountsThemASlowReaderKeepsTheRest) {
  MemSerialPort inner;
  inner.write_room = 0;  // the reader takes nothing
  hal::AsyncSerialPort port(inner, {}, 32, 16);
  const std::string text(50, 'x');
  EXPECT_EQ(port.write(reinterpret_cast<const uint8_t*>(text.data()), text.size()), 32U);
  EXPECT_EQ(port.counters().tx_refused, 18U);
  EXPECT_EQ(port.counters().tx_high_water, 32U);
  (void)port.pump();
  EXPECT_TRUE(inner.output.empty());
  inner.write_room = 1000;  // the reader catches up: every queued byte goes out, in order
  (void)port.pump();
  (void)port.pump();
  EXPECT_EQ(inner.output, std::string(32, 'x'));
}

TEST(AsyncSerialPort, StopWritesOutWhatIsQueued) {
  MemSerialPort inner;
  hal::AsyncSerialPort port(inner, {}, 4096, 64);
  port.start(100);
  const std::string text(3000, 'y');
  EXPECT_EQ(port.write(reinterpret_cast<const uint8_t*>(text.data()), text.size()), text.size());
  port.stop();
  EXPECT_EQ(inner.output, text);
}

}  // namespace
}  // namespace uwbnav
