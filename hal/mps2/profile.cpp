// Sampling profiler (see profile.hpp): SysTick handler and a fixed-size PC histogram.
#include "hal/mps2/profile.hpp"

#include <cstddef>

extern "C" void profile_sample(uint32_t pc, uint32_t lr);
extern "C" void SysTick_Handler();

namespace uwbnav::mps2 {
namespace {

constexpr size_t kSlots = 16384;  // distinct PCs kept (open addressing); more are counted as dropped

// One (interrupted PC, interrupted LR) pair: the LR names the caller of a leaf
// function (memset, soft-float helpers) that does not save it.
struct Slot {
  uint32_t pc;
  uint32_t lr;
  uint32_t count;
};

Slot g_slots[kSlots];
uint32_t g_samples = 0;
uint32_t g_dropped = 0;

volatile uint32_t* const kSystCsr = reinterpret_cast<volatile uint32_t*>(0xE000E010U);
volatile uint32_t* const kSystRvr = reinterpret_cast<volatile uint32_t*>(0xE000E014U);
volatile uint32_t* const kSystCvr = reinterpret_cast<volatile uint32_t*>(0xE000E018U);

}  // namespace

void profile_start() {
  *kSystCsr = 0U;
  *kSystRvr = kProfilePeriodTicks - 1U;
  *kSystCvr = 0U;
  *kSystCsr = (1U << 0) | (1U << 1) | (1U << 2);  // enable, interrupt, core clock
}

void profile_report(TextOut& out) {
  *kSystCsr = 0U;
  out.str("profile samples=").u64(g_samples).str(" dropped=").u64(g_dropped);
  out.str(" period_ticks=").u64(kProfilePeriodTicks).endl();
  for (const Slot& s : g_slots) {
    if (s.count == 0) continue;
    out.str("profile pc=").u64(s.pc).str(" lr=").u64(s.lr).str(" n=").u64(s.count).endl();
  }
}

}  // namespace uwbnav::mps2

extern "C" void profile_sample(uint32_t pc, uint32_t lr) {
  using uwbnav::mps2::g_slots;
  using uwbnav::mps2::kSlots;
  ++uwbnav::mps2::g_samples;
  size_t i = ((pc >> 1) * 2654435761U + lr) % kSlots;
  for (size_t probe = 0; probe < 64; ++probe, i = (i + 1) % kSlots) {
    if (g_slots[i].count == 0 || (g_slots[i].pc == pc && g_slots[i].lr == lr)) {
      g_slots[i].pc = pc;
      g_slots[i].lr = lr;
      ++g_slots[i].count;
      return;
    }
  }
  ++uwbnav::mps2::g_dropped;
}

// All code runs on the main stack: the stacked LR and PC are words 5 and 6 of
// the exception frame.
extern "C" __attribute__((naked)) void SysTick_Handler() {
  __asm__ volatile(
      "mrs r2, msp\n\t"
      "ldr r0, [r2, #24]\n\t"
      "ldr r1, [r2, #20]\n\t"
      "b profile_sample");
}
