// Arm semihosting calls (Arm "Semihosting for AArch32 and AArch64", v2.0):
// operation number in r0, parameter in r1, BKPT 0xAB in Thumb state.
#include "hal/mps2/semihost.hpp"

namespace uwbnav::mps2 {
namespace {

constexpr uint32_t kSysWrite0 = 0x04;
constexpr uint32_t kSysExitExtended = 0x20;
constexpr uint32_t kAdpStoppedApplicationExit = 0x20026;

uint32_t semihost_call(uint32_t op, const void* arg) {
  register uint32_t r0 __asm__("r0") = op;
  register const void* r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace

void semihost_write0(const char* text) { static_cast<void>(semihost_call(kSysWrite0, text)); }

void semihost_exit(uint32_t code) {
  const uint32_t block[2] = {kAdpStoppedApplicationExit, code};
  static_cast<void>(semihost_call(kSysExitExtended, block));
  for (;;) {
    __asm__ volatile("wfi");
  }
}

}  // namespace uwbnav::mps2
