// Host real-time clock on CLOCK_MONOTONIC with absolute-deadline sleep.
#include "hal/host/realtime_clock.hpp"

#include <cerrno>
#include <ctime>

namespace uwbnav::hal {

namespace {

uint64_t monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000U + static_cast<uint64_t>(ts.tv_nsec) / 1000U;
}

}  // namespace

RealtimeClock::RealtimeClock(uint64_t start_us) : origin_mono_us_(monotonic_us()), start_us_(start_us) {}

uint64_t RealtimeClock::now_us() { return start_us_ + (monotonic_us() - origin_mono_us_); }

void RealtimeClock::sleep_until_us(uint64_t deadline_us) {
  if (deadline_us <= now_us()) return;
  const uint64_t mono_deadline_us = origin_mono_us_ + (deadline_us - start_us_);
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(mono_deadline_us / 1000000U);
  ts.tv_nsec = static_cast<long>((mono_deadline_us % 1000000U) * 1000U);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace uwbnav::hal
