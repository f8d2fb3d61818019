// Host serial port on the process's stdin/stdout: non-blocking reads and
// writes (O_NONBLOCK while the port exists, restored on destruction). On a
// terminal, raw_terminal() makes it behave as the pty console: the console
// echoes and edits, Ctrl-C reaches it as a byte (drops the line, no signal),
// and Ctrl-D ends the input like end of file on a pipe.
#pragma once

#include <cstddef>
#include <cstdint>

#include <termios.h>

#include "hal/hal.hpp"

namespace uwbnav::hal {

class StdioSerialPort final : public SerialPort {
 public:
  // Sets O_NONBLOCK on in_fd and out_fd (default stdin/stdout).
  explicit StdioSerialPort(int in_fd = 0, int out_fd = 1);
  ~StdioSerialPort() override;
  StdioSerialPort(const StdioSerialPort&) = delete;
  StdioSerialPort& operator=(const StdioSerialPort&) = delete;

  // Pending input bytes; 0 when none (EAGAIN) or at end of input.
  size_t read(uint8_t* buf, size_t cap) override;
  // Bytes the output accepted without blocking; 0 when it is full or closed.
  size_t write(const uint8_t* buf, size_t len) override;

  // True once the input reached end of file (stdin closed / pipe drained), or
  // Ctrl-D (EOT) arrived on a raw terminal.
  bool input_closed() const { return eof_; }
  // Switches a terminal input to raw mode (no line buffering, echo or signal
  // keys) until destruction. False (nothing changed) when the input is not a
  // terminal or its attributes cannot be set.
  bool raw_terminal();
  // True when the input is a terminal (it echoes typed characters itself).
  bool input_is_tty() const;

 private:
  int in_fd_;
  int out_fd_;
  int in_flags_ = -1;   // fcntl flags before construction, restored after
  int out_flags_ = -1;
  bool eof_ = false;
  bool raw_ = false;
  termios saved_tty_{};  // terminal attributes before raw_terminal() (restored when raw_)
};

}  // namespace uwbnav::hal
