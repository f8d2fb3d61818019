// Bridge to a second copy of the estimator compiled in double precision
// (UWBNAV_ESTIMATOR_DOUBLE) under the renamed namespace uwbnav_f64, so one test
// binary can run float and double on the same input. Only plain types cross.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uwbnav_f64_bridge {

struct Output {
  uint64_t t_us = 0;
  int status = 0;
  double pos_nav_m[3] = {0, 0, 0};
  double pos_sigma_m[3] = {0, 0, 0};
};

// site/imu/uwb point to uwbnav::SiteConfig, ImuSample[n_imu], UwbRange[n_uwb]
// (their layout does not depend on Real); the byte sizes are checked. Returns
// one output per 10 ms cycle, as tests/estimator/nav_harness.hpp replays.
// param_ids/param_values: n_params overrides of the defaults (ParamId values).
std::vector<Output> replay_double(const void* site, size_t site_bytes, const void* imu, size_t n_imu, size_t imu_bytes,
                                  const void* uwb, size_t n_uwb, size_t uwb_bytes, const int* param_ids = nullptr,
                                  const float* param_values = nullptr, size_t n_params = 0);

}  // namespace uwbnav_f64_bridge
