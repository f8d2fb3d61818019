// Simulated clock for lockstep runs: time moves only when the loop sleeps or
// the board sets it, so a replay is deterministic and runs as fast as the CPU allows.
#pragma once

#include <cstdint>

#include "hal/hal.hpp"

namespace uwbnav::hal {

class LockstepClock : public Clock {
 public:
  explicit LockstepClock(uint64_t start_us = 0) : now_us_(start_us) {}

  uint64_t now_us() override { return now_us_; }
  // Advances the simulated time to deadline_us; never moves it backwards.
  void sleep_until_us(uint64_t deadline_us) override;
  // Sets the simulated time (start of a run); may move it in either direction.
  void set_us(uint64_t t_us) { now_us_ = t_us; }

 private:
  uint64_t now_us_;  // simulated time [us]
};

}  // namespace uwbnav::hal
