// End to end over a pseudo-terminal, as a person at a terminal would: the
// firmware loop runs in its own thread on a simulated replay board whose serial
// port is a PtySerialPort; the test opens the slave device, types commands a
// character at a time and reads the screen, including `param set` changing
// what the firmware does. Also the host serial ports' non-blocking contracts.
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <string>
#include <thread>

#include "console_rig.hpp"
#include "hal/host/pty_serial.hpp"
#include "hal/host/stdio_serial.hpp"

namespace uwbnav {
namespace {

using namespace std::chrono_literals;
using testing::kv;
using testing::kv_num;
using testing::lines_with_prefix;
using testing::split_lines;

// The firmware: App on a replay board, 10 ms cycles run 10x faster than real time.
class FirmwareThread {
 public:
  FirmwareThread(const dataset::Recording& rec, hal::PtySerialPort& port, hal::ParamStore& store)
      : sources_(rec), board_{sources_.imu, sources_.uwb, can_, port, clock_, store, rec.site}, app_(board_) {
    init_ok_ = ok(app_.init());
    t_us_ = testing::first_cycle_us(rec);
    thread_ = std::thread([this] { loop(); });
  }
  ~FirmwareThread() {
    stop_ = true;
    thread_.join();
  }
  bool init_ok() const { return init_ok_; }

 private:
  void loop() {
    while (!stop_) {
      clock_.sleep_until_us(t_us_);
      const auto w0 = std::chrono::steady_clock::now();
      app_.tick(t_us_);
      const auto work_us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - w0);
      app_.record_cycle_timing(static_cast<uint32_t>(work_us.count()), 0, work_us.count() > kCyclePeriodUs);
      hal::CanFrame f;
      while (ok(can_.receive_sent(f))) {
      }
      t_us_ += kCyclePeriodUs;
      std::this_thread::sleep_for(1ms);
    }
  }

  hal::ReplaySources sources_;
  hal::MemCanBus can_;
  hal::LockstepClock clock_;
  hal::Board board_;
  App app_;
  uint64_t t_us_ = 0;
  bool init_ok_ = false;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A person at a terminal on the pty's slave side.
class Terminal {
 public:
  explicit Terminal(const std::string& device) {
    fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY);
    if (fd_ >= 0) {
      termios tio{};
      tcgetattr(fd_, &tio);
      cfmakeraw(&tio);  // what screen/picocom do
      tcsetattr(fd_, TCSANOW, &tio);
    }
  }
  ~Terminal() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool is_open() const { return fd_ >= 0; }

  // Types text one key at a time, then Enter.
  void type_line(const std::string& text) {
    for (char c : text) {
      ASSERT_EQ(::write(fd_, &c, 1), 1);
      std::this_thread::sleep_for(200us);
    }
    const char cr = '\r';
    ASSERT_EQ(::write(fd_, &cr, 1), 1);
  }
  // Reads the screen until `needle` appears after `from` (or the timeout).
  // Returns the screen text from `from` on.
  std::string wait_for(const std::string& needle, size_t from, std::chrono::milliseconds timeout = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (screen_.find(needle, from) == std::string::npos && std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) > 0) {
        char buf[512];
        const ssize_t n = ::read(fd_, buf, sizeof buf);
        if (n > 0) screen_.append(buf, static_cast<size_t>(n));
      }
    }
    return screen_.substr(from);
  }
  // Types a command and returns its reply lines (echo and prompt removed).
  std::vector<std::string> run(const std::string& command) {
    const size_t from = screen_.size();
    type_line(command);
    const std::string out = wait_for("\r\n> ", from);
    std::vector<std::string> lines = split_lines(out);
    if (!lines.empty()) lines.erase(lines.begin());
    return lines;
  }
  const std::string& screen() const { return screen_; }

 private:
  int fd_ = -1;
  std::string screen_;
};

std::string find_line(const std::vector<std::string>& lines, const std::string& prefix) {
  const auto found = lines_with_prefix(lines, prefix);
  return found.empty() ? std::string() : found.front();
}

TEST(ConsolePty, PersonAtATerminalQueriesTheFirmwareAndChangesLiveBehaviourWithParamSet) {
  const dataset::Recording& rec = testing::sim_recording(11);
  hal::PtySerialPort port;
  std::string err;
  std::FILE* announce = std::tmpfile();
  ASSERT_NE(announce, nullptr);
  ASSERT_TRUE(ok(port.open(&err, announce))) << err;
  ASSERT_EQ(port.slave_name().rfind("/dev/pts/", 0), 0U) << port.slave_name();
  char printed[256] = {};
  std::rewind(announce);
  ASSERT_NE(std::fgets(printed, sizeof printed, announce), nullptr);
  std::fclose(announce);
  EXPECT_EQ(std::string(printed), "console on " + port.slave_name() + " (attach: screen " + port.slave_name() + ")\n");
  const std::string store_path = (std::filesystem::temp_directory_path() / "uwbnav_console_pty_params.bin").string();
  std::filesystem::remove(store_path);
  hal::FileParamStore store(store_path);

  Terminal term(port.slave_name());
  ASSERT_TRUE(term.is_open());
  FirmwareThread fw(rec, port, store);
  ASSERT_TRUE(fw.init_ok());

  // GIVEN the banner and a prompt on the screen
  term.wait_for("(type help)\r\n> ", 0);
  ASSERT_NE(term.screen().find("console ready fw="), std::string::npos) << term.screen();

  // WHEN the person asks the basics THEN each answer is there, tagged and parsable
  EXPECT_FALSE(find_line(term.run("version"), "version fw=").empty());
  EXPECT_GE(lines_with_prefix(term.run("help"), "help ").size(), 12U);
  std::this_thread::sleep_for(300ms);  // let the vehicle drive a few seconds
  const std::string status = find_line(term.run("status"), "status ");
  ASSERT_FALSE(status.empty()) << term.screen();
  EXPECT_FALSE(kv(status, "mode").empty());
  EXPECT_LE(kv_num(status, "imu_age_ms"), 50.0);
  EXPECT_EQ(lines_with_prefix(term.run("anchors"), "anchors id=").size(), rec.site.num_anchors);
  EXPECT_EQ(lines_with_prefix(term.run("ekf -v"), "ekf cov row=").size(), 15U);

  // Typing mistakes corrected with backspace still run the intended command.
  EXPECT_FALSE(find_line(term.run("statx\x7fus"), "status ").empty());
  // Binary garbage and nonsense get one error line each.
  EXPECT_EQ(find_line(term.run("\x01\x02\xff"), "error: "), "error: non-printable input (3 bytes), line ignored");
  EXPECT_EQ(find_line(term.run("launch"), "error: "), "error: unknown command 'launch' (try help)");

  // WHEN uwb.max_range is set below every possible range
  auto stats_uwb = [&] { return find_line(term.run("stats"), "stats src=uwb "); };
  EXPECT_EQ(find_line(term.run("param set uwb.max_range 1"), "param "), "param name=uwb.max_range value=1 old=500");
  const std::string s1 = stats_uwb();
  // Poll (as a person would look again) until the firmware thread has run on;
  // a loaded machine slows it down, so no fixed sleep decides the outcome.
  auto poll_until = [&](const std::function<bool(const std::string&)>& done) {
    std::string line = stats_uwb();
    for (auto deadline = std::chrono::steady_clock::now() + 20s; !done(line) && std::chrono::steady_clock::now() < deadline;) {
      std::this_thread::sleep_for(100ms);
      line = stats_uwb();
    }
    return line;
  };
  const std::string s2 =
      poll_until([&](const std::string& l) { return kv_num(l, "out_of_range") > kv_num(s1, "out_of_range") + 20.0; });
  // THEN ranges are rejected as out of range and none is accepted any more
  ASSERT_FALSE(s1.empty());
  ASSERT_FALSE(s2.empty());
  EXPECT_EQ(kv(s2, "accepted"), kv(s1, "accepted")) << s1 << "\n" << s2;
  EXPECT_GT(kv_num(s2, "out_of_range"), kv_num(s1, "out_of_range") + 20.0);

  // An out-of-range value is refused and the live value stays
  EXPECT_EQ(find_line(term.run("param set uwb.max_range 99999"), "error: "),
            "error: param: uwb.max_range=99999 out of range [1, 2000]; unchanged");
  EXPECT_EQ(kv(find_line(term.run("param get uwb.max_range"), "param "), "value"), "1");

  // WHEN the parameter is reset THEN ranges flow again
  EXPECT_EQ(find_line(term.run("param reset uwb.max_range"), "param "), "param name=uwb.max_range value=500 old=1");
  const std::string s3 = stats_uwb();
  const std::string s4 = poll_until([&](const std::string& l) { return kv_num(l, "accepted") > kv_num(s3, "accepted") + 20.0; });
  EXPECT_GT(kv_num(s4, "accepted"), kv_num(s3, "accepted") + 20.0) << s3 << "\n" << s4;

  // Saving goes to the board's parameter store (a file on the host)
  EXPECT_EQ(find_line(term.run("param save"), "param "), "param saved=ok count=" + std::to_string(kNumParams));
  EXPECT_TRUE(std::filesystem::exists(store_path));

  // A machine-readable stream, then quiet again
  (void)term.run("stream pos 20");
  const size_t mark = term.screen().size();
  const std::string streamed = term.wait_for("$pos ", mark);
  EXPECT_NE(streamed.find("$pos t_us="), std::string::npos);
  // While lines stream, the console redraws its prompt after each one, so the
  // reply to "stream off" may come after a prompt: wait for the reply itself.
  const size_t off_mark = term.screen().size();
  (void)term.run("stream off");
  EXPECT_NE(term.wait_for("stream pos_hz=0", off_mark).find("\nstream pos_hz=0"), std::string::npos);

  // Keep the session for docs/console.md and for debugging failures.
  std::ofstream(std::string(UWBNAV_BINARY_DIR) + "/console_pty_session.txt", std::ios::binary) << term.screen();
  std::filesystem::remove(store_path);
}

TEST(HostSerial, PtyReadsNothingWithoutAnAttachedTerminalAndNeverBlocksOnWrite) {
  hal::PtySerialPort port;
  std::string err;
  ASSERT_TRUE(ok(port.open(&err))) << err;
  uint8_t buf[64];
  EXPECT_EQ(port.read(buf, sizeof buf), 0U);
  // Nobody reads the slave: the pty buffer fills and write() accepts less, without blocking.
  const std::string chunk(4096, 'x');
  size_t accepted = 0;
  size_t last = 1;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 1000 && last > 0; ++i) {
    last = port.write(reinterpret_cast<const uint8_t*>(chunk.data()), chunk.size());
    accepted += last;
  }
  EXPECT_EQ(last, 0U);
  EXPECT_GT(accepted, 0U);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
}

TEST(HostSerial, StdioPortIsNonBlockingOnPipesAndRestoresTheFlags) {
  int in[2];
  int out[2];
  ASSERT_EQ(pipe(in), 0);
  ASSERT_EQ(pipe(out), 0);
  const int flags_before = fcntl(in[0], F_GETFL);
  {
    hal::StdioSerialPort port(in[0], out[1]);
    uint8_t buf[64];
    EXPECT_EQ(port.read(buf, sizeof buf), 0U);  // nothing typed: returns at once
    ASSERT_EQ(::write(in[1], "help\r", 5), 5);
    EXPECT_EQ(port.read(buf, sizeof buf), 5U);
    EXPECT_EQ(std::string(reinterpret_cast<char*>(buf), 5), "help\r");
    // Output pipe nobody reads: write() accepts what fits and then 0, never blocks.
    const std::string chunk(65536, 'y');
    size_t total = 0;
    size_t n = 1;
    for (int i = 0; i < 100 && n > 0; ++i) {
      n = port.write(reinterpret_cast<const uint8_t*>(chunk.data()), chunk.size());
      total += n;
    }
    EXPECT_EQ(n, 0U);
    EXPECT_GT(total, 0U);
    ::close(in[1]);
    EXPECT_EQ(port.read(buf, sizeof buf), 0U);
    EXPECT_TRUE(port.input_closed());
  }
  EXPECT_EQ(fcntl(in[0], F_GETFL), flags_before);
  ::close(in[0]);
  ::close(out[0]);
  ::close(out[1]);
}

// stdio console on a terminal (`uwbnav firmware --console stdio`): in raw mode
// Ctrl-C reaches the console as a byte (its line editor drops the line, as over
// the pty) instead of killing the process, Ctrl-D ends the input like end of
// file on a pipe, and the terminal's attributes come back afterwards.
TEST(HostSerial, StdioPortOnARawTerminalPassesCtrlCAndEndsTheInputAtCtrlD) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const int slave = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(slave, 0);
  termios before{};
  ASSERT_EQ(::tcgetattr(slave, &before), 0);
  ASSERT_NE(before.c_lflag & ISIG, 0U);  // a fresh terminal: Ctrl-C would be SIGINT
  auto read_n = [](hal::StdioSerialPort& port, int fd, size_t n) {
    std::string got;
    uint8_t buf[64];
    for (int i = 0; i < 100 && got.size() < n && !port.input_closed(); ++i) {
      pollfd p{fd, POLLIN, 0};
      (void)::poll(&p, 1, 100);  // waits for the bytes, not for time: no timing asserted
      const size_t k = port.read(buf, sizeof buf);
      got.append(reinterpret_cast<const char*>(buf), k);
    }
    return got;
  };
  {
    hal::StdioSerialPort port(slave, slave);
    ASSERT_TRUE(port.raw_terminal());
    termios raw{};
    ASSERT_EQ(::tcgetattr(slave, &raw), 0);
    EXPECT_EQ(raw.c_lflag & (ISIG | ICANON | ECHO), 0U);
    ASSERT_EQ(::write(master, "abc\x03", 4), 4);
    EXPECT_EQ(read_n(port, slave, 4), std::string("abc\x03"));
    EXPECT_FALSE(port.input_closed());
    ASSERT_EQ(::write(master, "xy\x04zz", 5), 5);
    EXPECT_EQ(read_n(port, slave, 5), "xy");
    EXPECT_TRUE(port.input_closed());
    uint8_t buf[8];
    EXPECT_EQ(port.read(buf, sizeof buf), 0U);
  }
  termios after{};
  ASSERT_EQ(::tcgetattr(slave, &after), 0);
  EXPECT_EQ(after.c_lflag, before.c_lflag);
  EXPECT_EQ(after.c_iflag, before.c_iflag);
  ::close(slave);
  ::close(master);
}

TEST(HostSerial, StdioPortLeavesAPipeAloneWhenAskedForARawTerminal) {
  int in[2];
  ASSERT_EQ(::pipe(in), 0);
  {
    hal::StdioSerialPort port(in[0], 1);
    EXPECT_FALSE(port.raw_terminal());
  }
  ::close(in[0]);
  ::close(in[1]);
}

}  // namespace
}  // namespace uwbnav
