// Real-time driver of App::tick(): absolute-deadline sleep on the board clock
// (no drift), per-cycle work time, start jitter and overruns recorded in AppStats.
#pragma once

#include <cstdint>

#include "firmware/app.hpp"
#include "hal/hal.hpp"

namespace uwbnav {

class RealtimeLoop {
 public:
  RealtimeLoop(App& app, hal::Clock& clock) : app_(app), clock_(clock) {}

  // Runs cycles until `stop` becomes true (checked once per cycle) or
  // `max_cycles` cycles ran (0 = unlimited). The first deadline is the next
  // multiple of the period after now. When a cycle overruns by more than one
  // period, the missed deadlines are skipped (counted as overruns), never
  // bunched up.
  void run(const volatile bool& stop, uint64_t max_cycles = 0);

  // One cycle at the current deadline; returns the next deadline.
  uint64_t step(uint64_t deadline_us);

 private:
  App& app_;
  hal::Clock& clock_;
};

}  // namespace uwbnav
