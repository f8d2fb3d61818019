// Host wall clock for real-time runs: CLOCK_MONOTONIC, absolute-deadline sleep.
#pragma once

#include <cstdint>

#include "hal/hal.hpp"

namespace uwbnav::hal {

class RealtimeClock : public Clock {
 public:
  // now_us() reads start_us at construction and then follows CLOCK_MONOTONIC.
  explicit RealtimeClock(uint64_t start_us = 0);

  uint64_t now_us() override;
  // clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) to the deadline, resumed
  // after signals; returns at once when the deadline has passed.
  void sleep_until_us(uint64_t deadline_us) override;

 private:
  uint64_t origin_mono_us_;  // CLOCK_MONOTONIC at construction [us]
  uint64_t start_us_;        // now_us() at construction [us]
};

}  // namespace uwbnav::hal
