// The estimator's one entry point for the firmware: initialisation (LS-Taylor,
// levelling), the error-state EKF, vehicle constraints, the NLOS gating layer
// and degraded modes, behind a small API. Pure library: no I/O, no heap.
#pragma once

#include <cstdint>

#include "estimator/gating.hpp"
#include "estimator/params.hpp"
#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

// Counters the console and CAN diagnostics read. Monotonic since start.
struct NavDiagnostics {
  uint32_t imu_samples = 0;
  uint32_t ranges_received = 0;
  uint32_t ranges_used = 0;
  uint32_t ranges_rejected = 0;
  uint32_t resets = 0;           // covariance/state resets (non-finite, exploding)
  uint32_t reinits = 0;          // re-initialisations after divergence
  uint64_t last_imu_t_us = 0;
  uint64_t last_range_used_t_us = 0;
};

// Per-anchor view for the console `anchors` command and CAN diagnostics.
struct AnchorStatus {
  uint16_t anchor_id = 0;
  uint64_t last_t_us = 0;        // time of the last range received [us]
  float last_range_m = kNaNf;
  float last_innovation_m = kNaNf;
  float last_p_nlos = kNaNf;     // last fused NLOS probability
  uint32_t los_count = 0;        // ranges classified LOS
  uint32_t nlos_count = 0;       // ranges classified NLOS
  uint32_t used_count = 0;       // ranges fused
  bool nlos_state = false;       // current (hysteretic) NLOS state of this anchor
};

// Public API used by firmware/. Calls must come in non-decreasing sensor time;
// the firmware guarantees that (validation rejects out-of-order frames).
class Navigator {
 public:
  Navigator();

  // Loads the site (anchors, tags, platform) and the parameters; clears state.
  [[nodiscard]] Status configure(const SiteConfig& site, const Params& params);
  // Applies changed parameter values live (console `param set`).
  void update_params(const Params& params);

  // One validated IMU sample: propagates the filter to imu.t_us.
  [[nodiscard]] Status on_imu(const ImuSample& imu);
  // One validated range: gating + sequential scalar update at range.t_us.
  [[nodiscard]] RangeReport on_range(const UwbRange& range);
  // The solution at t_us (end of a 10 ms cycle). Resets per-cycle counters.
  [[nodiscard]] NavOutput output(uint64_t t_us);

  // Drops the solution and starts initialisation again (console `reset filter`).
  void reset();

  const NavDiagnostics& diagnostics() const;
  size_t num_anchors() const;
  const AnchorStatus& anchor_status(size_t index) const;

  // Error-state size and access for the console `ekf` command.
  static constexpr size_t kErrorStateSize = 15;
  void state_vector(float out[16]) const;   // p(3) v(3) q(4) ba(3) bg(3)
  void covariance_diagonal(float out[kErrorStateSize]) const;
  float covariance(size_t row, size_t col) const;

 private:
  // Implementation members: see navigator.cpp.
};

}  // namespace uwbnav
