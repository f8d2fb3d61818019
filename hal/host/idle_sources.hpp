// Sensor sources with nothing attached: a board whose samples arrive another
// way (HIL over CAN) or a test that drives the loop without sensors.
#pragma once

#include "hal/hal.hpp"

namespace uwbnav::hal {

class IdleImuSource final : public ImuSource {
 public:
  Status poll(uint64_t, ImuSample&) override { return Status::kEmpty; }
  bool finished() const override { return false; }
};

class IdleUwbSource final : public UwbSource {
 public:
  Status poll(uint64_t, UwbRange&) override { return Status::kEmpty; }
  bool finished() const override { return false; }
};

}  // namespace uwbnav::hal
