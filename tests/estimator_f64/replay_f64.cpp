// Double-precision replay (compiled with UWBNAV_ESTIMATOR_DOUBLE and
// uwbnav=uwbnav_f64 together with a copy of the estimator sources).
#include "tests/estimator_f64/replay_f64.hpp"

#include <cstring>

#include "tests/estimator/nav_harness.hpp"

namespace uwbnav_f64_bridge {

std::vector<Output> replay_double(const void* site, size_t site_bytes, const void* imu, size_t n_imu, size_t imu_bytes,
                                  const void* uwb, size_t n_uwb, size_t uwb_bytes, const int* param_ids,
                                  const float* param_values, size_t n_params) {
  static_assert(sizeof(uwbnav::Real) == sizeof(double), "this file must be built with UWBNAV_ESTIMATOR_DOUBLE");
  std::vector<Output> out;
  if (site_bytes != sizeof(uwbnav::SiteConfig) || imu_bytes != sizeof(uwbnav::ImuSample) ||
      uwb_bytes != sizeof(uwbnav::UwbRange)) {
    return out;
  }
  uwbnav::dataset::Recording rec;
  std::memcpy(static_cast<void*>(&rec.site), site, site_bytes);
  rec.imu.resize(n_imu);
  if (n_imu > 0) std::memcpy(static_cast<void*>(rec.imu.data()), imu, n_imu * imu_bytes);
  rec.uwb.resize(n_uwb);
  for (size_t i = 0; i < n_uwb; ++i) {
    std::memcpy(static_cast<void*>(&rec.uwb[i].range), static_cast<const char*>(uwb) + i * uwb_bytes, uwb_bytes);
  }
  uwbnav::Params params;
  for (size_t i = 0; i < n_params; ++i) {
    if (params.set(static_cast<uwbnav::ParamId>(param_ids[i]), param_values[i]) != uwbnav::Status::kOk) return out;
  }
  const uwbnav::test::RunScore s = uwbnav::test::replay(rec, params);
  for (const auto& o : s.outputs) {
    Output r;
    r.t_us = o.out.t_us;
    r.status = static_cast<int>(o.out.status);
    r.pos_nav_m[0] = static_cast<double>(o.out.pos_nav_m.x);
    r.pos_nav_m[1] = static_cast<double>(o.out.pos_nav_m.y);
    r.pos_nav_m[2] = static_cast<double>(o.out.pos_nav_m.z);
    r.pos_sigma_m[0] = static_cast<double>(o.out.pos_sigma_m.x);
    r.pos_sigma_m[1] = static_cast<double>(o.out.pos_sigma_m.y);
    r.pos_sigma_m[2] = static_cast<double>(o.out.pos_sigma_m.z);
    out.push_back(r);
  }
  return out;
}

}  // namespace uwbnav_f64_bridge
