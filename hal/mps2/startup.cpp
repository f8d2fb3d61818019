// Cortex-M reset and exception entry for the MPS2-AN386 image: vector table,
// FPU enable, .data/.bss/TLS initialisation, stack painting (for the measured
// high-water mark), static constructors, main(); faults report over
// semihosting and end the run with exit code 3.
#include <cstddef>
#include <cstdint>

#include "hal/mps2/board.hpp"
#include "hal/mps2/semihost.hpp"

// Linker script symbols (hal/mps2/mps2_an386.ld).
extern "C" {
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern const uint32_t __data_source[];
extern uint32_t __tdata_start[];
extern uint32_t __tdata_end[];
extern const uint32_t __tdata_source[];
extern uint32_t __tbss_start[];
extern uint32_t __tbss_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_bottom[];
extern uint32_t __stack_top[];
extern uint32_t __tls_base[];
using InitFn = void (*)();
extern const InitFn __init_array_start[];
extern const InitFn __init_array_end[];

void _set_tls(void* tls);  // picolibc: thread pointer for __aeabi_read_tp
int main();
[[noreturn]] void Reset_Handler();
[[noreturn]] void Fault_Handler();
[[noreturn]] void Fault_Report();
[[noreturn]] void Unexpected_Handler();
// The profile build (hal/mps2/profile.cpp) provides its own.
[[noreturn]] void SysTick_Handler() __attribute__((weak, alias("Unexpected_Handler")));

// Static objects are never destroyed (the firmware never returns from main):
// destructor registration (Arm EABI __aeabi_atexit) is accepted and dropped,
// so no atexit list exists.
void* __dso_handle = nullptr;
int __aeabi_atexit(void*, void (*)(void*), void*) { return 0; }
}

// Virtual destructors make every vtable reference the deleting destructor and
// with it operator delete, although nothing is ever allocated. These
// definitions satisfy the reference without libstdc++'s heap-backed ones; a
// call would be a bug and ends the run (exit code 4).
void operator delete(void*) noexcept {
  uwbnav::mps2::semihost_write0("mps2: operator delete called (no heap in the image)\n");
  uwbnav::mps2::semihost_exit(4);
}
void operator delete(void* p, std::size_t) noexcept { operator delete(p); }

namespace {

using Handler = void (*)();

// Cortex-M vector table: initial SP, then the 15 system exceptions. The board
// uses no interrupts, so the external IRQ entries are left out.
struct VectorTable {
  uint32_t* initial_sp;
  Handler handlers[15];
};

__attribute__((section(".vectors"), used)) const VectorTable kVectors = {
    __stack_top,
    {
        Reset_Handler,       // Reset
        Fault_Handler,       // NMI
        Fault_Handler,       // HardFault
        Fault_Handler,       // MemManage
        Fault_Handler,       // BusFault
        Fault_Handler,       // UsageFault
        nullptr, nullptr, nullptr, nullptr,
        Unexpected_Handler,  // SVCall
        Unexpected_Handler,  // DebugMonitor
        nullptr,
        Unexpected_Handler,  // PendSV
        SysTick_Handler,     // SysTick: counter runs without its interrupt, except in the profile build
    },
};

volatile uint32_t* const kCpacr = reinterpret_cast<volatile uint32_t*>(0xE000ED88U);

}  // namespace

extern "C" void Reset_Handler() {
  // CP10/CP11 full access before any floating-point instruction runs.
  *kCpacr = *kCpacr | (0xFU << 20);
  __asm__ volatile("dsb\n\tisb" ::: "memory");

  const uint32_t* src = __data_source;
  for (uint32_t* dst = __data_start; dst < __data_end;) *dst++ = *src++;
  src = __tdata_source;
  for (uint32_t* dst = __tdata_start; dst < __tdata_end;) *dst++ = *src++;
  for (uint32_t* dst = __tbss_start; dst < __tbss_end;) *dst++ = 0U;
  for (uint32_t* dst = __bss_start; dst < __bss_end;) *dst++ = 0U;
  _set_tls(__tls_base);

  // Paint the unused stack below the current frame (64-byte margin).
  uint32_t* sp = nullptr;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (uint32_t* p = __stack_bottom; p < sp - 16; ++p) *p = uwbnav::mps2::kStackPaint;

  for (const InitFn* f = __init_array_start; f < __init_array_end; ++f) (*f)();

  uwbnav::mps2::semihost_exit(static_cast<uint32_t>(main()));
}

// A fault may come from a stack overflow (SP below RAM): report on a fresh stack.
extern "C" __attribute__((naked)) void Fault_Handler() {
  __asm__ volatile(
      "ldr r0, =__stack_top\n\t"
      "mov sp, r0\n\t"
      "b Fault_Report");
}

extern "C" void Fault_Report() {
  uwbnav::mps2::semihost_write0("mps2: fault exception (HardFault/MemManage/BusFault/UsageFault/NMI)\n");
  uwbnav::mps2::semihost_exit(3);
}

extern "C" void Unexpected_Handler() {
  uwbnav::mps2::semihost_write0("mps2: unexpected exception (SVCall/PendSV/SysTick/DebugMonitor)\n");
  uwbnav::mps2::semihost_exit(3);
}

namespace uwbnav::mps2 {

uint32_t stack_used_bytes() {
  const uint32_t* p = __stack_bottom;
  while (p < __stack_top && *p == kStackPaint) ++p;
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(__stack_top) - reinterpret_cast<uintptr_t>(p));
}

uint32_t stack_size_bytes() {
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(__stack_top) -
                               reinterpret_cast<uintptr_t>(__stack_bottom));
}

}  // namespace uwbnav::mps2
