// Sampling profiler of the MPS2 image (profile build only): the SysTick
// exception samples the interrupted PC and LR every kProfilePeriodTicks; the
// counts go out over semihosting for image_analysis/footprint_report to
// attribute to functions (and leaf library time to its callers).
#pragma once

#include <cstdint>

#include "hal/mps2/text_out.hpp"

namespace uwbnav::mps2 {

// 1009 ticks = 40,360 instructions under -icount shift=0 (prime: no lock-step with the loop).
constexpr uint32_t kProfilePeriodTicks = 1009;

// Starts SysTick with its interrupt at kProfilePeriodTicks (replaces CycleCounter::start).
void profile_start();
// Stops sampling and prints "profile ..." lines: totals, then one line per sampled (PC, LR).
void profile_report(TextOut& out);

}  // namespace uwbnav::mps2
