// Real-time loop driver (see realtime_loop.hpp).
#include "firmware/realtime_loop.hpp"

namespace uwbnav {

uint64_t RealtimeLoop::step(uint64_t deadline_us) {
  clock_.sleep_until_us(deadline_us);
  const uint64_t start_us = clock_.now_us();
  app_.tick(deadline_us);
  const uint64_t end_us = clock_.now_us();
  const uint64_t work_us = end_us - start_us;
  const uint64_t late_us = start_us > deadline_us ? start_us - deadline_us : 0;
  uint64_t next_us = deadline_us + kCyclePeriodUs;
  bool overrun = end_us > next_us;
  if (overrun) {
    // Skip the deadlines already missed: resynchronise on the grid.
    next_us = deadline_us + ((end_us - deadline_us) / kCyclePeriodUs + 1) * kCyclePeriodUs;
  }
  app_.record_cycle_timing(static_cast<uint32_t>(work_us), static_cast<uint32_t>(late_us), overrun);
  return next_us;
}

void RealtimeLoop::run(const volatile bool& stop, uint64_t max_cycles) {
  uint64_t deadline_us = (clock_.now_us() / kCyclePeriodUs + 1) * kCyclePeriodUs;
  for (uint64_t n = 0; !stop && (max_cycles == 0 || n < max_cycles); ++n) deadline_us = step(deadline_us);
}

}  // namespace uwbnav
