// candump -l log format: exact lines as can-utils writes them, parsing of
// lines other tools write, file round trip, and the logging bus decorator.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "hal/host/candump_log.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::hal {
namespace {

std::string tmp_path(const char* name) { return std::string(UWBNAV_BINARY_DIR) + "/" + name; }

TEST(CandumpFormat, WritesCanUtilsLinesForClassicExtendedFdAndErrorFrames) {
  CanFrame f;
  f.t_us = 1700000000123456ULL;
  f.id = 0x1A3;
  f.len = 4;
  f.data[0] = 0xDE;
  f.data[1] = 0xAD;
  f.data[2] = 0xBE;
  f.data[3] = 0xEF;
  EXPECT_EQ(format_candump_line(f, "can0"), "(1700000000.123456) can0 1A3#DEADBEEF");
  f.t_us = 10000;
  EXPECT_EQ(format_candump_line(f, "vcan1"), "(0000000000.010000) vcan1 1A3#DEADBEEF");
  f.flags = CanFrame::kFlagExtended;
  f.id = 0x18DAF110;
  EXPECT_EQ(format_candump_line(f, "can0"), "(0000000000.010000) can0 18DAF110#DEADBEEF");
  f.flags = CanFrame::kFlagFd | CanFrame::kFlagBrs;
  f.id = 0x123;
  f.len = 12;
  EXPECT_EQ(format_candump_line(f, "can0"), "(0000000000.010000) can0 123##1DEADBEEF0000000000000000");
  CanFrame e;
  e.flags = CanFrame::kFlagError;
  e.id = 0x40;  // CAN_ERR_BUSOFF
  e.len = 8;
  EXPECT_EQ(format_candump_line(e, "can0"), "(0000000000.000000) can0 20000040#0000000000000000");
  CanFrame empty;
  empty.id = 0x7FF;
  EXPECT_EQ(format_candump_line(empty, "can0", 5000000), "(0000000005.000000) can0 7FF#");
}

TEST(CandumpFormat, ParsesLinesFromCandumpPythonCanAndCanplayer) {
  CanFrame f;
  std::string ifname;
  ASSERT_EQ(parse_candump_line("(1436509052.249713) vcan0 044#2A366C2BBA", f, ifname), Status::kOk);
  EXPECT_EQ(ifname, "vcan0");
  EXPECT_EQ(f.t_us, 1436509052249713ULL);
  EXPECT_EQ(f.id, 0x44U);
  EXPECT_EQ(f.len, 5);
  EXPECT_EQ(f.data[4], 0xBA);
  ASSERT_EQ(parse_candump_line("(0.5) can1 12345678#00 R", f, ifname), Status::kOk) << "python-can direction suffix";
  EXPECT_EQ(f.t_us, 500000U);
  EXPECT_EQ(f.flags, CanFrame::kFlagExtended);
  ASSERT_EQ(parse_candump_line("(1.000001) can0 321##0112233", f, ifname), Status::kOk);
  EXPECT_EQ(f.flags, CanFrame::kFlagFd);
  EXPECT_EQ(f.len, 3);
  ASSERT_EQ(parse_candump_line("(1.0) can0 20000004#0004000000000000", f, ifname), Status::kOk);
  EXPECT_EQ(f.flags, CanFrame::kFlagError);
  EXPECT_EQ(f.id, 4U);
  ASSERT_EQ(parse_candump_line("(1.0) can0 123#1122334455667788_9", f, ifname), Status::kOk) << "len8_dlc";
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(parse_candump_line("(1.0) can0 123#R", f, ifname), Status::kUnsupported);
  EXPECT_EQ(parse_candump_line("can0 123#00", f, ifname), Status::kInvalidArgument);
  EXPECT_EQ(parse_candump_line("(1.0) can0 123#0", f, ifname), Status::kInvalidArgument);
  EXPECT_EQ(parse_candump_line("(1.0) can0 800#00", f, ifname), Status::kInvalidArgument);
  EXPECT_EQ(parse_candump_line("(1.0) can0 123#001122334455667788", f, ifname), Status::kInvalidArgument);
}

TEST(CandumpLog, FileRoundTripPreservesEveryFrameAndSkipsJunk) {
  const std::string path = tmp_path("candump_roundtrip.log");
  CandumpLogWriter w;
  ASSERT_EQ(w.open(path, "can0", 1700000000000000ULL), Status::kOk);
  for (int i = 0; i < 100; ++i) {
    CanFrame f;
    f.t_us = static_cast<uint64_t>(i) * 10000 + 7;
    f.id = static_cast<uint32_t>(0x100 + i % 6);
    f.len = static_cast<uint8_t>(i % 9);
    if (i % 10 == 9) {
      f.flags = CanFrame::kFlagFd;
      f.len = 64;
    }
    for (int k = 0; k < f.len; ++k) f.data[k] = static_cast<uint8_t>(i * 31 + k);
    ASSERT_EQ(w.write(f), Status::kOk);
  }
  ASSERT_EQ(w.close(), Status::kOk);
  {
    std::ofstream app(path, std::ios::app);
    app << "garbage line\n\n";
  }
  CandumpLogReader r;
  ASSERT_EQ(r.open(path), Status::kOk);
  CanFrame f;
  std::string ifname;
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(r.next(f, &ifname), Status::kOk) << i;
    EXPECT_EQ(ifname, "can0");
    EXPECT_EQ(f.t_us, 1700000000000000ULL + static_cast<uint64_t>(i) * 10000 + 7);
    EXPECT_EQ(f.id, static_cast<uint32_t>(0x100 + i % 6));
    const uint8_t len = i % 10 == 9 ? 64 : static_cast<uint8_t>(i % 9);
    ASSERT_EQ(f.len, len);
    for (int k = 0; k < f.len; ++k) EXPECT_EQ(f.data[k], static_cast<uint8_t>(i * 31 + k));
  }
  EXPECT_EQ(r.next(f), Status::kEmpty);
  EXPECT_EQ(r.skipped(), 1U);
  std::remove(path.c_str());
}

TEST(CanLogTee, LogsOnlyFramesTheBusAcceptedAndOptionallyReceived) {
  const std::string path = tmp_path("candump_tee.log");
  CandumpLogWriter w;
  ASSERT_EQ(w.open(path), Status::kOk);
  MemCanBus bus(1, 4);
  bus.set_auto_flush(false);
  CanLogTee tee(bus, w, true);
  CanFrame f;
  f.id = 0x101;
  f.len = 1;
  EXPECT_EQ(tee.send(f), Status::kOk);
  EXPECT_EQ(tee.send(f), Status::kWouldBlock);
  f.id = 0x0A0;
  bus.inject(f);
  CanFrame in;
  EXPECT_EQ(tee.receive(in), Status::kOk);
  EXPECT_EQ(tee.counters().tx_dropped, 1U);
  EXPECT_EQ(w.lines(), 2U);
  ASSERT_EQ(w.close(), Status::kOk);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace uwbnav::hal
