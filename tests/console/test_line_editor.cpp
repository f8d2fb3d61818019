// Console line discipline and logger: line ends, editing, bad lines, history,
// cursor-key recall; log levels, rate limit, single-line output.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "firmware/console/byte_ring.hpp"
#include "firmware/console/line_editor.hpp"
#include "firmware/console/log.hpp"

namespace uwbnav {
namespace {

struct Fed {
  std::vector<LineEditor::Event> events;
  std::vector<std::string> lines;
  std::string echo;
};

Fed feed(LineEditor& ed, const std::string& bytes) {
  Fed f;
  for (char c : bytes) {
    const LineEditor::Event e = ed.feed(static_cast<uint8_t>(c));
    f.echo.append(ed.echo(), ed.echo_len());
    if (e != LineEditor::Event::kNone) f.events.push_back(e);
    if (e == LineEditor::Event::kLine) f.lines.emplace_back(ed.line(), ed.line_len());
  }
  return f;
}

TEST(LineEditor, CrLfAndCrlfEachEndExactlyOneLine) {
  LineEditor ed;
  const Fed f = feed(ed, "a\rb\nc\r\nd\n\r");
  ASSERT_EQ(f.lines.size(), 5U);  // "\n\r" is two line ends: the second line is empty
  EXPECT_EQ(f.lines[0], "a");
  EXPECT_EQ(f.lines[1], "b");
  EXPECT_EQ(f.lines[2], "c");
  EXPECT_EQ(f.lines[3], "d");
  EXPECT_EQ(f.lines[4], "");
}

TEST(LineEditor, BackspaceAndDeleteEditTheLineAndEchoTheErase) {
  LineEditor ed;
  const Fed f = feed(ed, "statx\x7fus\b\bus\r");
  ASSERT_EQ(f.lines.size(), 1U);
  EXPECT_EQ(f.lines[0], "status");
  EXPECT_NE(f.echo.find("\b \b"), std::string::npos);
  EXPECT_EQ(f.echo.substr(f.echo.size() - 2), "\r\n");
}

TEST(LineEditor, OverlongLineIsReportedOnceAtItsEndAndDiscarded) {
  LineEditor ed;
  const std::string longline(LineEditor::kMaxChars + 50, 'x');
  const Fed f = feed(ed, longline + "\rhelp\r");
  ASSERT_EQ(f.events.size(), 2U);
  EXPECT_EQ(f.events[0], LineEditor::Event::kOverlong);
  EXPECT_EQ(f.events[1], LineEditor::Event::kLine);
  EXPECT_EQ(ed.line(), std::string("help"));
  // A line of exactly kMaxChars is still accepted.
  const Fed g = feed(ed, std::string(LineEditor::kMaxChars, 'y') + "\r");
  ASSERT_EQ(g.lines.size(), 1U);
  EXPECT_EQ(g.lines[0].size(), LineEditor::kMaxChars);
}

TEST(LineEditor, NonPrintableBytesDiscardTheLineAndAreCounted) {
  LineEditor ed;
  const Fed f = feed(ed, std::string("par\x01\x02\xff\xfe" "am\r", 10));
  ASSERT_EQ(f.events.size(), 1U);
  EXPECT_EQ(f.events[0], LineEditor::Event::kGarbage);
  EXPECT_EQ(ed.garbage_count(), 4U);
  // Non-printable bytes are never echoed.
  for (char c : f.echo) EXPECT_TRUE(c == '\r' || c == '\n' || (c >= 0x20 && c < 0x7f)) << int(c);
}

TEST(LineEditor, BinaryStreamWithoutLineEndsIsOneOverlongLine) {
  LineEditor ed;
  std::string bin;
  for (int i = 0; i < 5000; ++i) bin.push_back(static_cast<char>(0x80 + (i % 100)));
  const Fed f = feed(ed, bin + "\n");
  ASSERT_EQ(f.events.size(), 1U);
  EXPECT_EQ(f.events[0], LineEditor::Event::kOverlong);
  EXPECT_EQ(ed.overlong_count(), 5000U);
}

TEST(LineEditor, CtrlCCancelsTheLine) {
  LineEditor ed;
  const Fed f = feed(ed, "param set x 1\x03" "help\r");
  ASSERT_EQ(f.events.size(), 2U);
  EXPECT_EQ(f.events[0], LineEditor::Event::kCancel);
  EXPECT_EQ(f.lines.at(0), "help");
  EXPECT_NE(f.echo.find("^C"), std::string::npos);
}

TEST(LineEditor, HistoryKeepsTheLastEntriesNumberedAndSkipsRepeats) {
  LineEditor ed;
  for (int i = 1; i <= 10; ++i) ed.history_add(("cmd" + std::to_string(i)).c_str());
  ed.history_add("cmd10");  // consecutive duplicate: not stored
  EXPECT_EQ(ed.history_newest(), 10U);
  EXPECT_EQ(ed.history_oldest(), 10U - LineEditor::kHistoryDepth + 1);
  EXPECT_EQ(ed.history_find(1), nullptr);
  EXPECT_STREQ(ed.history_find(10), "cmd10");
  EXPECT_STREQ(ed.history_find(3), "cmd3");
  EXPECT_EQ(ed.history_find(11), nullptr);
}

TEST(LineEditor, CursorUpRecallsOlderEntriesAndDownReturns) {
  LineEditor ed;
  ed.history_add("status");
  ed.history_add("stats");
  const Fed f = feed(ed, "\x1b[A\x1b[A\x1b[B\r");
  ASSERT_EQ(f.lines.size(), 1U);
  EXPECT_EQ(f.lines[0], "stats");
  EXPECT_NE(f.echo.find("\r\x1b[K> status"), std::string::npos);
  // Unknown escape sequences (cursor left, F-keys) are swallowed, not garbage.
  const Fed g = feed(ed, "he\x1b[D\x1b[15~lp\r");
  ASSERT_EQ(g.lines.size(), 1U);
  EXPECT_EQ(g.lines[0], "help");
}

TEST(ByteRing, PushIsAllOrNothingAndWrapsAround) {
  ByteRing<8> r;
  EXPECT_TRUE(r.push("abcdef", 6));
  EXPECT_FALSE(r.push("xyz", 3));
  EXPECT_EQ(r.size(), 6U);
  r.consume(4);
  EXPECT_TRUE(r.push("ghijk", 5));  // wraps
  std::string got;
  while (!r.empty()) {
    size_t n = 0;
    const uint8_t* p = r.peek(&n);
    got.append(reinterpret_cast<const char*>(p), n);
    r.consume(n);
  }
  EXPECT_EQ(got, "efghijk");
}

class CaptureSink final : public LogSink {
 public:
  std::vector<std::string> lines;
  void log_line(LogLevel, const char* text, size_t len) override { lines.emplace_back(text, len); }
};

// Restores the global logger after each test.
class LoggerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    saved_sink_ = logger().sink();
    logger().set_sink(&sink_);
    logger().set_level(LogLevel::kInfo);
    logger().set_rate_per_s(5);
    logger().set_time_us(1000000);
    logger().reset_counters();
  }
  void TearDown() override { logger().set_sink(saved_sink_); }
  CaptureSink sink_;
  LogSink* saved_sink_ = nullptr;
};

TEST_F(LoggerTest, LevelThresholdFiltersAndLinesCarryModuleLevelAndTime) {
  UWBNAV_LOG_INFO("can", "bus %s count=%d", "off", 3);
  UWBNAV_LOG_DEBUG("can", "not shown");
  ASSERT_EQ(sink_.lines.size(), 1U);
  EXPECT_EQ(sink_.lines[0], "log t_us=1000000 level=info mod=can msg=bus off count=3");
  EXPECT_EQ(logger().counters().filtered, 1U);
  logger().set_level(LogLevel::kDebug);
  UWBNAV_LOG_DEBUG("ekf", "now shown");
  EXPECT_EQ(sink_.lines.size(), 2U);
}

void spam(int i) { UWBNAV_LOG_WARN("uwb", "spam %d", i); }

TEST_F(LoggerTest, RateLimitPerCallSiteCountsSuppressedAndReportsThemLater) {
  for (int i = 0; i < 100; ++i) spam(i);
  EXPECT_EQ(sink_.lines.size(), 5U);
  EXPECT_EQ(logger().counters().suppressed, 95U);
  // Another call site has its own budget.
  UWBNAV_LOG_WARN("uwb", "other site");
  EXPECT_EQ(sink_.lines.size(), 6U);
  // After the one-second window the site speaks again and says how many were lost.
  logger().set_time_us(2000001);
  spam(100);
  spam(101);
  ASSERT_EQ(sink_.lines.size(), 8U);
  EXPECT_NE(sink_.lines[6].find("(suppressed "), std::string::npos);
  EXPECT_EQ(sink_.lines[7].find("(suppressed "), std::string::npos);
}

TEST_F(LoggerTest, MessagesStayOneLineAndLongOnesAreTruncated) {
  UWBNAV_LOG_ERROR("x", "two\r\nlines");
  const std::string big(1000, 'z');
  UWBNAV_LOG_ERROR("y", "%s", big.c_str());
  ASSERT_EQ(sink_.lines.size(), 2U);
  EXPECT_EQ(sink_.lines[0].find('\n'), std::string::npos);
  EXPECT_EQ(sink_.lines[0].find('\r'), std::string::npos);
  EXPECT_LT(sink_.lines[1].size(), Logger::kLineMax);
}

TEST(LogLevelParse, AcceptsNamesAndDigitsOnly) {
  LogLevel l = LogLevel::kError;
  EXPECT_TRUE(parse_log_level("debug", &l));
  EXPECT_EQ(l, LogLevel::kDebug);
  EXPECT_TRUE(parse_log_level("1", &l));
  EXPECT_EQ(l, LogLevel::kWarn);
  EXPECT_FALSE(parse_log_level("verbose", &l));
  EXPECT_FALSE(parse_log_level("4", &l));
}

}  // namespace
}  // namespace uwbnav
