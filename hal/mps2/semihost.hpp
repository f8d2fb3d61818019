// Arm semihosting on the MPS2 board (qemu-system-arm -semihosting-config
// enable=on,target=native): console text and the exit code, without stdio.
// Each call is a BKPT 0xAB trap that the debugger/emulator services.
#pragma once

#include <cstdint>

namespace uwbnav::mps2 {

// Writes a NUL-terminated string to the host console (SYS_WRITE0).
void semihost_write0(const char* text);

// Ends the program with `code` as the emulator's exit status
// (SYS_EXIT_EXTENDED, reason ADP_Stopped_ApplicationExit). Never returns.
[[noreturn]] void semihost_exit(uint32_t code);

}  // namespace uwbnav::mps2
