// Host stdin/stdout serial port (see stdio_serial.hpp).
#include "hal/host/stdio_serial.hpp"

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace uwbnav::hal {
namespace {

int set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL);
  if (flags >= 0) (void)fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  return flags;
}

}  // namespace

StdioSerialPort::StdioSerialPort(int in_fd, int out_fd) : in_fd_(in_fd), out_fd_(out_fd) {
  in_flags_ = set_nonblocking(in_fd_);
  out_flags_ = set_nonblocking(out_fd_);
}

StdioSerialPort::~StdioSerialPort() {
  if (raw_) (void)tcsetattr(in_fd_, TCSANOW, &saved_tty_);
  // stdin and stdout may share one open file description: restore output first,
  // input last, so the input's original flags win when they are the same.
  if (out_flags_ >= 0) (void)fcntl(out_fd_, F_SETFL, out_flags_);
  if (in_flags_ >= 0) (void)fcntl(in_fd_, F_SETFL, in_flags_);
}

bool StdioSerialPort::raw_terminal() {
  termios t{};
  if (raw_ || isatty(in_fd_) != 1 || tcgetattr(in_fd_, &t) != 0) return false;
  termios raw = t;
  raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO | ISIG | IEXTEN);
  raw.c_iflag &= ~static_cast<tcflag_t>(IXON | ICRNL);
  raw.c_cc[VMIN] = 0;
  raw.c_cc[VTIME] = 0;
  if (tcsetattr(in_fd_, TCSANOW, &raw) != 0) return false;
  saved_tty_ = t;
  raw_ = true;
  return true;
}

size_t StdioSerialPort::read(uint8_t* buf, size_t cap) {
  if (eof_ || cap == 0) return 0;
  for (;;) {
    const ssize_t n = ::read(in_fd_, buf, cap);
    if (n > 0 && raw_) {
      const void* eot = std::memchr(buf, 0x04, static_cast<size_t>(n));  // Ctrl-D: end of input
      if (eot == nullptr) return static_cast<size_t>(n);
      eof_ = true;
      return static_cast<size_t>(static_cast<const uint8_t*>(eot) - buf);
    }
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0) {
      eof_ = true;
      return 0;
    }
    if (errno == EINTR) continue;
    return 0;  // EAGAIN: nothing pending; other errors: treated as no input
  }
}

size_t StdioSerialPort::write(const uint8_t* buf, size_t len) {
  size_t done = 0;
  while (done < len) {
    const ssize_t n = ::write(out_fd_, buf + done, len - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN (reader slow), EPIPE or closed: the caller keeps or drops the rest
  }
  return done;
}

bool StdioSerialPort::input_is_tty() const { return isatty(in_fd_) == 1; }

}  // namespace uwbnav::hal
