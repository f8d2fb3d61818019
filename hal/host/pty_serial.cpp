// Host pseudo-terminal serial port (see pty_serial.hpp).
#include "hal/host/pty_serial.hpp"

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace uwbnav::hal {

PtySerialPort::~PtySerialPort() {
  if (master_fd_ >= 0) ::close(master_fd_);
}

Status PtySerialPort::open(std::string* error, std::FILE* announce) {
  auto fail = [&](const char* what) {
    if (error != nullptr) *error = std::string(what) + ": " + std::strerror(errno);
    if (master_fd_ >= 0) ::close(master_fd_);
    master_fd_ = -1;
    return Status::kIoError;
  };
  if (master_fd_ >= 0) return Status::kOk;
  master_fd_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (master_fd_ < 0) return fail("posix_openpt");
  if (grantpt(master_fd_) != 0) return fail("grantpt");
  if (unlockpt(master_fd_) != 0) return fail("unlockpt");
  char name[128];
  if (ptsname_r(master_fd_, name, sizeof name) != 0) return fail("ptsname_r");
  // Raw line discipline (applies to the slave side): no echo by the kernel, no
  // line buffering, no CR/LF translation; the console behaves as on a UART.
  termios tio{};
  if (tcgetattr(master_fd_, &tio) != 0) return fail("tcgetattr");
  cfmakeraw(&tio);
  if (tcsetattr(master_fd_, TCSANOW, &tio) != 0) return fail("tcsetattr");
  slave_name_ = name;
  if (announce != nullptr) {
    std::fprintf(announce, "console on %s (attach: screen %s)\n", name, name);
    std::fflush(announce);
  }
  return Status::kOk;
}

size_t PtySerialPort::read(uint8_t* buf, size_t cap) {
  if (master_fd_ < 0 || cap == 0) return 0;
  for (;;) {
    const ssize_t n = ::read(master_fd_, buf, cap);
    if (n > 0) return static_cast<size_t>(n);
    if (n < 0 && errno == EINTR) continue;
    return 0;  // EAGAIN: nothing typed; EIO: no terminal attached (yet or any more)
  }
}

size_t PtySerialPort::write(const uint8_t* buf, size_t len) {
  if (master_fd_ < 0) return 0;
  size_t done = 0;
  while (done < len) {
    const ssize_t n = ::write(master_fd_, buf + done, len - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN: the terminal is not reading; EIO: nobody attached
  }
  return done;
}

}  // namespace uwbnav::hal
