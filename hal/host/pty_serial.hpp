// Host serial port on a pseudo-terminal: the firmware holds the master side,
// a person attaches a terminal program (screen, picocom, minicom) to the slave
// device whose name slave_name() returns. Non-blocking; the line discipline is
// raw, so the console does its own echo and line editing as on a UART.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "hal/hal.hpp"

namespace uwbnav::hal {

class PtySerialPort final : public SerialPort {
 public:
  PtySerialPort() = default;
  ~PtySerialPort() override;
  PtySerialPort(const PtySerialPort&) = delete;
  PtySerialPort& operator=(const PtySerialPort&) = delete;

  // posix_openpt + grantpt + unlockpt, raw mode, O_NONBLOCK. `error` gets a
  // one-line reason on failure. With `announce`, prints
  // "console on /dev/pts/N (attach: screen /dev/pts/N)" there once open.
  [[nodiscard]] Status open(std::string* error, std::FILE* announce = nullptr);
  bool is_open() const { return master_fd_ >= 0; }
  // "/dev/pts/N" once open.
  const std::string& slave_name() const { return slave_name_; }

  // Pending bytes typed on the slave side; 0 when none or nobody is attached.
  size_t read(uint8_t* buf, size_t cap) override;
  // Bytes the pty buffer accepted; fewer when the terminal is not reading.
  size_t write(const uint8_t* buf, size_t len) override;

 private:
  int master_fd_ = -1;
  std::string slave_name_;
};

}  // namespace uwbnav::hal
