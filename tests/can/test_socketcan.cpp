// SocketCanBus: the real AF_CAN path where the kernel has it (skipped with a
// reason otherwise) and the same framing, EAGAIN and error-frame logic over a
// Unix SOCK_SEQPACKET socketpair carrying struct can_frame / canfd_frame bytes.
#include <gtest/gtest.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <string>

#include "hal/host/socketcan_bus.hpp"

namespace uwbnav::hal {
namespace {

struct Pair {
  SocketCanBus a;
  int raw = -1;  // the other end, written/read as plain struct can_frame bytes
  explicit Pair(bool fd = false) {
    int x = -1;
    int y = -1;
    EXPECT_EQ(can_link_pair(x, y), Status::kOk);
    SocketCanOptions o;
    o.fd = fd;
    EXPECT_EQ(a.adopt_fd(x, o), Status::kOk);
    raw = y;
  }
  ~Pair() {
    if (raw >= 0) ::close(raw);
  }
  void write_frame(const struct can_frame& cf) const { ASSERT_EQ(::write(raw, &cf, sizeof(cf)), static_cast<ssize_t>(sizeof(cf))); }
};

TEST(SocketCan, OpenReportsAClearStatusWhereTheKernelLacksAfCan) {
  SocketCanBus bus;
  const Status s = bus.open("vcan0");
  if (s == Status::kUnsupported) {
    EXPECT_NE(bus.last_error().find("SocketCAN"), std::string::npos) << bus.last_error();
    EXPECT_FALSE(bus.is_open());
    CanFrame f;
    EXPECT_EQ(bus.send(f), Status::kIoError);
    GTEST_SKIP() << "kernel has no AF_CAN: " << bus.last_error();
  }
  if (s == Status::kNotFound) {
    GTEST_SKIP() << "AF_CAN present but no vcan0 (ip link add dev vcan0 type vcan && ip link set up vcan0)";
  }
  ASSERT_EQ(s, Status::kOk) << bus.last_error();
  SocketCanBus rx;
  ASSERT_EQ(rx.open("vcan0"), Status::kOk) << rx.last_error();
  CanFrame f;
  f.id = 0x101;
  f.len = 2;
  f.data[0] = 0xAB;
  ASSERT_EQ(bus.send(f), Status::kOk);
  CanFrame got;
  Status r = Status::kEmpty;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (r == Status::kEmpty && std::chrono::steady_clock::now() < until) r = rx.receive(got);
  ASSERT_EQ(r, Status::kOk);
  EXPECT_EQ(got.id, 0x101U);
  EXPECT_EQ(got.data[0], 0xAB);
}

TEST(SocketCan, OpenOfAMissingInterfaceIsNotFoundOrUnsupported) {
  SocketCanBus bus;
  const Status s = bus.open("nosuchcan7");
  EXPECT_TRUE(s == Status::kNotFound || s == Status::kUnsupported) << status_name(s);
  EXPECT_FALSE(bus.last_error().empty());
}

TEST(SocketCanWire, RecordsHaveTheKernelStructLayout) {
  CanFrame f;
  f.id = 0x123;
  f.len = 3;
  f.data[0] = 1;
  f.data[1] = 2;
  f.data[2] = 3;
  uint8_t buf[kCanFdMtu];
  ASSERT_EQ(to_wire(f, false, buf), kCanMtu);
  struct can_frame cf;
  std::memcpy(&cf, buf, sizeof(cf));
  EXPECT_EQ(cf.can_id, 0x123U);
  EXPECT_EQ(cf.len, 3);
  EXPECT_EQ(cf.data[2], 3);
  f.flags = CanFrame::kFlagExtended;
  f.id = 0x1ABCDEF0;
  ASSERT_EQ(to_wire(f, false, buf), kCanMtu);
  std::memcpy(&cf, buf, sizeof(cf));
  EXPECT_EQ(cf.can_id, 0x1ABCDEF0U | CAN_EFF_FLAG);
  f.flags = CanFrame::kFlagFd | CanFrame::kFlagBrs;
  f.id = 0x10;
  f.len = 20;
  EXPECT_EQ(to_wire(f, false, buf), 0U) << "FD frame on a classic socket";
  ASSERT_EQ(to_wire(f, true, buf), kCanFdMtu);
  struct canfd_frame fd;
  std::memcpy(&fd, buf, sizeof(fd));
  EXPECT_EQ(fd.len, 20);
  EXPECT_EQ(fd.flags & CANFD_BRS, CANFD_BRS);
  f.len = 21;
  EXPECT_EQ(to_wire(f, true, buf), 0U) << "21 is not a CAN FD length";
  CanFrame back;
  f.len = 20;
  ASSERT_EQ(to_wire(f, true, buf), kCanFdMtu);
  ASSERT_EQ(from_wire(buf, kCanFdMtu, back), Status::kOk);
  EXPECT_EQ(back.flags, CanFrame::kFlagFd | CanFrame::kFlagBrs);
  EXPECT_EQ(back.len, 20);
  EXPECT_EQ(from_wire(buf, 15, back), Status::kInvalidArgument);
}

TEST(SocketCanPair, ClassicAndFdFramesCrossTheLinkIntact) {
  int x = -1;
  int y = -1;
  ASSERT_EQ(can_link_pair(x, y), Status::kOk);
  SocketCanOptions o;
  o.fd = true;
  SocketCanBus a, b;
  ASSERT_EQ(a.adopt_fd(x, o), Status::kOk);
  ASSERT_EQ(b.adopt_fd(y, o), Status::kOk);
  CanFrame f;
  f.id = 0x105;
  f.len = 8;
  for (int i = 0; i < 8; ++i) f.data[i] = static_cast<uint8_t>(0xA0 + i);
  ASSERT_EQ(a.send(f), Status::kOk);
  CanFrame fd;
  fd.id = 0x0A0;
  fd.flags = CanFrame::kFlagFd;
  fd.len = 64;
  fd.data[63] = 0x5A;
  ASSERT_EQ(a.send(fd), Status::kOk);
  CanFrame got;
  ASSERT_EQ(b.receive(got), Status::kOk);
  EXPECT_EQ(got.id, 0x105U);
  EXPECT_EQ(0, std::memcmp(got.data, f.data, 8));
  EXPECT_GT(got.t_us, 0U) << "receive time stamped";
  ASSERT_EQ(b.receive(got), Status::kOk);
  EXPECT_EQ(got.len, 64);
  EXPECT_EQ(got.data[63], 0x5A);
  EXPECT_EQ(b.receive(got), Status::kEmpty);
  EXPECT_EQ(a.counters().tx_ok, 2U);
  EXPECT_EQ(b.counters().rx_ok, 2U);
}

TEST(SocketCanPair, FullSocketBufferDropsAndCountsWithoutBlocking) {
  Pair p;
  CanFrame f;
  f.id = 0x101;
  f.len = 8;
  const auto t0 = std::chrono::steady_clock::now();
  int ok_count = 0;
  int would_block = 0;
  for (int i = 0; i < 100000 && would_block < 10; ++i) {
    const Status s = p.a.send(f);
    if (s == Status::kOk) ++ok_count;
    if (s == Status::kWouldBlock) ++would_block;
    ASSERT_TRUE(s == Status::kOk || s == Status::kWouldBlock) << status_name(s);
  }
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(ok_count, 0);
  EXPECT_EQ(would_block, 10);
  EXPECT_EQ(p.a.counters().tx_dropped, 10U);
  EXPECT_LT(elapsed_s, 2.0) << "send never blocks";
}

TEST(SocketCanPair, ErrorFramesAreDecodedCountedAndDriveTheBusState) {
  Pair p;
  struct can_frame e;
  std::memset(&e, 0, sizeof(e));
  e.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT;
  e.len = CAN_ERR_DLC;
  e.data[1] = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_RX_OVERFLOW;
  e.data[6] = 12;
  e.data[7] = 130;
  p.write_frame(e);
  CanFrame got;
  EXPECT_EQ(p.a.receive(got), Status::kEmpty) << "error frames are not handed to the firmware";
  EXPECT_EQ(p.a.state(), CanBusState::kErrorPassive);
  EXPECT_EQ(p.a.counters().error_frames, 1U);
  EXPECT_EQ(p.a.counters().rx_overflow, 1U);
  EXPECT_EQ(p.a.error_counters().passive, 1U);
  EXPECT_EQ(p.a.error_counters().rx_error_count, 130);
  EXPECT_TRUE(p.a.last_error_frame().controller);

  e.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  std::memset(e.data, 0, sizeof(e.data));
  p.write_frame(e);
  struct can_frame d;
  std::memset(&d, 0, sizeof(d));
  d.can_id = 0x0A0;
  d.len = 1;
  p.write_frame(d);
  ASSERT_EQ(p.a.receive(got), Status::kOk) << "data frame after the error frame";
  EXPECT_EQ(got.id, 0x0A0U);
  EXPECT_EQ(p.a.state(), CanBusState::kBusOff);
  EXPECT_EQ(p.a.counters().bus_off, 1U);
  CanFrame f;
  f.id = 0x101;
  EXPECT_EQ(p.a.send(f), Status::kIoError) << "bus-off: frames dropped until the controller restarts";
  EXPECT_EQ(p.a.counters().tx_dropped, 1U);

  e.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  p.write_frame(e);
  EXPECT_EQ(p.a.receive(got), Status::kEmpty);
  EXPECT_EQ(p.a.state(), CanBusState::kErrorActive);
  EXPECT_EQ(p.a.send(f), Status::kOk);
  EXPECT_EQ(p.a.counters().error_frames, 3U);
}

TEST(SocketCanErrors, DecodesProtocolTransceiverAckAndArbitrationClasses) {
  CanFrame e;
  e.flags = CanFrame::kFlagError;
  e.id = CAN_ERR_PROT | CAN_ERR_TRX | CAN_ERR_ACK | CAN_ERR_LOSTARB | CAN_ERR_TX_TIMEOUT | CAN_ERR_BUSERROR;
  e.len = 8;
  e.data[0] = 17;
  e.data[2] = CAN_ERR_PROT_STUFF;
  e.data[3] = CAN_ERR_PROT_LOC_ACK;
  e.data[4] = CAN_ERR_TRX_CANH_NO_WIRE;
  const CanErrorInfo i = decode_error_frame(e);
  EXPECT_TRUE(i.protocol);
  EXPECT_EQ(i.protocol_type, CAN_ERR_PROT_STUFF);
  EXPECT_EQ(i.protocol_location, CAN_ERR_PROT_LOC_ACK);
  EXPECT_TRUE(i.transceiver);
  EXPECT_EQ(i.transceiver_status, CAN_ERR_TRX_CANH_NO_WIRE);
  EXPECT_TRUE(i.no_ack);
  EXPECT_TRUE(i.lost_arbitration);
  EXPECT_EQ(i.lost_arbitration_bit, 17);
  EXPECT_TRUE(i.tx_timeout);
  EXPECT_TRUE(i.bus_error);
  EXPECT_FALSE(i.bus_off);
  const std::string d = describe_error(i);
  EXPECT_NE(d.find("no-ack"), std::string::npos) << d;
  EXPECT_NE(d.find("protocol-violation"), std::string::npos) << d;
}

TEST(SocketCanLink, UnixSeqpacketLinkConnectsTwoEndpointsByPath) {
  const std::string path = std::string(UWBNAV_BINARY_DIR) + "/can_link_test.sock";
  int listen_fd = -1;
  std::string err;
  ASSERT_EQ(can_link_listen(path, listen_fd, &err), Status::kOk) << err;
  int c = -1;
  ASSERT_EQ(can_link_connect(path, c, &err), Status::kOk) << err;
  int s = -1;
  ASSERT_EQ(can_link_accept(listen_fd, 1000, s, &err), Status::kOk) << err;
  SocketCanBus client, server;
  ASSERT_EQ(client.adopt_fd(c), Status::kOk);
  ASSERT_EQ(server.adopt_fd(s), Status::kOk);
  CanFrame f;
  f.id = 0x0B0;
  f.len = 8;
  f.data[7] = 0x77;
  ASSERT_EQ(client.send(f), Status::kOk);
  CanFrame got;
  ASSERT_EQ(server.receive(got), Status::kOk);
  EXPECT_EQ(got.data[7], 0x77);
  client.close();
  EXPECT_EQ(server.receive(got), Status::kIoError) << "peer closed";
  EXPECT_EQ(server.state(), CanBusState::kDown);
  EXPECT_EQ(server.send(f), Status::kIoError);
  int none = -1;
  EXPECT_EQ(can_link_accept(listen_fd, 10, none, &err), Status::kEmpty);
  ::close(listen_fd);
  ::unlink(path.c_str());
  EXPECT_EQ(can_link_connect(path, none, &err), Status::kNotFound);
}

}  // namespace
}  // namespace uwbnav::hal
