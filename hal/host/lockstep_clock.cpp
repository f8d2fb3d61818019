// Simulated lockstep clock.
#include "hal/host/lockstep_clock.hpp"

namespace uwbnav::hal {

void LockstepClock::sleep_until_us(uint64_t deadline_us) {
  if (deadline_us > now_us_) now_us_ = deadline_us;
}

}  // namespace uwbnav::hal
