// AsyncCanLog: the firmware's CAN log leaves the cycle through a bounded queue;
// no file I/O happens in the thread that sends (issue 18: the candump log
// written inside the cycle stalled it for up to 88 ms under disk load).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hal/host/async_can_log.hpp"
#include "hal/host/candump_log.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav::hal {
namespace {

std::vector<std::string> file_lines(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);) lines.push_back(l);
  return lines;
}

CanFrame frame(uint32_t id, uint8_t b) {
  CanFrame f;
  f.id = id;
  f.len = 1;
  f.data[0] = b;
  f.t_us = 1000U * id;
  return f;
}

std::string temp_path(const char* name) {
  return (std::filesystem::temp_directory_path() / name).string();
}

TEST(AsyncCanLog, SendingWritesNothingToTheFileTheWriterLogsEveryFrameInOrder) {
  const std::string path = temp_path("uwbnav_async_can_log.log");
  CandumpLogWriter writer;
  ASSERT_TRUE(ok(writer.open(path, "can0")));
  MemCanBus bus(64, 64, 64);
  {
    AsyncCanLog log(bus, writer, false, 64);
    for (uint32_t i = 1; i <= 20; ++i) ASSERT_TRUE(ok(log.send(frame(i, static_cast<uint8_t>(i)))));
    // Not started: the frames wait in the queue, the sender did no file I/O.
    EXPECT_EQ(writer.lines(), 0U);
    EXPECT_EQ(log.log_counters().high_water, 20U);
    log.start(100);
    log.stop();  // drains
    EXPECT_EQ(log.log_counters().written, 20U);
    EXPECT_EQ(log.log_counters().overflow, 0U);
  }
  ASSERT_TRUE(ok(writer.close()));
  const auto lines = file_lines(path);
  ASSERT_EQ(lines.size(), 20U);
  for (uint32_t i = 1; i <= 20; ++i) {
    CanFrame f;
    std::string ifname;
    ASSERT_TRUE(ok(parse_candump_line(lines[i - 1], f, ifname)));
    EXPECT_EQ(f.id, i);
    EXPECT_EQ(f.data[0], i);
  }
  std::filesystem::remove(path);
}

TEST(AsyncCanLog, AFullQueueDropsFromTheLogOnlyAndCountsIt) {
  const std::string path = temp_path("uwbnav_async_can_log_full.log");
  CandumpLogWriter writer;
  ASSERT_TRUE(ok(writer.open(path, "can0")));
  MemCanBus bus(64, 64, 64);
  AsyncCanLog log(bus, writer, false, 4);
  for (uint32_t i = 1; i <= 10; ++i) EXPECT_TRUE(ok(log.send(frame(i, 0))));  // the bus takes all ten
  EXPECT_EQ(bus.counters().tx_ok, 10U);
  EXPECT_EQ(log.log_counters().overflow, 6U);
  EXPECT_EQ(log.drain(), 4U);
  EXPECT_EQ(log.log_counters().written, 4U);
  EXPECT_TRUE(ok(log.send(frame(11, 0))));  // room again after the drain
  EXPECT_EQ(log.drain(), 1U);
  ASSERT_TRUE(ok(writer.close()));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace uwbnav::hal
